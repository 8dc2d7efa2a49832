//! The driver's own settings: the `[camera]` table of the profile. [`register`](crate::register)
//! hands [`SETTINGS`] to the registry, so `Params::set("VisionCameraSource", …)` and a
//! profile's `VisionCameraSource = …` reach these checks; [`CameraConfig::from_params`] reads
//! the values back typed.
//!
//! [`CameraConfig::from_params`]: crate::CameraConfig::from_params

use vision_core::params::{DriverSettings, Setting, SettingsTable};
use vision_core::{ParamKind, ParamSpec, ParamValue, Params};

/// The driver's profile table, `[camera]`.
pub const TABLE: &str = "camera";

/// The pixel formats `VisionCameraPixelFormat` accepts (`auto`: the device's best).
pub const PIXEL_FORMATS: &[&str] = &["auto", "MJPEG", "YUYV", "GREY"];
/// The mark kinds `VisionCameraMark` accepts.
pub const MARKS: &[&str] = &["dot", "ring", "cross"];
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

/// The camera driver's settings.
pub static SETTINGS: SettingsTable = SettingsTable {
    table: TABLE,
    settings: &[
        Setting {
            spec: ParamSpec::driver_setting(
                "VisionCameraSource",
                ParamKind::Text,
                "",
                "a V4L2 device, an http:// snapshot URL, or an image file or folder",
                "`VisionCameraSource`: where frames come from: a V4L2 device (`/dev/video0`), an HTTP \
                 snapshot URL (`http://host:8080/?action=snapshot`), or an image file or folder (replay, \
                 one image per trigger in name order).",
            ),
            default: || ParamValue::Text("/dev/video0".to_string()),
            check: source,
        },
        Setting {
            spec: ParamSpec::driver_setting(
                "VisionCameraWidth",
                ParamKind::Integer,
                "px",
                "0 (the device's largest) or a size up to 16384 pixels",
                "`VisionCameraWidth`: V4L2 frame width, pixels; 0 takes the device's largest.",
            ),
            default: || ParamValue::Int(0),
            check: side,
        },
        Setting {
            spec: ParamSpec::driver_setting(
                "VisionCameraHeight",
                ParamKind::Integer,
                "px",
                "0 (the device's largest) or a size up to 16384 pixels",
                "`VisionCameraHeight`: V4L2 frame height, pixels; 0 takes the device's largest.",
            ),
            default: || ParamValue::Int(0),
            check: side,
        },
        Setting {
            spec: ParamSpec::driver_setting(
                "VisionCameraPixelFormat",
                ParamKind::Choice(PIXEL_FORMATS),
                "",
                "",
                "`VisionCameraPixelFormat`: V4L2 pixel format, auto, MJPEG, YUYV or GREY (auto prefers \
                 GREY, then YUYV, then MJPEG: uncompressed frames have no JPEG artefacts).",
            ),
            default: || ParamValue::Text("auto".to_string()),
            check: |_| Ok(()),
        },
        Setting {
            spec: ParamSpec::driver_setting(
                "VisionCameraMark",
                ParamKind::Choice(MARKS),
                "",
                "",
                "`VisionCameraMark`: the printed fiducial, dot (filled disc), ring or cross.",
            ),
            default: || ParamValue::Text("dot".to_string()),
            check: |_| Ok(()),
        },
        Setting {
            spec: ParamSpec::driver_setting(
                "VisionCameraMarkDiameterPx",
                ParamKind::Float,
                "px",
                "0 (derive it) or a diameter up to 16384 pixels",
                "`VisionCameraMarkDiameterPx`: the mark's expected diameter in the image, pixels; 0 derives it \
                 from VisionMarkDiameter and the calibrated K.",
            ),
            default: || ParamValue::Float(0.0),
            check: diameter,
        },
        Setting {
            spec: ParamSpec::driver_setting(
                "VisionCameraMarkTolerance",
                ParamKind::Float,
                "%",
                "more than 0 and less than 100 percent",
                "`VisionCameraMarkTolerance`: how far the seen diameter may differ from the expected one, \
                 percent, more than 0 and less than 100.",
            ),
            default: || ParamValue::Float(25.0),
            check: tolerance,
        },
        Setting {
            spec: ParamSpec::driver_setting(
                "VisionCameraPolarity",
                ParamKind::Choice(POLARITIES),
                "",
                "",
                "`VisionCameraPolarity`: dark (a dark mark on a light ground, as printed) or light.",
            ),
            default: || ParamValue::Text("dark".to_string()),
            check: |_| Ok(()),
        },
        Setting {
            spec: ParamSpec::driver_setting(
                "VisionCameraSearchRadius",
                ParamKind::Float,
                "%",
                "5 to 100 percent",
                "`VisionCameraSearchRadius`: search only within this distance of the image centre, percent of \
                 half the shorter image side, 5 to 100 (100: the whole frame). M281 re-centres the mark, so a \
                 radius that leaves neighbouring marks outside keeps them from making the view ambiguous.",
            ),
            default: || ParamValue::Float(100.0),
            check: radius,
        },
        Setting {
            spec: ParamSpec::driver_setting(
                "VisionCameraTimeout",
                ParamKind::Float,
                "s",
                "more than 0 and at most 300 seconds",
                "`VisionCameraTimeout`: time allowed for one frame (connect, request, whole image; or one \
                 device capture), and again for the mark search in it, seconds, more than 0 and at most 300.",
            ),
            default: || ParamValue::Float(3.0),
            check: timeout,
        },
        Setting {
            spec: ParamSpec::driver_setting(
                "VisionCameraFlushFrames",
                ParamKind::Integer,
                "frames",
                "0 to 30 frames",
                "`VisionCameraFlushFrames`: frames taken and thrown away before the one searched, so none \
                 predates the last move (V4L2 queues frames; a snapshot server may hold an old one), 0 to 30.",
            ),
            default: || ParamValue::Int(2),
            check: flush,
        },
    ],
};

