//! V4L2 (USB/UVC) cameras: format negotiation and frame decoding over a small [`Device`]
//! interface, so both are tested without a camera (a scripted fake device) and the kernel edge
//! stays thin (`v4l2` cargo feature, [`open`]).

use std::fmt;
use std::io;
use std::time::Duration;

use crate::config::PixelFormat;
use crate::error::CameraError;
use crate::frame::{decode_raw, Frame};
use crate::source::FrameSource;

/// One frame size of one pixel format a device offers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FormatOffer {
    /// The V4L2 FourCC (`YUYV`, `MJPG`, `GREY`, …).
    pub fourcc: [u8; 4],
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
}

impl fmt::Display for FormatOffer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let name = PixelFormat::from_fourcc(self.fourcc)
            .map_or_else(|| String::from_utf8_lossy(&self.fourcc).into_owned(), |p| p.to_string());
        write!(f, "{name} {}×{}", self.width, self.height)
    }
}

/// The format a device says it set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeviceFormat {
    /// The offer it set.
    pub offer: FormatOffer,
    /// Bytes from one row to the next (`bytesperline`; 0 for compressed formats).
    pub stride: u32,
}

/// What the driver needs of a V4L2 device: what it offers, setting a format, and capturing.
pub trait Device: Send {
    /// The device path, for messages.
    fn path(&self) -> &str;

    /// Every (format, size) the device offers (`VIDIOC_ENUM_FMT` × `VIDIOC_ENUM_FRAMESIZES`).
    ///
    /// # Errors
    /// The device's I/O error.
    fn offers(&mut self) -> io::Result<Vec<FormatOffer>>;

    /// Sets `offer` (`VIDIOC_S_FMT`) and starts streaming; returns what the device set, which a
    /// driver may have adjusted.
    ///
    /// # Errors
    /// The device's I/O error.
    fn set_format(&mut self, offer: FormatOffer) -> io::Result<DeviceFormat>;

    /// The next frame's bytes, waiting at most `timeout`; `Ok(None)` when none came in time.
    ///
    /// # Errors
    /// The device's I/O error.
    fn capture(&mut self, timeout: Duration) -> io::Result<Option<Vec<u8>>>;
}

/// The offer to use: of the offers the driver decodes, those of `format` and `size` when given;
/// then the largest, then the best format (GREY, YUYV, MJPEG).
///
/// # Errors
/// [`CameraError::Format`] listing what the device offers.
pub fn negotiate(
    device: &str,
    offers: &[FormatOffer],
    format: Option<PixelFormat>,
    size: Option<(u32, u32)>,
) -> Result<(PixelFormat, FormatOffer), CameraError> {
    let best = offers
        .iter()
        .filter_map(|o| PixelFormat::from_fourcc(o.fourcc).map(|p| (p, *o)))
        .filter(|(p, o)| format.is_none_or(|f| f == *p) && size.is_none_or(|s| s == (o.width, o.height)))
        .max_by_key(|(p, o)| (u64::from(o.width) * u64::from(o.height), std::cmp::Reverse(p.rank())));
    best.ok_or_else(|| {
        let wanted = match (format, size) {
            (None, None) => "any of GREY, YUYV or MJPEG".to_string(),
            (Some(f), None) => f.to_string(),
            (None, Some((w, h))) => format!("{w}×{h} in GREY, YUYV or MJPEG"),
            (Some(f), Some((w, h))) => format!("{f} {w}×{h}"),
        };
        let offered = if offers.is_empty() {
            "nothing".to_string()
        } else {
            offers.iter().map(ToString::to_string).collect::<Vec<_>>().join(", ")
        };
        CameraError::Format { device: device.to_string(), wanted, offered }
    })
}

/// A V4L2 camera as a frame source: negotiates on the first frame, then captures and decodes.
pub struct V4l2Source<D: Device> {
    device: D,
    format: Option<PixelFormat>,
    size: Option<(u32, u32)>,
    timeout: Duration,
    set: Option<(PixelFormat, DeviceFormat)>,
}

impl<D: Device> fmt::Debug for V4l2Source<D> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("V4l2Source").field("device", &self.device.path()).field("set", &self.set).finish()
    }
}

impl<D: Device> V4l2Source<D> {
    /// A source on `device` for `format` and `size` (`None`: the best the device offers), each
    /// capture within `timeout`.
    pub fn new(device: D, format: Option<PixelFormat>, size: Option<(u32, u32)>, timeout: Duration) -> V4l2Source<D> {
        V4l2Source { device, format, size, timeout, set: None }
    }

    /// The negotiated format, once a frame has been asked for.
    pub fn negotiated(&self) -> Option<(PixelFormat, DeviceFormat)> {
        self.set
    }

