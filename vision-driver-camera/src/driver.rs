//! [`FrameDriver`]: a frame source plus `vision-locate`, as a [`CameraDriver`].

use std::path::PathBuf;
use std::time::{Duration, Instant};

use vision_core::{CameraDriver, Capabilities, DriverError, DriverRegistry, ImageRequest, Judgment, Params, Reading};
use vision_locate::{Budget, GrayImage, LocateError, Located, NotFoundReason, Pixels};

use crate::config::{CameraConfig, Polarity, Source};
use crate::error::CameraError;
use crate::frame::Frame;
use crate::source::{FileSource, FrameSource, HttpSource};
use crate::v4l2::{self, V4l2Source};
use crate::window::window;

/// The driver's registry name (`VisionDriver = Camera`).
pub const DRIVER_NAME: &str = "Camera";

/// Why the last trigger found no mark, in `vision-locate`'s words.
#[derive(Debug, Clone, PartialEq)]
pub struct Miss {
    /// The finder's reason (no candidate, several candidates, clipped, size out of range).
    pub reason: String,
    /// How many candidate marks it saw, when it says (2 or more: it refused to pick one).
    pub candidates: Option<u32>,
}

/// A camera whose frames the driver searches itself.
///
/// Per trigger: a live source first gives `VisionCameraFlushFrames` frames that are thrown
/// away (a V4L2 queue or a snapshot server's buffer may hold frames from before the last
/// move); the next frame is searched for the mark. A found mark is an `OK` reading, count 1,
/// its centre in native pixels (the finder's pixel-centre coordinates + ½: native (0, 0) is the
/// top-left corner of the image, as the Keyence camera and the simulator count), width and
/// height its diameter in pixels, angle in degrees, score 0–1. No mark, or several, is `NG`
/// ([`FrameDriver::last_miss`] says why), as the Keyence camera judges a failed inspection.
///
/// The search gets `VisionCameraTimeout` of its own, counted from the frame's arrival: one
/// that runs longer (a huge or hostile frame) is cut off, [`CameraError::SearchCutOff`], never
/// a guess.
pub struct FrameDriver<S: FrameSource = Box<dyn FrameSource>> {
    config: CameraConfig,
    source: S,
    last_frame: Option<Frame>,
    last_miss: Option<Miss>,
    /// The size of the last frame the source gave, pixels (a trigger's or a size probe's).
    frame_size: Option<(u32, u32)>,
}

impl<S: FrameSource> std::fmt::Debug for FrameDriver<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FrameDriver").field("config", &self.config).field("source", &self.source.describe()).finish()
    }
}

impl FrameSource for Box<dyn FrameSource> {
    fn frame(&mut self) -> Result<Frame, CameraError> {
        (**self).frame()
    }
    fn describe(&self) -> String {
        (**self).describe()
    }
    fn is_live(&self) -> bool {
        (**self).is_live()
    }
    fn has_jobs(&self) -> bool {
        (**self).has_jobs()
    }
    fn select_job(&mut self, job: u32) -> Result<(), CameraError> {
        (**self).select_job(job)
    }
}

impl FrameDriver {
    /// A driver from its settings in `params`, on the source `VisionCameraSource` names. Opens
    /// nothing until the first frame.
    ///
    /// # Errors
    /// As [`CameraConfig::from_params`]; [`CameraError::NoDevice`] for a V4L2 device path that
    /// names nothing, [`CameraError::DeviceOpen`] for a V4L2 device in a build without the
    /// `v4l2` feature or a device that cannot be opened.
    pub fn from_params(params: &Params) -> Result<FrameDriver, CameraError> {
        let config = CameraConfig::from_params(params)?;
        let source: Box<dyn FrameSource> = match &config.source {
            Source::Files(path) => Box::new(FileSource::new(path.clone())),
            Source::Http(url) => Box::new(HttpSource::new(url.clone(), config.timeout)),
            Source::Device(path) => {
                Box::new(V4l2Source::new(v4l2::open(path)?, config.format, config.size, config.timeout))
            }
        };
        FrameDriver::new(config, source)
    }
}

impl<S: FrameSource> FrameDriver<S> {
    /// A driver searching `source`'s frames as `config` says (its `source` field is for
    /// [`FrameDriver::from_params`]; here `source` is used).
    ///
    /// # Errors
    /// [`CameraError::Config`] when the configuration is unusable.
    pub fn new(config: CameraConfig, source: S) -> Result<FrameDriver<S>, CameraError> {
        config.validate()?;
        Ok(FrameDriver { config, source, last_frame: None, last_miss: None, frame_size: None })
    }

