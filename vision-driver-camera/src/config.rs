//! What the driver needs, typed, from its settings ([`crate::settings`]).

use std::fmt;
use std::path::PathBuf;
use std::time::Duration;

use vision_core::Params;
pub use vision_locate::MarkKind;

use crate::error::CameraError;
use crate::http::HttpUrl;
use crate::settings;

/// Where frames come from (`VisionCameraSource`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Source {
    /// A V4L2 device node, e.g. `/dev/video0` (written `/dev/video…` or `v4l2:PATH`).
    Device(PathBuf),
    /// An HTTP snapshot URL: one GET, one image.
    Http(HttpUrl),
    /// An image file (every trigger reads it again) or a folder (one image per trigger, in name
    /// order): anything else, or `file:PATH`.
    Files(PathBuf),
}

impl Source {
    /// Reads a `VisionCameraSource` value.
    ///
    /// # Errors
    /// Why the text names no source: empty, an `https://` URL (no TLS here), a bad URL.
    pub fn parse(text: &str) -> Result<Source, String> {
        let t = text.trim();
        if t.is_empty() {
            return Err("must name a device (/dev/video0), an http:// snapshot URL, or an image file or folder".into());
        }
        if t.len() > 4096 || t.contains('\0') {
            return Err("must be at most 4096 bytes, without NUL".into());
        }
        let lower = t.to_ascii_lowercase();
        if lower.starts_with("http://") {
            return HttpUrl::parse(t).map(Source::Http);
        }
        if lower.starts_with("https://") {
            return Err(
                "https is not supported: use the camera's plain http:// snapshot URL on the machine's network".into()
            );
        }
        if let Some(path) = t.strip_prefix("v4l2:") {
            return Ok(Source::Device(PathBuf::from(path)));
        }
        if t.starts_with("/dev/video") {
            return Ok(Source::Device(PathBuf::from(t)));
        }
        Ok(Source::Files(PathBuf::from(t.strip_prefix("file:").unwrap_or(t))))
    }
}

impl fmt::Display for Source {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Source::Device(p) | Source::Files(p) => write!(f, "{}", p.display()),
            Source::Http(u) => write!(f, "{u}"),
        }
    }
}

/// A V4L2 pixel format the driver decodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PixelFormat {
    /// 8-bit grey, one byte per pixel.
    Grey,
    /// YUV 4:2:2, `Y0 U Y1 V`: the Y bytes are the grey image.
    Yuyv,
    /// Motion JPEG: each frame a JPEG.
    Mjpeg,
}

impl PixelFormat {
    /// The V4L2 FourCC.
    #[must_use]
    pub fn fourcc(self) -> [u8; 4] {
        match self {
            PixelFormat::Grey => *b"GREY",
            PixelFormat::Yuyv => *b"YUYV",
            PixelFormat::Mjpeg => *b"MJPG",
        }
    }

    /// The format of a FourCC, `None` for one the driver does not decode.
    #[must_use]
    pub fn from_fourcc(fourcc: [u8; 4]) -> Option<PixelFormat> {
        match &fourcc {
            b"GREY" => Some(PixelFormat::Grey),
            b"YUYV" => Some(PixelFormat::Yuyv),
            b"MJPG" => Some(PixelFormat::Mjpeg),
            _ => None,
        }
    }

    /// How `auto` ranks it: lower is better (no compression artefacts first).
    pub(crate) fn rank(self) -> u8 {
        match self {
            PixelFormat::Grey => 0,
            PixelFormat::Yuyv => 1,
            PixelFormat::Mjpeg => 2,
        }
    }
}

impl fmt::Display for PixelFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            PixelFormat::Grey => "GREY",
            PixelFormat::Yuyv => "YUYV",
            PixelFormat::Mjpeg => "MJPEG",
        })
    }
}

/// Which way the mark contrasts with its ground (`VisionCameraPolarity`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Polarity {
    /// A dark mark on a light ground (printed black on white).
    Dark,
    /// A light mark on a dark ground.
    Light,
}