    fn io(&self, e: &io::Error) -> CameraError {
        CameraError::Io { from: self.device.path().to_string(), reason: e.to_string() }
    }

    fn open(&mut self) -> Result<(PixelFormat, DeviceFormat), CameraError> {
        if let Some(set) = self.set {
            return Ok(set);
        }
        let path = self.device.path().to_string();
        let offers = self.device.offers().map_err(|e| self.io(&e))?;
        let (pixel, offer) = negotiate(&path, &offers, self.format, self.size)?;
        let got = self.device.set_format(offer).map_err(|e| self.io(&e))?;
        if got.offer != offer {
            return Err(CameraError::FormatChanged {
                device: path,
                wanted: offer.to_string(),
                got: got.offer.to_string(),
            });
        }
        self.set = Some((pixel, got));
        Ok((pixel, got))
    }
}

impl<D: Device> FrameSource for V4l2Source<D> {
    fn frame(&mut self) -> Result<Frame, CameraError> {
        let (pixel, set) = self.open()?;
        let path = self.device.path().to_string();
        let bytes = match self.device.capture(self.timeout) {
            Ok(Some(bytes)) => bytes,
            Ok(None) => return Err(CameraError::Timeout { from: path, timeout: self.timeout, waiting_for: "a frame" }),
            Err(e) => {
                // A device that failed mid-stream is renegotiated at the next frame.
                self.set = None;
                return Err(self.io(&e));
            }
        };
        decode_raw(pixel, set.offer.width, set.offer.height, set.stride, &bytes, &path)
    }

    fn describe(&self) -> String {
        match self.set {
            Some((pixel, set)) => format!("{} {pixel} {}×{}", self.device.path(), set.offer.width, set.offer.height),
            None => format!("{} (format not negotiated yet)", self.device.path()),
        }
    }
}

/// Opens a V4L2 device node. A build without the `v4l2` cargo feature (or not on 64-bit
/// Linux) has no kernel backend and answers [`CameraError::DeviceOpen`] saying so for a path
/// that exists, [`CameraError::NoDevice`] for one that does not, as the backend does.
///
/// # Errors
/// [`CameraError::NoDevice`], [`CameraError::DeviceOpen`].
#[cfg(not(all(feature = "v4l2", target_os = "linux", target_pointer_width = "64")))]
pub fn open(path: &std::path::Path) -> Result<Box<dyn Device>, CameraError> {
    let device = path.display().to_string();
    if !path.exists() {
        return Err(CameraError::NoDevice { device });
    }
    let reason = "this build of mach-vision has no V4L2 capture backend (build vision-driver-camera with the `v4l2` \
                  feature), or serve the camera with mjpg-streamer or ustreamer and set VisionCameraSource to its \
                  http:// snapshot URL";
    Err(CameraError::DeviceOpen { device, reason: reason.into() })
}

#[cfg(all(feature = "v4l2", target_os = "linux", target_pointer_width = "64"))]
pub use crate::v4l2_linux::open;