    /// The configuration.
    #[must_use]
    pub fn config(&self) -> &CameraConfig {
        &self.config
    }

    /// The frame source.
    pub fn source(&self) -> &S {
        &self.source
    }

    /// Why the last trigger found no mark (`None` after a found mark or before any trigger).
    #[must_use]
    pub fn last_miss(&self) -> Option<&Miss> {
        self.last_miss.as_ref()
    }

    /// The frame the last trigger searched.
    #[must_use]
    pub fn last_frame(&self) -> Option<&Frame> {
        self.last_frame.as_ref()
    }

    fn spec(&self) -> Result<vision_locate::MarkSpec, CameraError> {
        let m = &self.config.mark;
        let diameter = m.diameter_px.ok_or(CameraError::Config {
            setting: "VisionCameraMarkDiameterPx",
            reason: "is 0 and cannot be derived (VisionMarkDiameter or K is not set): give the mark's diameter in \
                     image pixels"
                .into(),
        })?;
        let polarity = match m.polarity {
            Polarity::Dark => vision_locate::Polarity::DarkOnLight,
            Polarity::Light => vision_locate::Polarity::LightOnDark,
        };
        vision_locate::MarkSpec::new(m.kind, diameter, m.tolerance_pct / 100.0, polarity)
            .map_err(|e| CameraError::Config { setting: "VisionCameraMarkDiameterPx", reason: e.to_string() })
    }

    /// One frame, and its search: the reading as [`CameraDriver::trigger`] gives it.
    ///
    /// # Errors
    /// The source's [`CameraError`], or [`CameraError::Config`] for an unusable mark.
    pub fn measure(&mut self) -> Result<Reading, CameraError> {
        let spec = self.spec()?;
        if self.source.is_live() {
            for _ in 0..self.config.flush_frames {
                self.source.frame()?;
            }
        }
        let frame = self.source.frame()?;
        let budget = Budget::until(Instant::now() + self.config.timeout);
        let search = |frame: &Frame, miss: &mut Option<Miss>| search(frame, &spec, &budget, self.config.timeout, miss);
        let reading = match window(&frame, self.config.mark.search_radius_pct) {
            Some((part, x0, y0)) => search(&part, &mut self.last_miss).map(|r| {
                if r.found() {
                    Reading { x_px: r.x_px + f64::from(x0), y_px: r.y_px + f64::from(y0), ..r }
                } else {
                    r
                }
            }),
            None => search(&frame, &mut self.last_miss),
        };
        self.frame_size = Some((frame.width(), frame.height()));
        self.last_frame = Some(frame);
        reading
    }
}

/// Searches `frame` within `budget` (`timeout` is what it allows, for the message); a miss is
/// recorded in `miss`.
fn search(
    frame: &Frame,
    spec: &vision_locate::MarkSpec,
    budget: &Budget,
    timeout: Duration,
    miss: &mut Option<Miss>,
) -> Result<Reading, CameraError> {
    let image = GrayImage::new(frame.width() as usize, frame.height() as usize, Pixels::Gray8(frame.pixels()))
        .map_err(|e| CameraError::Decode { from: "the frame".into(), reason: e.to_string() })?;
    let located = vision_locate::locate_within(&image, spec, budget).map_err(|e| match e {
        LocateError::Deadline => CameraError::SearchCutOff { width: frame.width(), height: frame.height(), timeout },
        e => CameraError::Config { setting: "VisionCameraMarkDiameterPx", reason: e.to_string() },
    })?;
    let ng = |count| Reading { judgment: Judgment::Ng, count: Some(count), ..Reading::position(0.0, 0.0) };
    match located {
        Located::Found(m) if [m.x, m.y, m.diameter, m.score, m.angle.unwrap_or(0.0)].iter().all(|v| v.is_finite()) => {
            *miss = None;
            Ok(Reading {
                judgment: Judgment::Ok,
                count: Some(1),
                // Pixel centres → native pixels (corner origin).
                x_px: m.x + 0.5,
                y_px: m.y + 0.5,
                width_px: m.diameter,
                height_px: m.diameter,
                // Radians towards +y (down) → degrees counter-clockwise as seen; 0 for a round mark.
                angle_deg: m.angle.map_or(0.0, |a| -a.to_degrees()),
                score: m.score,
            })
        }
        Located::Found(m) => {
            *miss = Some(Miss { reason: format!("the finder returned a non-finite mark {m:?}"), candidates: None });
            Ok(ng(0))
        }
        Located::NotFound(reason) => {
            let candidates = match reason {
                NotFoundReason::SeveralCandidates { count } => Some(u32::try_from(count).unwrap_or(u32::MAX)),
                _ => None,
            };
            // The finder's advice says "the diameter setting": here that is two, with their values.
            let settings = format!(
                "VisionCameraMarkDiameterPx ({} px) and VisionCameraMarkTolerance ({} %)",
                tenths(spec.diameter_px),
                tenths(spec.tolerance * 100.0)
            );
            let reason = reason.to_string().replacen("the diameter setting", &settings, 1);
            *miss = Some(Miss { reason, candidates });
            Ok(ng(candidates.unwrap_or(0)))
        }
    }
}