/// What mark to search for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MarkSettings {
    /// The shape.
    pub kind: MarkKind,
    /// Expected diameter in the image, pixels; `None`: derive it from `VisionMarkDiameter`
    /// and K ([`CameraConfig::from_params`] does when it can).
    pub diameter_px: Option<f64>,
    /// Allowed size difference, percent of the diameter (0 < t < 100).
    pub tolerance_pct: f64,
    /// The contrast.
    pub polarity: Polarity,
    /// Search only within this distance of the image centre, percent of half the shorter
    /// image side (5–100; 100: the whole frame).
    pub search_radius_pct: f64,
}

/// Everything the driver needs.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraConfig {
    /// Where frames come from.
    pub source: Source,
    /// V4L2 frame size `(width, height)`, pixels; `None`: the device's largest.
    pub size: Option<(u32, u32)>,
    /// V4L2 pixel format; `None`: the best the device offers.
    pub format: Option<PixelFormat>,
    /// The mark.
    pub mark: MarkSettings,
    /// Time allowed for one frame, and again for the mark search in it (cut off after it).
    pub timeout: Duration,
    /// Frames thrown away before the one searched.
    pub flush_frames: u32,
}

impl CameraConfig {
    /// A configuration reading `source` for a dark dot of `diameter_px`, with the defaults: ±25 %,
    /// 3 s, any size and format, 2 frames flushed.
    #[must_use]
    pub fn new(source: Source, diameter_px: f64) -> CameraConfig {
        CameraConfig {
            source,
            size: None,
            format: None,
            mark: MarkSettings {
                kind: MarkKind::Dot,
                diameter_px: Some(diameter_px),
                tolerance_pct: 25.0,
                polarity: Polarity::Dark,
                search_radius_pct: 100.0,
            },
            timeout: Duration::from_secs(3),
            flush_frames: 2,
        }
    }

