//! The Keyence VS-series smart camera, driven over its Non-Procedural command port (TCP 8500),
//! and an emulator that behaves like one (SPEC §7).
//!
//! * [`KeyenceDriver`]: the [`vision_core::CameraDriver`] (`TRG`, `FVR`, `PR`, job switch with
//!   `PL`, falling back to `PW`), one persistent connection, typed errors; [`register`] adds
//!   it to a [`vision_core::DriverRegistry`] as `Keyence`.
//! * [`settings`]: the driver's own settings, `[keyence]` in the profile under the manual's
//!   names (`VisionIP`, `VisionPort`, `VisionTimeout`, `VisionImageWatchDir`,
//!   `VisionImageGrabTimeout`); [`register`] hands them to the registry.
//! * [`KeyenceConfig`]: address, timeout, bounds and the image folder, from those settings.
//! * `images`: M281 D1, the image the camera FTP-pushed for a trigger
//!   ([`vision_core::CameraDriver::grab_image`]).
//! * [`Exchange`]: the pure part — framing, reply parsing and the command/reply state machine
//!   over any `Read + Write` (a transport of your own, e.g. a serial link); the socket is a thin
//!   edge around it. [`parse_data_line`] reads one Data Output line.
//! * `emulator` (cargo feature `emulator`): a TCP server that answers like a VS camera, with
//!   pluggable results and fault injection.
//!
//! ```
//! use vision_core::DriverRegistry;
//! use vision_driver_keyence::emulator::Emulator;
//!
//! let camera = Emulator::builder().bind("127.0.0.1:0")?; // a mark at the image centre
//! let mut registry = DriverRegistry::new();
//! vision_driver_keyence::register(&mut registry);
//! let mut params = registry.params(); // knows the driver's settings by name
//! params.set("VisionIP", "127.0.0.1")?;
//! params.set("VisionPort", i64::from(camera.addr().port()))?;
//! let mut driver = registry.create("Keyence", &params)?;
//! let reading = driver.trigger()?;
//! assert_eq!((reading.x_px, reading.y_px), (888.0, 888.0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! What the camera may answer, the timeouts, the error table ([`KeyenceError`] →
//! [`vision_core::DriverErrorKind`]), why a command is never sent twice, and the protocol facts
//! (confirmed and assumed) are in `docs/keyence-driver.md`.

mod config;
mod driver;
#[cfg(feature = "emulator")]
pub mod emulator;
mod error;
mod images;
mod protocol;
pub mod settings;
mod transport;

pub use config::{ImageWatch, KeyenceConfig, DEFAULT_PORT, DEFAULT_TIMEOUT, MAX_TIMEOUT};
pub use driver::{register, KeyenceDriver, DRIVER_NAME};
pub use error::{er_meaning, KeyenceError, FIRST_BYTES_SHOWN};
pub use protocol::{parse_data_line, Exchange, JobCommand, Limits, Program};