/// `v` to a tenth, without trailing zeros (`40`, `12.5`).
fn tenths(v: f64) -> f64 {
    (v * 10.0).round() / 10.0
}

impl<S: FrameSource> CameraDriver for FrameDriver<S> {
    fn name(&self) -> &str {
        DRIVER_NAME
    }

    fn capabilities(&self) -> Capabilities {
        Capabilities { select_job: self.source.has_jobs(), grab_image: true }
    }

    fn trigger(&mut self) -> Result<Reading, DriverError> {
        self.measure().map_err(DriverError::from)
    }

    fn select_job(&mut self, job: u32) -> Result<(), DriverError> {
        self.source.select_job(job).map_err(DriverError::from)
    }

    /// The frame the last trigger searched, a [`Frame`].
    fn last_frame(&self) -> Option<&dyn std::any::Any> {
        self.last_frame.as_ref().map(|f| f as &dyn std::any::Any)
    }

    /// The shape and contrast searched for (the diameter is left out: unset, it follows K).
    fn mark_spec(&self) -> Option<String> {
        let mark = &self.config.mark;
        let kind = mark.kind.name();
        let contrast = match mark.polarity {
            crate::Polarity::Dark => "dark on light",
            crate::Polarity::Light => "light on dark",
        };
        Some(format!("{kind}, {contrast}"))
    }

    /// The last frame's size; before the first trigger, one frame is taken to find it out.
    fn frame_size(&mut self) -> Option<(u32, u32)> {
        if self.frame_size.is_none() {
            let frame = self.source.frame().ok()?;
            self.frame_size = Some((frame.width(), frame.height()));
        }
        self.frame_size
    }

    fn miss_reason(&self) -> Option<String> {
        self.last_miss.as_ref().map(|m| format!("the finder: {}", m.reason))
    }

    fn test_connection(&mut self) -> Result<String, DriverError> {
        let frame = self.source.frame().map_err(DriverError::from)?;
        let text = format!("{}: {}×{} frame", self.source.describe(), frame.width(), frame.height());
        self.frame_size = Some((frame.width(), frame.height()));
        self.last_frame = Some(frame);
        Ok(text)
    }