/// The driver's settings in `params`: its table, or the defaults when `params` has none.
#[must_use]
pub fn settings(params: &Params) -> DriverSettings {
    params.driver_settings(TABLE).cloned().unwrap_or_else(|| DriverSettings::new(&SETTINGS))
}

fn source(v: &ParamValue) -> Result<(), String> {
    match v {
        ParamValue::Text(s) => crate::config::Source::parse(s).map(|_| ()),
        _ => Err("must be text".into()),
    }
}

fn side(v: &ParamValue) -> Result<(), String> {
    match v {
        ParamValue::Int(p) if (0..=MAX_SIDE_PX).contains(p) => Ok(()),
        _ => Err(format!("must be 0 (the device's largest) or a size up to {MAX_SIDE_PX} pixels")),
    }
}

fn diameter(v: &ParamValue) -> Result<(), String> {
    let max = MAX_SIDE_PX as f64;
    match v {
        ParamValue::Float(d) if d.is_finite() && *d >= 0.0 && *d <= max => Ok(()),
        _ => Err(format!("must be 0 (derive it) or a diameter up to {MAX_SIDE_PX} pixels")),
    }
}

fn tolerance(v: &ParamValue) -> Result<(), String> {
    match v {
        ParamValue::Float(t) if t.is_finite() && *t > 0.0 && *t < 100.0 => Ok(()),
        _ => Err("must be more than 0 and less than 100 percent".into()),
    }
}

fn radius(v: &ParamValue) -> Result<(), String> {
    match v {
        ParamValue::Float(r) if r.is_finite() && (MIN_SEARCH_RADIUS_PCT..=100.0).contains(r) => Ok(()),
        _ => Err("must be 5 to 100 percent".into()),
    }
}

fn timeout(v: &ParamValue) -> Result<(), String> {
    match v {
        ParamValue::Float(t) if t.is_finite() && *t > 0.0 && *t <= MAX_TIMEOUT_S => Ok(()),
        _ => Err("must be more than 0 and at most 300 seconds".into()),
    }
}

fn flush(v: &ParamValue) -> Result<(), String> {
    match v {
        ParamValue::Int(n) if (0..=MAX_FLUSH_FRAMES).contains(n) => Ok(()),
        _ => Err(format!("must be 0 to {MAX_FLUSH_FRAMES} frames")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
            assert_eq!((s.check)(&value), Err(format!("must be {}", s.spec.range)), "{name}");
        }
        for s in SETTINGS.settings {
            let choice = matches!(s.spec.kind, ParamKind::Choice(_));
            assert_eq!(s.spec.range.is_empty(), choice, "{}: a range unless a choice", s.spec.name);
        }
    }
}