    /// The driver's settings in `params` (`[camera]`, defaults when absent). A diameter of 0 is
    /// derived from `VisionMarkDiameter` (world unit) over the pixel size K gives, when both
    /// are known; otherwise it stays `None` and the driver refuses to search.
    ///
    /// # Errors
    /// [`CameraError::Config`] naming the setting when a value is out of range.
    pub fn from_params(params: &Params) -> Result<CameraConfig, CameraError> {
        let table = settings::settings(params);
        let bad = |setting: &'static str, reason: String| CameraError::Config { setting, reason };
        let missing = |name: &'static str| bad(name, "is missing".into());
        // The table read each value as its type and checked its range when it was set.
        let text = |name: &'static str| table.text(name).ok_or_else(|| missing(name));
        let float = |name: &'static str| table.float(name).ok_or_else(|| missing(name));
        let count = |name: &'static str| {
            let v = table.int(name).ok_or_else(|| missing(name))?;
            u32::try_from(v).map_err(|_| bad(name, format!("{v}")))
        };
        let source = Source::parse(text("VisionCameraSource")?).map_err(|r| bad("VisionCameraSource", r))?;
        let size = match (count("VisionCameraWidth")?, count("VisionCameraHeight")?) {
            (0, 0) => None,
            (0, _) | (_, 0) => {
                return Err(bad("VisionCameraWidth", "and VisionCameraHeight must both be 0 or both be set".into()))
            }
            (w, h) => Some((w, h)),
        };
        let format = match text("VisionCameraPixelFormat")?.to_ascii_uppercase().as_str() {
            "AUTO" => None,
            "MJPEG" => Some(PixelFormat::Mjpeg),
            "YUYV" => Some(PixelFormat::Yuyv),
            "GREY" => Some(PixelFormat::Grey),
            other => return Err(bad("VisionCameraPixelFormat", format!("{other} is not auto, MJPEG, YUYV or GREY"))),
        };
        let mark = text("VisionCameraMark")?;
        let kind = mark
            .parse::<MarkKind>()
            .map_err(|_| bad("VisionCameraMark", format!("{} is not dot, ring or cross", mark.to_ascii_lowercase())))?;
        let polarity = match text("VisionCameraPolarity")?.to_ascii_lowercase().as_str() {
            "dark" => Polarity::Dark,
            "light" => Polarity::Light,
            other => return Err(bad("VisionCameraPolarity", format!("{other} is not dark or light"))),
        };
        let diameter = float("VisionCameraMarkDiameterPx")?;
        let diameter_px = if diameter > 0.0 { Some(diameter) } else { derived_diameter(params) };
        let seconds = float("VisionCameraTimeout")?;
        let config = CameraConfig {
            source,
            size,
            format,
            mark: MarkSettings {
                kind,
                diameter_px,
                tolerance_pct: float("VisionCameraMarkTolerance")?,
                polarity,
                search_radius_pct: float("VisionCameraSearchRadius")?,
            },
            timeout: Duration::try_from_secs_f64(seconds)
                .map_err(|_| bad("VisionCameraTimeout", format!("{seconds} s is not a duration")))?,
            flush_frames: count("VisionCameraFlushFrames")?,
        };
        config.validate()?;
        Ok(config)
    }

    /// Checks every field against the settings' ranges ([`settings`]), for a configuration
    /// built in code; a derived diameter and a frame size have their own.
    ///
    /// # Errors
    /// [`CameraError::Config`] naming the first bad one.
    pub fn validate(&self) -> Result<(), CameraError> {
        let named = |setting: &'static str| move |reason: String| CameraError::Config { setting, reason };
        if let Some(d) = self.mark.diameter_px {
            settings::DIAMETER_SET.check(&d).map_err(named("VisionCameraMarkDiameterPx"))?;
        }
        settings::TOLERANCE.check(&self.mark.tolerance_pct).map_err(named("VisionCameraMarkTolerance"))?;
        settings::SEARCH_RADIUS.check(&self.mark.search_radius_pct).map_err(named("VisionCameraSearchRadius"))?;
        settings::TIMEOUT.check(&self.timeout.as_secs_f64()).map_err(named("VisionCameraTimeout"))?;
        settings::FLUSH_FRAMES.check(&i64::from(self.flush_frames)).map_err(named("VisionCameraFlushFrames"))?;
        if let Some((w, h)) = self.size {
            for side in [w, h] {
                settings::SIDE_SET.check(&i64::from(side)).map_err(named("VisionCameraWidth"))?;
            }
        }
        Ok(())
    }
}

/// `VisionMarkDiameter` over the pixel size K gives (√|det K|, world unit per pixel), when both
/// are set and the result is a usable size.
fn derived_diameter(params: &Params) -> Option<f64> {
    let get = |name: &str| params.get(name).ok().and_then(|v| v.as_f64());
    let d = get("VisionMarkDiameter")?;
    let k = ["VisionCal_K11", "VisionCal_K12", "VisionCal_K21", "VisionCal_K22"].map(get);
    let [Some(k11), Some(k12), Some(k21), Some(k22)] = k else { return None };
    let pixel = (k11 * k22 - k12 * k21).abs().sqrt();
    let px = d / pixel;
    (px.is_finite() && px >= 2.0).then_some(px)
}

#[cfg(test)]
mod tests {
    use vision_core::ParamValue;

    use super::*;

    fn params() -> Params {
        Params::default().with_driver_settings(&settings::SETTINGS)
    }

    #[test]
    fn sources_are_told_apart() {
        assert_eq!(Source::parse("/dev/video2"), Ok(Source::Device("/dev/video2".into())));
        assert_eq!(Source::parse("v4l2:/dev/v4l/by-id/usb-cam"), Ok(Source::Device("/dev/v4l/by-id/usb-cam".into())));
        assert_eq!(Source::parse(" frames/ "), Ok(Source::Files("frames/".into())));
        assert_eq!(Source::parse("file:a.png"), Ok(Source::Files("a.png".into())));
        assert!(matches!(Source::parse("http://cam:8080/?action=snapshot"), Ok(Source::Http(_))));
        assert!(Source::parse("https://cam/").expect_err("tls").contains("https is not supported"));
        assert!(Source::parse("  ").is_err());
    }

