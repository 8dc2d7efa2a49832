//! The Vision module of a CNC control: parameters, alignment runs (M280–M282), calibration
//! (M283), job switching (M284), pound variables, and the traits a host implements:
//! [`CameraDriver`] for the camera and [`Machine`] for the CNC.
//!
//! * [`driver`]: the camera trait; drivers return native pixels, all math lives here.
//! * [`machine`]: the host trait (positions, G-code, tools, units, pound variables, clock).
//! * [`params`]: the OEM parameters under the manual's names; [`profile`]: their TOML file.
//! * [`module`]: [`VisionModule`] with the typed entry points `m280` … `m284`.
//! * [`pound`]: the pound-variable block; [`image_grab`]: M281 D1.
//! * [`calibrate`]: M283's axis detect, quick calibration and sheet walk; [`sheets`]: `CAL_SHEETS`.
//! * [`registry`]: drivers by name for the CLI.
//!
//! The crate depends on `vision-math` only (plus `thiserror`, `serde`, `toml`); it knows no
//! driver, no G-code interpreter and no CLI.
//!
//! ```
//! use vision_core::{Params, VisionError, VisionModule};
//!
//! let mut params = Params::default();
//! assert!(!params.enabled());
//! params.set("VisionEnabled", "Yes")?;
//! params.set("VisionCal_K11", 0.00203)?;
//! params.set("VisionCal_K22", 0.00203)?;
//! // Telemetry is read-only from outside.
//! assert!(matches!(params.set("VisionLastStatus", "OK"), Err(VisionError::ReadOnlyParam { .. })));
//! let module = VisionModule::new(params);
//! assert!(module.dots().is_empty());
//! # Ok::<(), VisionError>(())
//! ```

pub mod calibrate;
pub mod driver;
mod error;
pub mod image_grab;
pub mod machine;
pub mod module;
pub mod params;
pub mod pound;
pub mod profile;
pub mod registry;
pub mod sheets;

pub use calibrate::{AxisReport, CalReport, Calibrate, DotVerify, QuickReport, SheetReport};
pub use driver::{CameraDriver, Capabilities, DriverError, DriverErrorKind, Judgment, Reading};
pub use error::VisionError;
pub use machine::{Machine, MachineError, Timestamp};
pub use module::{AlignReport, Capture, Dot, JobReport, Pieces, Reply, RunMode, VisionModule};
pub use params::{Access, ParamKind, ParamSpec, ParamValue, Params, Section};
pub use pound::{PoundBlock, SlotValues};
pub use profile::{ProfileFs, ProfileStore, StdFs};
pub use registry::{DriverFactory, DriverRegistry};
pub use sheets::{cal_sheet, CalSheet, CAL_SHEETS};
