//! The driver's own settings: the `[camera]` table of the profile. [`register`](crate::register)
//! hands [`SETTINGS`] to the registry, so `Params::set("VisionCameraSource", …)` and a
//! profile's `VisionCameraSource = …` reach these checks; [`CameraConfig::from_params`] reads
//! the values back typed.
//!
//! [`CameraConfig::from_params`]: crate::CameraConfig::from_params

use std::ops::Bound;

use vision_core::params::{Check, DriverSettings, Setting, SettingsTable};
use vision_core::Params;

/// The driver's profile table, `[camera]`.
pub const TABLE: &str = "camera";

/// The pixel formats `VisionCameraPixelFormat` accepts (`auto`: the device's best).
pub const PIXEL_FORMATS: &[&str] = &["auto", "MJPEG", "YUYV", "GREY"];
/// The mark kinds `VisionCameraMark` accepts.
pub const MARKS: &[&str] = vision_locate::MarkKind::NAMES;
/// The polarities `VisionCameraPolarity` accepts: a dark mark on a light ground, or the reverse.
pub const POLARITIES: &[&str] = &["dark", "light"];

/// Smallest `VisionCameraSearchRadius`, percent.
pub const MIN_SEARCH_RADIUS_PCT: f64 = 5.0;
/// Longest `VisionCameraTimeout`, seconds.
pub const MAX_TIMEOUT_S: f64 = 300.0;
/// Most `VisionCameraFlushFrames`.
pub const MAX_FLUSH_FRAMES: i64 = 30;
/// Largest `VisionCameraWidth` / `VisionCameraHeight` and `VisionCameraMarkDiameterPx`, pixels.
pub const MAX_SIDE_PX: i64 = 16_384;

/// `VisionCameraSource`: what [`Source::parse`] reads (its refusal says what is wrong).
///
/// [`Source::parse`]: crate::Source::parse
pub const SOURCE: Check<String> =
    Check::explained("a V4L2 device, an http:// snapshot URL, or an image file or folder", |s| {
        crate::config::Source::parse(s).map(|_| ())
    });
/// `VisionCameraWidth` and `VisionCameraHeight`, pixels.
pub const SIDE: Check<i64> = Check::closed("0 (the device's largest) or a size up to 16384 pixels", 0, MAX_SIDE_PX);
/// A frame size the driver asks for, both sides set, pixels.
pub const SIDE_SET: Check<i64> = Check::closed("1 to 16384 pixels, with VisionCameraHeight", 1, MAX_SIDE_PX);
/// `VisionCameraMarkDiameterPx`, pixels (0: derived).
pub const DIAMETER: Check<f64> =
    Check::closed("0 (derive it) or a diameter up to 16384 pixels", 0.0, MAX_SIDE_PX as f64);
/// The diameter the driver searches for, pixels.
pub const DIAMETER_SET: Check<f64> = Check::closed("2 to 16384 pixels", 2.0, MAX_SIDE_PX as f64);
/// `VisionCameraMarkTolerance`, percent.
pub const TOLERANCE: Check<f64> =
    Check::within("more than 0 and less than 100 percent", Bound::Excluded(0.0), Bound::Excluded(100.0));
/// `VisionCameraSearchRadius`, percent.
pub const SEARCH_RADIUS: Check<f64> = Check::closed("5 to 100 percent", MIN_SEARCH_RADIUS_PCT, 100.0);
/// `VisionCameraTimeout`, seconds.
pub const TIMEOUT: Check<f64> =
    Check::within("more than 0 and at most 300 seconds", Bound::Excluded(0.0), Bound::Included(MAX_TIMEOUT_S));
/// `VisionCameraFlushFrames`.
pub const FLUSH_FRAMES: Check<i64> = Check::closed("0 to 30 frames", 0, MAX_FLUSH_FRAMES);

/// `VisionCameraSource`'s default: mjpg-streamer's snapshot URL on this machine (its default
/// port). An HTTP source opens in every build on every platform, where a V4L2 device needs the
/// `v4l2` feature and 64-bit Linux; a USB camera is served by mjpg-streamer or ustreamer.
pub const DEFAULT_SOURCE: &str = "http://127.0.0.1:8080/?action=snapshot";