    #[test]
    fn the_defaults_read_back_and_the_diameter_follows_k() {
        let mut p = params();
        let c = CameraConfig::from_params(&p).expect("defaults");
        assert!(matches!(&c.source, Source::Http(_)), "the default opens without the v4l2 feature: {:?}", c.source);
        assert_eq!((c.size, c.format, c.flush_frames), (None, None, 2));
        assert_eq!(c.mark.diameter_px, None, "no K, no VisionMarkDiameter: nothing to derive from");
        p.set("VisionMarkDiameter", 0.25).expect("set");
        for (name, v) in
            [("VisionCal_K11", 0.002), ("VisionCal_K12", 0.0), ("VisionCal_K21", 0.0), ("VisionCal_K22", -0.002)]
        {
            p.set(name, v).expect("set");
        }
        let d = CameraConfig::from_params(&p).expect("derived").mark.diameter_px.expect("a diameter");
        assert!((d - 125.0).abs() < 1e-9, "{d}");
        p.set("VisionCameraMarkDiameterPx", 80.0).expect("set");
        p.set("VisionCameraPixelFormat", "yuyv").expect("set");
        p.set("VisionCameraPolarity", "light").expect("set");
        let c = CameraConfig::from_params(&p).expect("explicit");
        assert_eq!(
            (c.mark.diameter_px, c.format, c.mark.polarity),
            (Some(80.0), Some(PixelFormat::Yuyv), Polarity::Light)
        );
    }

    #[test]
    fn out_of_range_settings_are_refused_by_name() {
        let mut p = params();
        for (name, v) in [
            ("VisionCameraTimeout", ParamValue::Float(0.0)),
            ("VisionCameraFlushFrames", ParamValue::Int(31)),
            ("VisionCameraMarkTolerance", ParamValue::Float(100.0)),
            ("VisionCameraWidth", ParamValue::Int(-1)),
            ("VisionCameraSource", ParamValue::Text("https://x/".into())),
            ("VisionCameraMark", ParamValue::Text("star".into())),
        ] {
            let e = p.set(name, v).expect_err(name).to_string();
            assert!(e.contains(name), "{e}");
        }
        p.set("VisionCameraWidth", 640).expect("set");
        let e = CameraConfig::from_params(&p).expect_err("height missing");
        assert!(matches!(e, CameraError::Config { setting: "VisionCameraWidth", .. }), "{e}");
    }
}

#[cfg(test)]
mod props {
    use vision_core::ParamValue;

    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Any text as VisionCameraSource: a source or a reason, never a panic.
        #[test]
        fn any_source_text_parses_or_says_why(text in "\\PC{0,80}") {
            if let Ok(Source::Http(u)) = Source::parse(&text) {
                prop_assert!(u.path.starts_with('/'));
            }
        }

        /// Any value of any setting: the profile refuses it by name, or the typed config reads
        /// it back within its range. Never a panic, never a NaN.
        #[test]
        fn any_setting_value_is_refused_or_read_in_range(
            which in 0usize..11, f in proptest::num::f64::ANY, i in any::<i64>(), t in "\\PC{0,20}", kind in 0usize..3,
        ) {
            let name = settings::SETTINGS.settings[which].spec.name;
            let value = match kind {
                0 => ParamValue::Float(f),
                1 => ParamValue::Int(i),
                _ => ParamValue::Text(t),
            };
            let mut p = Params::default().with_driver_settings(&settings::SETTINGS);
            if p.set(name, value).is_ok() {
                // Width alone is refused by the typed read (it needs a height).
                if let Ok(c) = CameraConfig::from_params(&p) {
                    prop_assert!(c.validate().is_ok());
                    prop_assert!(c.mark.tolerance_pct.is_finite() && c.mark.search_radius_pct.is_finite());
                    prop_assert!(c.mark.diameter_px.is_none_or(f64::is_finite));
                }
            }
        }
    }
}
