//! The driver's own settings: the `[keyence]` table of the profile, under the manual's names
//! (`VisionIP`, `VisionPort`, `VisionTimeout`, `VisionImageWatchDir`,
//! `VisionImageGrabTimeout`). [`register`](crate::register) hands [`SETTINGS`] to the registry,
//! so `Params::set("VisionIP", …)` and a profile's `VisionIP = …` (in `[keyence]`, or in
//! `[vision]` as the manual writes it) reach these checks; [`KeyenceConfig::from_params`]
//! reads the values back typed.
//!
//! [`KeyenceConfig::from_params`]: crate::KeyenceConfig::from_params

use vision_core::params::{DriverSettings, Setting, SettingsTable};
use vision_core::{ParamKind, ParamSpec, ParamValue, Params};

/// The driver's profile table, `[keyence]`.
pub const TABLE: &str = "keyence";

/// `VisionIP`'s default, the manual's camera address.
pub const DEFAULT_IP: &str = "192.168.208.80";

/// The longest `VisionImageGrabTimeout`, seconds.
pub const MAX_IMAGE_GRAB_TIMEOUT_S: f64 = 60.0;

/// The Keyence driver's settings.
pub static SETTINGS: SettingsTable = SettingsTable {
    table: TABLE,
    settings: &[
        Setting {
            spec: ParamSpec::driver_setting(
                "VisionIP",
                ParamKind::Text,
                "",
                "an IP address (e.g. 192.168.208.80) or a host name",
                "`VisionIP`: camera IP address or host name.",
            ),
            default: || ParamValue::Text(DEFAULT_IP.to_string()),
            check: host,
        },
        Setting {
            spec: ParamSpec::driver_setting(
                "VisionPort",
                ParamKind::Integer,
                "",
                "a TCP port 1..65535",
                "`VisionPort`: the camera's Non-Procedural command TCP port (Keyence VS default 8500).",
            ),
            default: || ParamValue::Int(8500),
            check: port,
        },
        Setting {
            spec: ParamSpec::driver_setting(
                "VisionTimeout",
                ParamKind::Float,
                "s",
                "more than 0 and at most 300 seconds",
                "`VisionTimeout`: time allowed for one whole driver call (connect, command, complete reply), \
                 seconds, more than 0 and at most 300.",
            ),
            default: || ParamValue::Float(3.0),
            check: timeout,
        },
        Setting {
            spec: ParamSpec::driver_setting(
                "VisionImageWatchDir",
                ParamKind::Text,
                "",
                "a folder path of at most 4096 bytes",
                "`VisionImageWatchDir`: folder the camera FTP-pushes its images into; empty disables M281 D1.",
            ),
            default: || ParamValue::Text(String::new()),
            check: folder,
        },
        Setting {
            spec: ParamSpec::driver_setting(
                "VisionImageGrabTimeout",
                ParamKind::Float,
                "s",
                "between 0 and 60 seconds",
                "`VisionImageGrabTimeout`: how long M281 D1 waits for a fresh image, seconds, 0 to 60.",
            ),
            default: || ParamValue::Float(2.0),
            check: grab_timeout,
        },
    ],
};

/// The driver's settings in `params`: its table, or the defaults when `params` has none.
#[must_use]
pub fn settings(params: &Params) -> DriverSettings {
    params.driver_settings(TABLE).cloned().unwrap_or_else(|| DriverSettings::new(&SETTINGS))
}

fn host(v: &ParamValue) -> Result<(), String> {
    let ParamValue::Text(v) = v else { return Err("must be text".into()) };
    let ok = v.parse::<std::net::IpAddr>().is_ok()
        || (!v.is_empty()
            && v.len() <= 253
            && v.chars().all(|c| c.is_ascii_alphanumeric() || c == '.' || c == '-')
            && !v.starts_with('-'));
    if ok {
        Ok(())
    } else {
        Err("must be an IP address (e.g. 192.168.208.80) or a host name".into())
    }
}

fn port(v: &ParamValue) -> Result<(), String> {
    match v {
        ParamValue::Int(p) if (1..=65_535).contains(p) => Ok(()),
        _ => Err("must be a TCP port 1..65535".into()),
    }
}

fn timeout(v: &ParamValue) -> Result<(), String> {
    match v {
        ParamValue::Float(t) if t.is_finite() && *t > 0.0 && *t <= 300.0 => Ok(()),
        _ => Err("must be more than 0 and at most 300 seconds".into()),
    }
}

fn folder(v: &ParamValue) -> Result<(), String> {
    match v {
        ParamValue::Text(s) if s.len() <= 4096 && !s.contains('\0') => Ok(()),
        _ => Err("must be a folder path of at most 4096 bytes".into()),
    }
}

fn grab_timeout(v: &ParamValue) -> Result<(), String> {
    match v {
        ParamValue::Float(t) if t.is_finite() && (0.0..=MAX_IMAGE_GRAB_TIMEOUT_S).contains(t) => Ok(()),
        _ => Err("must be between 0 and 60 seconds".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
            assert_eq!((s.check)(&value), Err(format!("must be {}", s.spec.range)), "{name}");
        }
    }
}