/// The camera driver's settings.
pub static SETTINGS: SettingsTable = SettingsTable {
    table: TABLE,
    settings: &[
        Setting::text(
            "VisionCameraSource",
            DEFAULT_SOURCE,
            SOURCE,
            "`VisionCameraSource`: where frames come from: a V4L2 device (`/dev/video0`), an HTTP \
             snapshot URL (`http://host:8080/?action=snapshot`), or an image file or folder (replay, \
             one image per trigger in name order).",
        ),
        Setting::int(
            "VisionCameraWidth",
            "px",
            0,
            SIDE,
            "`VisionCameraWidth`: V4L2 frame width, pixels; 0 takes the device's largest.",
        ),
        Setting::int(
            "VisionCameraHeight",
            "px",
            0,
            SIDE,
            "`VisionCameraHeight`: V4L2 frame height, pixels; 0 takes the device's largest.",
        ),
        Setting::choice(
            "VisionCameraPixelFormat",
            PIXEL_FORMATS,
            "auto",
            "`VisionCameraPixelFormat`: V4L2 pixel format, auto, MJPEG, YUYV or GREY (auto prefers \
             GREY, then YUYV, then MJPEG: uncompressed frames have no JPEG artefacts).",
        ),
        Setting::choice(
            "VisionCameraMark",
            MARKS,
            "dot",
            "`VisionCameraMark`: the printed fiducial, dot (filled disc), ring or cross.",
        ),
        Setting::float(
            "VisionCameraMarkDiameterPx",
            "px",
            0.0,
            DIAMETER,
            "`VisionCameraMarkDiameterPx`: the mark's expected diameter in the image, pixels; 0 derives it \
             from VisionMarkDiameter and the calibrated K.",
        ),
        Setting::float(
            "VisionCameraMarkTolerance",
            "%",
            25.0,
            TOLERANCE,
            "`VisionCameraMarkTolerance`: how far the seen diameter may differ from the expected one, \
             percent, more than 0 and less than 100.",
        ),
        Setting::choice(
            "VisionCameraPolarity",
            POLARITIES,
            "dark",
            "`VisionCameraPolarity`: dark (a dark mark on a light ground, as printed) or light.",
        ),
        Setting::float(
            "VisionCameraSearchRadius",
            "%",
            100.0,
            SEARCH_RADIUS,
            "`VisionCameraSearchRadius`: search only within this distance of the image centre, percent of \
             half the shorter image side, 5 to 100 (100: the whole frame). M281 re-centres the mark, so a \
             radius that leaves neighbouring marks outside keeps them from making the view ambiguous.",
        ),
        Setting::float(
            "VisionCameraTimeout",
            "s",
            3.0,
            TIMEOUT,
            "`VisionCameraTimeout`: time allowed for one frame (connect, request, whole image; or one \
             device capture), and again for the mark search in it, seconds, more than 0 and at most 300.",
        ),
        Setting::int(
            "VisionCameraFlushFrames",
            "frames",
            2,
            FLUSH_FRAMES,
            "`VisionCameraFlushFrames`: frames taken and thrown away before the one searched, so none \
             predates the last move (V4L2 queues frames; a snapshot server may hold an old one), 0 to 30.",
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
    use vision_core::{ParamKind, ParamValue};

    use super::*;
    use crate::CameraConfig;

    #[test]
    fn each_refusal_quotes_the_range_the_reference_shows() {
        // The source's refusal says what is wrong with the given one; the choices are checked
        // by their kind (the reference lists the words).
        let bad = [
            ("VisionCameraWidth", ParamValue::Int(MAX_SIDE_PX + 1)),
            ("VisionCameraHeight", ParamValue::Int(-1)),
            ("VisionCameraMarkDiameterPx", ParamValue::Float(-1.0)),
            ("VisionCameraMarkTolerance", ParamValue::Float(100.0)),
            ("VisionCameraSearchRadius", ParamValue::Float(4.0)),
            ("VisionCameraTimeout", ParamValue::Float(0.0)),
            ("VisionCameraFlushFrames", ParamValue::Int(31)),
        ];
        for (name, value) in bad {
            let s = SETTINGS.settings.iter().find(|s| s.spec.name == name).expect(name);
            assert_eq!(s.check(&value), Err(format!("must be {}", s.spec.range)), "{name}");
        }
        for s in SETTINGS.settings {
            let choice = matches!(s.spec.kind, ParamKind::Choice(_));
            assert_eq!(s.spec.range.is_empty(), choice, "{}: a range unless a choice", s.spec.name);
        }
    }

    /// Each end of each range, and the nearest value beyond it, through the profile's setter.
    #[test]
    fn each_range_ends_where_its_words_say() {
        let cases: [(&str, &[ParamValue], &[ParamValue]); 8] = [
            (
                "VisionCameraWidth",
                &[ParamValue::Int(0), ParamValue::Int(16_384)],
                &[ParamValue::Int(-1), ParamValue::Int(16_385)],
            ),
            (
                "VisionCameraHeight",
                &[ParamValue::Int(0), ParamValue::Int(16_384)],
                &[ParamValue::Int(-1), ParamValue::Int(16_385)],
            ),
            (
                "VisionCameraMarkDiameterPx",
                &[ParamValue::Float(0.0), ParamValue::Float(16_384.0)],
                &[ParamValue::Float(-1e-9), ParamValue::Float(16_384.001), ParamValue::Float(f64::NAN)],
            ),
            (
                "VisionCameraMarkTolerance",
                &[ParamValue::Float(1e-9), ParamValue::Float(99.999)],
                &[ParamValue::Float(0.0), ParamValue::Float(100.0), ParamValue::Float(f64::INFINITY)],
            ),
            (
                "VisionCameraSearchRadius",
                &[ParamValue::Float(5.0), ParamValue::Float(100.0)],
                &[ParamValue::Float(4.999), ParamValue::Float(100.001)],
            ),
            (
                "VisionCameraTimeout",
                &[ParamValue::Float(1e-9), ParamValue::Float(300.0)],
                &[ParamValue::Float(0.0), ParamValue::Float(300.001), ParamValue::Float(f64::NAN)],
            ),
            (
                "VisionCameraFlushFrames",
                &[ParamValue::Int(0), ParamValue::Int(30)],
                &[ParamValue::Int(-1), ParamValue::Int(31)],
            ),
            (
                "VisionCameraSource",
                &[ParamValue::Text("/dev/video0".into()), ParamValue::Text("http://cam/".into())],
                &[ParamValue::Text(" ".into()), ParamValue::Text("https://cam/".into())],
            ),
        ];
        for (name, accepted, refused) in cases {
            for v in accepted {
                let mut p = Params::default().with_driver_settings(&SETTINGS);
                p.set(name, v.clone()).unwrap_or_else(|e| panic!("{name} = {v}: {e}"));
                assert_eq!(p.get(name).as_ref(), Ok(v), "{name}");
            }
            for v in refused {
                let mut p = Params::default().with_driver_settings(&SETTINGS);
                let e = p.set(name, v.clone()).expect_err(name).to_string();
                assert!(e.starts_with(&format!("{name} = ")), "{e}");
                assert_eq!(
                    p.get(name),
                    Ok(SETTINGS.settings.iter().find(|s| s.spec.name == name).expect(name).default_value())
                );
            }
        }
        // The driver's own ranges for what it is asked to search: a set diameter, a set size.
        assert!(DIAMETER_SET.accepts(&2.0) && !DIAMETER_SET.accepts(&1.999) && DIAMETER_SET.accepts(&16_384.0));
        assert!(SIDE_SET.accepts(&1) && !SIDE_SET.accepts(&0) && !SIDE_SET.accepts(&16_385));
    }

    proptest::proptest! {
        /// Any text for any setting: the profile refuses it by name or keeps a value the typed
        /// read turns into a configuration or a named refusal. Never a panic.
        #[test]
        fn any_text_for_any_setting_is_read_or_refused(which in 0usize..11, text in "\\PC{0,40}|[-+]?[0-9]{0,6}(\\.[0-9]{0,4})?(e[-+]?[0-9]{1,3})?") {
            let name = SETTINGS.settings[which].spec.name;
            let mut p = Params::default().with_driver_settings(&SETTINGS);
            match p.set(name, text.as_str()) {
                Ok(()) => {
                    if let Err(e) = CameraConfig::from_params(&p) {
                        proptest::prop_assert!(e.to_string().contains("VisionCamera"), "{e}");
                    }
                }
                Err(e) => proptest::prop_assert!(e.to_string().contains(name), "{e}"),
            }
        }
    }
}
