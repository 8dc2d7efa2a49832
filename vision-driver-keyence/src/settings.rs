//! The driver's own settings: the `[keyence]` table of the profile, under the manual's names
//! (`VisionIP`, `VisionPort`, `VisionTimeout`, `VisionImageWatchDir`,
//! `VisionImageGrabTimeout`). [`register`](crate::register) hands [`SETTINGS`] to the registry,
//! so `Params::set("VisionIP", …)` and a profile's `VisionIP = …` (in `[keyence]`, or in
//! `[vision]` as the manual writes it) reach these checks; [`KeyenceConfig::from_params`]
//! reads the values back typed.
//!
//! [`KeyenceConfig::from_params`]: crate::KeyenceConfig::from_params

use std::ops::Bound;

use vision_core::params::{Check, DriverSettings, Setting, SettingsTable};
use vision_core::Params;

/// The driver's profile table, `[keyence]`.
pub const TABLE: &str = "keyence";

/// `VisionIP`'s default, the manual's camera address.
pub const DEFAULT_IP: &str = "192.168.208.80";

/// The longest `VisionImageGrabTimeout`, seconds.
pub const MAX_IMAGE_GRAB_TIMEOUT_S: f64 = 60.0;

/// `VisionIP`: an IP address, or a host name of letters, digits, `.` and `-`.
pub const HOST: Check<String> = Check::test("an IP address (e.g. 192.168.208.80) or a host name", |v| {
    v.parse::<std::net::IpAddr>().is_ok()
        || (!v.is_empty()
            && v.len() <= 253
            && v.chars().all(|c| c.is_ascii_alphanumeric() || c == '.' || c == '-')
            && !v.starts_with('-'))
});
/// `VisionPort`.
pub const PORT: Check<i64> = Check::closed("a TCP port 1..65535", 1, 65_535);
/// `VisionTimeout`, seconds.
pub const TIMEOUT: Check<f64> =
    Check::within("more than 0 and at most 300 seconds", Bound::Excluded(0.0), Bound::Included(300.0));
/// `VisionImageWatchDir`.
pub const FOLDER: Check<String> =
    Check::test("a folder path of at most 4096 bytes", |s| s.len() <= 4096 && !s.contains('\0'));
/// `VisionImageGrabTimeout`, seconds.
pub const GRAB_TIMEOUT: Check<f64> = Check::closed("between 0 and 60 seconds", 0.0, MAX_IMAGE_GRAB_TIMEOUT_S);

/// The Keyence driver's settings.
pub static SETTINGS: SettingsTable = SettingsTable {
    table: TABLE,
    settings: &[
        Setting::text("VisionIP", DEFAULT_IP, HOST, "`VisionIP`: camera IP address or host name."),
        Setting::int(
            "VisionPort",
            "",
            8500,
            PORT,
            "`VisionPort`: the camera's Non-Procedural command TCP port (Keyence VS default 8500).",
        ),
        Setting::float(
            "VisionTimeout",
            "s",
            3.0,
            TIMEOUT,
            "`VisionTimeout`: time allowed for one whole driver call (connect, command, complete reply), \
             seconds, more than 0 and at most 300.",
        ),
        Setting::text(
            "VisionImageWatchDir",
            "",
            FOLDER,
            "`VisionImageWatchDir`: folder the camera FTP-pushes its images into; empty disables M281 D1.",
        ),
        Setting::float(
            "VisionImageGrabTimeout",
            "s",
            2.0,
            GRAB_TIMEOUT,
            "`VisionImageGrabTimeout`: how long M281 D1 waits for a fresh image, seconds, 0 to 60.",
        ),
    ],
};

/// The driver's settings in `params`: its table, or the defaults when `params` has none.
#[must_use]
pub fn settings(params: &Params) -> DriverSettings {
    params.driver_settings(TABLE).cloned().unwrap_or_else(|| DriverSettings::new(&SETTINGS))
}

#[cfg(test)]
mod tests {
    use vision_core::ParamValue;

    use super::*;
    use crate::KeyenceConfig;

    #[test]
    fn each_refusal_quotes_the_range_the_reference_shows() {
        let bad = [
            ("VisionIP", ParamValue::Text("-camera".into())),
            ("VisionPort", ParamValue::Int(0)),
            ("VisionTimeout", ParamValue::Float(0.0)),
            ("VisionImageWatchDir", ParamValue::Text("a\0b".into())),
            ("VisionImageGrabTimeout", ParamValue::Float(61.0)),
        ];
        assert_eq!(bad.len(), SETTINGS.settings.len(), "a bad value for every setting");
        for (name, value) in bad {
            let s = SETTINGS.settings.iter().find(|s| s.spec.name == name).expect(name);
            assert_eq!(s.check(&value), Err(format!("must be {}", s.spec.range)), "{name}");
        }
    }

    /// Each end of each range, and the nearest value beyond it, through the profile's setter.
    #[test]
    fn each_range_ends_where_its_words_say() {
        let long = "d".repeat(4096);
        let cases: [(&str, Vec<ParamValue>, Vec<ParamValue>); 5] = [
            (
                "VisionIP",
                vec!["10.0.0.1".into(), "::1".into(), "a".repeat(253).into()],
                vec!["".into(), "-cam".into(), "a".repeat(254).into(), "cam_1".into()],
            ),
            ("VisionPort", vec![1.into(), 65_535.into()], vec![0.into(), 65_536.into()]),
            ("VisionTimeout", vec![1e-9.into(), 300.0.into()], vec![0.0.into(), 300.001.into(), f64::NAN.into()]),
            ("VisionImageWatchDir", vec!["".into(), long.clone().into()], vec![format!("{long}d").into()]),
            ("VisionImageGrabTimeout", vec![0.0.into(), 60.0.into()], vec![(-1e-9).into(), 60.001.into()]),
        ];
        for (name, accepted, refused) in cases {
            for v in accepted {
                let mut p = Params::default().with_driver_settings(&SETTINGS);
                p.set(name, v.clone()).unwrap_or_else(|e| panic!("{name} = {v}: {e}"));
                assert!(KeyenceConfig::from_params(&p).is_ok(), "{name} = {v}");
            }
            for v in refused {
                let mut p = Params::default().with_driver_settings(&SETTINGS);
                let e = p.set(name, v.clone()).expect_err(name).to_string();
                assert!(e.starts_with(&format!("{name} = ")), "{e}");
            }
        }
    }

    proptest::proptest! {
        /// Any text for any setting: refused by name, or read into a configuration. Never a panic.
        #[test]
        fn any_text_for_any_setting_is_read_or_refused(which in 0usize..5, text in "\\PC{0,40}|[-+]?[0-9]{0,6}(\\.[0-9]{0,4})?") {
            let name = SETTINGS.settings[which].spec.name;
            let mut p = Params::default().with_driver_settings(&SETTINGS);
            match p.set(name, text.as_str()) {
                Ok(()) => proptest::prop_assert!(KeyenceConfig::from_params(&p).is_ok()),
                Err(e) => proptest::prop_assert!(e.to_string().contains(name), "{e}"),
            }
        }
    }
}