    /// M281 D1: the frame the last trigger searched, saved as `vision_<stamp>.png`.
    fn grab_image(&mut self, request: &ImageRequest<'_>) -> Result<PathBuf, DriverError> {
        let frame =
            self.last_frame.as_ref().ok_or(CameraError::Unsupported { what: "keep an image before a trigger" })?;
        let io = |e: &dyn std::fmt::Display| CameraError::File {
            path: request.dir.display().to_string(),
            reason: e.to_string(),
        };
        std::fs::create_dir_all(request.dir).map_err(|e| io(&e))?;
        let image = image::GrayImage::from_raw(frame.width(), frame.height(), frame.pixels().to_vec())
            .ok_or_else(|| io(&"the frame's size does not match its pixels"))?;
        for n in 1..1000 {
            let name = if n == 1 {
                format!("vision_{}.png", request.stamp)
            } else {
                format!("vision_{}_{n}.png", request.stamp)
            };
            let path = request.dir.join(name);
            // create_new: a file is never overwritten, even by a race.
            match std::fs::OpenOptions::new().write(true).create_new(true).open(&path) {
                Ok(file) => {
                    let mut w = std::io::BufWriter::new(file);
                    image.write_to(&mut w, image::ImageFormat::Png).map_err(|e| io(&e))?;
                    return Ok(path);
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
                Err(e) => return Err(io(&e).into()),
            }
        }
        Err(io(&"999 images with this stamp already exist").into())
    }

    fn timeout(&self) -> Duration {
        self.config.timeout
    }
}

/// Registers the driver as `Camera` with its `[camera]` settings.
pub fn register(registry: &mut DriverRegistry) {
    registry.register_with_settings(DRIVER_NAME, &crate::settings::SETTINGS, |params: &Params| {
        let driver = FrameDriver::from_params(params).map_err(DriverError::from)?;
        Ok(Box::new(driver) as Box<dyn CameraDriver>)
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use vision_locate::render::{render, Depth, PlacedMark, Scene, Shape};
    use vision_locate::OwnedPixels;

    /// A live source of rendered frames: dots at `marks` (native pixels), counting its frames.
    struct Rendered {
        marks: Vec<(f64, f64)>,
        frames: usize,
    }

    impl FrameSource for Rendered {
        fn frame(&mut self) -> Result<Frame, CameraError> {
            self.frames += 1;
            let scene = Scene {
                marks: self
                    .marks
                    .iter()
                    .map(|&(x, y)| PlacedMark {
                        shape: Shape::Dot { diameter: 40.0 },
                        x: x - 0.5,
                        y: y - 0.5,
                        reflectance: 0.1,
                    })
                    .collect(),
                blur_sigma: 1.0,
                noise_sigma: 1.0,
                seed: self.frames as u64,
                ..Scene::blank(320, 240, Depth::Eight)
            };
            let OwnedPixels::Gray8(pixels) = render(&scene).expect("scene").into_pixels() else { unreachable!() };
            Ok(Frame::new(320, 240, pixels).expect("frame"))
        }
        fn describe(&self) -> String {
            "rendered".into()
        }
    }

    fn driver(marks: Vec<(f64, f64)>) -> FrameDriver<Rendered> {
        let config = CameraConfig::new(Source::Files("unused".into()), 40.0);
        FrameDriver::new(config, Rendered { marks, frames: 0 }).expect("driver")
    }

    #[test]
    fn a_mark_is_read_in_native_pixels_after_the_flushed_frames() {
        let mut d = driver(vec![(150.3, 110.7)]);
        let r = d.trigger().expect("reading");
        assert_eq!((r.judgment, r.count), (Judgment::Ok, Some(1)));
        assert!((r.x_px - 150.3).abs() < 0.05 && (r.y_px - 110.7).abs() < 0.05, "{r:?}");
        assert!((r.width_px - 40.0).abs() < 0.5 && r.score > 0.8, "{r:?}");
        assert_eq!(d.source().frames, 3, "two flushed, one searched");
        assert!(d.last_miss().is_none());
        assert_eq!(d.capabilities(), Capabilities { select_job: false, grab_image: true });
        assert_eq!(d.select_job(1).expect_err("no jobs").kind(), vision_core::DriverErrorKind::Unsupported);
    }

    #[test]
    fn two_marks_or_none_are_ng_and_say_why() {
        let mut d = driver(vec![(80.0, 120.0), (240.0, 120.0)]);
        let r = d.trigger().expect("reading");
        assert_eq!((r.judgment, r.count, r.found()), (Judgment::Ng, Some(2), false));
        let miss = d.last_miss().expect("a reason");
        assert_eq!(miss.candidates, Some(2));
        assert!(miss.reason.contains("2 marks in view"), "{miss:?}");
        // The core's NG message carries it.
        let ng = vision_core::VisionError::NoMark { reason: d.miss_reason() }.to_string();
        assert!(ng.starts_with("NG / no mark found — the camera job did not find a fiducial in the field of view (the finder: 2 marks in view"), "{ng}");
        // A search radius that leaves the neighbour out reads the centred mark.
        let mut d = driver(vec![(160.0, 120.0), (290.0, 120.0)]);
        d.config.mark.search_radius_pct = 80.0;
        let r = d.trigger().expect("reading");
        assert!(r.found() && (r.x_px - 160.0).abs() < 0.05, "{r:?} {:?}", d.last_miss());
        let mut d = driver(Vec::new());
        let r = d.trigger().expect("reading");
        assert_eq!((r.judgment, r.count), (Judgment::Ng, Some(0)));
        assert!(d.last_miss().expect("a reason").reason.starts_with("no mark in view"));
    }

    #[test]
    fn the_frame_searched_is_handed_out_through_the_trait_as_a_frame() {
        let mut d = driver(vec![(150.3, 110.7)]);
        assert!(CameraDriver::last_frame(&d).is_none(), "no trigger yet");
        d.trigger().expect("reading");
        let boxed: Box<dyn CameraDriver> = Box::new(d);
        let frame = boxed.last_frame().and_then(|f| f.downcast_ref::<Frame>()).expect("a Frame");
        assert_eq!((frame.width(), frame.height()), (320, 240));
    }

    #[test]
    fn a_search_past_the_timeout_is_cut_off_never_a_mark() {
        // Issue 33: one M281 searched for 25.6 s under VisionCameraTimeout = 3. The search now
        // has the timeout as its deadline: 1 ns has passed before the search's first stage ends.
        let mut d = driver(vec![(150.3, 110.7)]);
        d.config.timeout = Duration::from_nanos(1);
        let e = d.trigger().expect_err("cut off");
        assert_eq!(e.kind(), vision_core::DriverErrorKind::Timeout);
        assert!(
            e.to_string().starts_with("timeout: the mark search in a 320×240 frame was cut off after 0.000 s (VisionCameraTimeout); nothing is known of the mark — narrow VisionCameraSearchRadius"),
            "{e}"
        );
        assert!(d.last_miss().is_none());
        // A deadline already passed is honoured however small the frame.
        let frame = d.last_frame().cloned().expect("the searched frame is kept");
        let spec = d.spec().expect("spec");
        let passed = Budget::until(Instant::now());
        let e = search(&frame, &spec, &passed, Duration::from_secs(3), &mut None).expect_err("cut off");
        assert_eq!(e, CameraError::SearchCutOff { width: 320, height: 240, timeout: Duration::from_secs(3) });
        // With the default 3 s the same frames are read.
        d.config.timeout = Duration::from_secs(3);
        assert!(d.trigger().expect("reading").found());
    }

    #[test]
    fn a_mark_of_another_size_is_ng_naming_both_sizes_and_the_setting() {
        // Issue 33: the NG message said "check position, focus and lighting" for a wrong diameter.
        let mut d = driver(vec![(160.0, 120.0)]);
        d.config.mark.diameter_px = Some(25.0);
        let r = d.trigger().expect("reading");
        assert_eq!((r.judgment, r.count), (Judgment::Ng, Some(0)));
        let ng = vision_core::VisionError::NoMark { reason: d.miss_reason() }.to_string();
        assert!(
            ng.contains("(the finder: a mark of 39.9 px is in view, but 18.8–31.2 px was expected — check VisionCameraMarkDiameterPx (25 px) and VisionCameraMarkTolerance (25 %)); re-jog"),
            "{ng}"
        );
        // Far too small a diameter: the coarse search passes the dot over, and says its size.
        d.config.mark.diameter_px = Some(8.0);
        d.trigger().expect("reading");
        let miss = &d.last_miss().expect("a miss").reason;
        assert!(miss.starts_with("no mark of 6.0–10.0 px in view, but a blob about "), "{miss}");
        assert!(
            miss.ends_with(
                " px across is — check VisionCameraMarkDiameterPx (8 px) and VisionCameraMarkTolerance (25 %) (or the \
                 position, focus and lighting)"
            ),
            "{miss}"
        );
    }

    #[test]
    fn an_unknown_diameter_is_a_setting_error_before_any_frame() {
        let mut config = CameraConfig::new(Source::Files("unused".into()), 40.0);
        config.mark.diameter_px = None;
        let mut d = FrameDriver::new(config, Rendered { marks: Vec::new(), frames: 0 }).expect("driver");
        let e = d.trigger().expect_err("no diameter");
        assert_eq!(e.kind(), vision_core::DriverErrorKind::InvalidArgument);
        assert!(e.to_string().starts_with("invalid camera setting VisionCameraMarkDiameterPx: is 0"), "{e}");
        assert_eq!(d.source().frames, 0);
    }

    #[test]
    fn m281_d1_keeps_the_searched_frame_and_never_overwrites() {
        let dir = std::env::temp_dir().join(format!("vision-camera-grab-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut d = driver(vec![(160.0, 120.0)]);
        let request = ImageRequest { dir: &dir, since: std::time::SystemTime::now(), stamp: "20261126_000000_000" };
        assert_eq!(d.grab_image(&request).expect_err("no frame yet").kind(), vision_core::DriverErrorKind::Unsupported);
        d.trigger().expect("reading");
        let first = d.grab_image(&request).expect("saved");
        let second = d.grab_image(&request).expect("saved again");
        assert!(
            first.ends_with("vision_20261126_000000_000.png") && second.ends_with("vision_20261126_000000_000_2.png")
        );
        let saved = crate::decode_image(&std::fs::read(&first).expect("read"), "saved").expect("png");
        assert_eq!(Some(&saved), d.last_frame());
        std::fs::remove_dir_all(&dir).expect("clean up");
    }
}