impl Device for Box<dyn Device> {
    fn path(&self) -> &str {
        (**self).path()
    }
    fn offers(&mut self) -> io::Result<Vec<FormatOffer>> {
        (**self).offers()
    }
    fn set_format(&mut self, offer: FormatOffer) -> io::Result<DeviceFormat> {
        (**self).set_format(offer)
    }
    fn capture(&mut self, timeout: Duration) -> io::Result<Option<Vec<u8>>> {
        (**self).capture(timeout)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::VecDeque;

    /// A scripted device: what it offers, how it adjusts a format, and the captures it returns.
    struct Fake {
        offers: Vec<FormatOffer>,
        adjust: Option<FormatOffer>,
        stride_pad: u32,
        captures: VecDeque<io::Result<Option<Vec<u8>>>>,
        set_calls: usize,
    }

    impl Device for Fake {
        fn path(&self) -> &str {
            "/dev/video7"
        }
        fn offers(&mut self) -> io::Result<Vec<FormatOffer>> {
            Ok(self.offers.clone())
        }
        fn set_format(&mut self, offer: FormatOffer) -> io::Result<DeviceFormat> {
            self.set_calls += 1;
            let offer = self.adjust.unwrap_or(offer);
            let per = if offer.fourcc == *b"YUYV" { 2 } else { 1 };
            Ok(DeviceFormat { offer, stride: offer.width * per + self.stride_pad })
        }
        fn capture(&mut self, _: Duration) -> io::Result<Option<Vec<u8>>> {
            self.captures.pop_front().unwrap_or(Ok(None))
        }
    }

    fn offer(fourcc: [u8; 4], width: u32, height: u32) -> FormatOffer {
        FormatOffer { fourcc, width, height }
    }

    fn webcam() -> Vec<FormatOffer> {
        vec![
            offer(*b"YUYV", 640, 480),
            offer(*b"MJPG", 1280, 960),
            offer(*b"YUYV", 1280, 960),
            offer(*b"H264", 1920, 1080),
        ]
    }

    #[test]
    fn negotiation_takes_the_largest_then_the_best_format() {
        let (p, o) = negotiate("d", &webcam(), None, None).expect("auto");
        assert_eq!((p, o), (PixelFormat::Yuyv, offer(*b"YUYV", 1280, 960)), "H264 is not decoded; YUYV beats MJPEG");
        let (p, _) = negotiate("d", &webcam(), Some(PixelFormat::Mjpeg), None).expect("mjpeg");
        assert_eq!(p, PixelFormat::Mjpeg);
        let (_, o) = negotiate("d", &webcam(), None, Some((640, 480))).expect("size");
        assert_eq!(o, offer(*b"YUYV", 640, 480));
        let e = negotiate("/dev/video7", &webcam(), Some(PixelFormat::Grey), Some((640, 480))).expect_err("no grey");
        assert_eq!(
            e.to_string(),
            "/dev/video7 does not offer GREY 640×480; it offers YUYV 640×480, MJPEG 1280×960, YUYV 1280×960, H264 1920×1080 \
             — set VisionCameraWidth, VisionCameraHeight and VisionCameraPixelFormat to one the device offers \
             (v4l2-ctl --list-formats-ext)"
        );
        assert!(negotiate("d", &[], None, None).expect_err("nothing").to_string().contains("it offers nothing"));
    }

    #[test]
    fn frames_decode_in_the_negotiated_format_and_the_format_is_set_once() {
        // A 4×2 YUYV frame with 4 bytes of row padding: Y = 0..8.
        let row = |y0: u8| [y0, 128, y0 + 1, 128, y0 + 2, 128, y0 + 3, 128, 0, 0, 0, 0];
        let frame = [row(0), row(4)].concat();
        let device = Fake {
            offers: vec![offer(*b"YUYV", 4, 2)],
            adjust: None,
            stride_pad: 4,
            captures: VecDeque::from([Ok(Some(frame.clone())), Ok(Some(frame)), Ok(None)]),
            set_calls: 0,
        };
        let mut source = V4l2Source::new(device, None, None, Duration::from_millis(50));
        assert_eq!(source.frame().expect("frame").pixels(), [0, 1, 2, 3, 4, 5, 6, 7]);
        assert!(source.frame().is_ok());
        assert_eq!(source.device.set_calls, 1);
        assert_eq!(source.describe(), "/dev/video7 YUYV 4×2");
        let e = source.frame().expect_err("silent device");
        assert!(
            e.to_string().starts_with("timeout: no complete frame from /dev/video7 within 0.050 s: a frame never came"),
            "{e}"
        );
    }

    #[test]
    fn a_device_that_changes_the_format_or_fails_is_reported() {
        let mut source = V4l2Source::new(
            Fake {
                offers: vec![offer(*b"MJPG", 1280, 960)],
                adjust: Some(offer(*b"MJPG", 640, 480)),
                stride_pad: 0,
                captures: VecDeque::new(),
                set_calls: 0,
            },
            None,
            None,
            Duration::from_secs(1),
        );
        let e = source.frame().expect_err("adjusted");
        assert!(matches!(&e, CameraError::FormatChanged { got, .. } if got == "MJPEG 640×480"), "{e}");
        let mut source = V4l2Source::new(
            Fake {
                offers: vec![offer(*b"GREY", 2, 2)],
                adjust: None,
                stride_pad: 0,
                captures: VecDeque::from([Err(io::Error::other("device unplugged")), Ok(Some(vec![1, 2, 3]))]),
                set_calls: 0,
            },
            None,
            None,
            Duration::from_secs(1),
        );
        assert!(source.frame().expect_err("unplugged").to_string().contains("device unplugged"));
        let e = source.frame().expect_err("short");
        assert_eq!(e, CameraError::ShortFrame { device: "/dev/video7".into(), got: 3, want: 4 });
        assert_eq!(source.device.set_calls, 2, "renegotiated after the failure");
    }

    #[cfg(not(feature = "v4l2"))]
    #[test]
    fn opening_says_what_to_do_instead() {
        let Err(e) = open(std::path::Path::new("/dev/video-none")) else { panic!("opened a missing device") };
        assert_eq!(e, CameraError::NoDevice { device: "/dev/video-none".into() });
        assert!(e.to_string().starts_with("the video device /dev/video-none does not exist — check"), "{e}");
        // An existing path: no backend in this build, and what to do instead.
        let Err(e) = open(std::path::Path::new("/dev/null")) else { panic!("opened /dev/null") };
        assert!(e.to_string().starts_with("cannot open the video device /dev/null (this build"), "{e}");
    }
}
