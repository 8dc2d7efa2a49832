//! Any camera: a USB (V4L2), network (HTTP snapshot) or file camera, whose frames mach-vision
//! searches for the fiducial itself with `vision-locate`.
//!
//! * [`CameraDriver`](vision_core::CameraDriver) implementation: [`FrameDriver`] takes a
//!   frame (flushing the ones a live camera may have queued before the last move), finds the
//!   mark, and returns its centre in **native pixels exactly as the Keyence driver does**
//!   (origin at the top-left corner of the top-left pixel, +x right, +y down; the image centre
//!   is `(width/2, height/2)`), so the pixel chain, K, calibration and every M-code are
//!   unchanged. [`register`] adds it to a [`vision_core::DriverRegistry`] as `Camera`.
//! * [`settings`]: the driver's own `[camera]` profile table; [`CameraConfig`] reads it typed.
//! * Frame sources behind [`FrameSource`]: [`v4l2`] devices (negotiation and decoding over a
//!   small [`v4l2::Device`] interface; the kernel edge, 64-bit Linux ioctls on memory-mapped
//!   buffers, behind the `v4l2` cargo feature and not verified on a camera),
//!   [`HttpSource`] snapshot URLs (a minimal HTTP/1.1 client, [`http`]), and [`FileSource`]
//!   files or folders (replay).
//! * [`CameraError`]: specific errors, mapped to [`vision_core::DriverErrorKind`].
//!
//! ```
//! use vision_driver_camera::{CameraConfig, FileSource, FrameDriver, Source};
//! use vision_core::CameraDriver;
//!
//! // A 64×48 white frame with a dark 16 px dot centred at native pixel (30.0, 20.0).
//! let dir = std::env::temp_dir().join(format!("camera-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir)?;
//! let frame = image::GrayImage::from_fn(64, 48, |x, y| {
//!     let (dx, dy) = (f64::from(x) + 0.5 - 30.0, f64::from(y) + 0.5 - 20.0);
//!     image::Luma([if dx.hypot(dy) < 8.0 { 20 } else { 230 }])
//! });
//! frame.save(dir.join("frame.png"))?;
//! let config = CameraConfig::new(Source::Files(dir.join("frame.png")), 16.0);
//! let mut camera = FrameDriver::new(config.clone(), FileSource::new(dir.join("frame.png")))?;
//! let reading = camera.trigger()?;
//! assert!(reading.found());
//! assert!((reading.x_px - 30.0).abs() < 0.3 && (reading.y_px - 20.0).abs() < 0.3);
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod config;
pub mod decode;
mod driver;
mod error;
pub mod file;
mod frame;
pub mod http;
#[cfg(feature = "server")]
pub mod server;
pub mod settings;
mod source;
pub mod v4l2;
#[cfg(all(feature = "v4l2", target_os = "linux", target_pointer_width = "64"))]
mod v4l2_linux;
mod window;

pub use config::{CameraConfig, MarkKind, MarkSettings, PixelFormat, Polarity, Source};
pub use driver::{register, FrameDriver, Miss, DRIVER_NAME};
pub use error::CameraError;
pub use frame::{decode_image, decode_raw, Frame, MAX_PIXELS};
pub use source::{FileSource, FrameSource, HttpSource};
