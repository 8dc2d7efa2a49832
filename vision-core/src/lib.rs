//! The Vision module of a CNC control: parameters, alignment runs (M280–M282), calibration
//! (M283), job switching (M284), pound variables, and the traits a host implements:
//! [`CameraDriver`] for the camera and [`Machine`] for the CNC.
//!
//! * [`driver`]: the camera trait; drivers return native pixels, all math lives here.
//! * [`command`]: what the module asks the machine to do ([`MachineCommand`]), typed.
//! * [`machine`]: the one machine trait every front end implements (positions, commands, tools,
//!   units, pound variables, clock), with typed [`MachineError`]s.
//! * [`controller`]: every rule that differs between Mach4, LinuxCNC and seed 002's
//!   MachineMotion, one file each ([`Controller`], [`CONTROLLERS`]).
//! * [`params`]: the OEM parameters under the manual's names, in three parts ([`Config`],
//!   [`Calibration`], [`Telemetry`]); [`profile`]: the TOML file of the first two ([`Params`]).
//! * [`module`]: [`VisionModule`] with the typed entry points `m280` … `m284`.
//! * [`pound`]: the pound-variable block.
//! * [`calibrate`]: M283's modes and reports (the routine is in `module/m283/`); [`sheets`]:
//!   `CAL_SHEETS`.
//! * [`registry`]: the camera drivers by name, with their settings tables.
//! * [`text`]: messages and reports made safe to show a person (control characters, huge input).
//!
//! The crate depends on `vision-math` only (plus `thiserror`, `serde`, `toml`); it knows no
//! driver, no G-code interpreter and no CLI.
//!
//! # How a host uses it
//!
//! `vision-host`'s session parses `M280 P3`, `M281 D1`, … (through `vision-mcode`) into typed
//! values ([`RunMode`], [`Pieces`], [`Calibrate`], a job number, a keep-image flag) and calls
//! [`VisionModule::m280`] … [`VisionModule::m284`] with the controller's [`Machine`]. The module
//! hands the machine typed [`MachineCommand`]s ([`Machine::command`]: M280's cancel, M282's
//! alignment, M283's moves), as the machine's [`Controller`] chooses them; the bridge runs them
//! in its controller's G-code text (written by `vision-mcode`), and [`Reply::gcode`] lists the
//! lines it ran. The run's state is typed ([`Run`]); the `Last*` / `Run_*` telemetry is
//! written from it after each operation and never read back. Drivers come from a
//! [`DriverRegistry`] by `VisionDriver`; parameters load and save with a [`ProfileStore`].
//!
//! The decisions where the spec is open are in `docs/vision-module.md`.
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
//! // A DRO reads every parameter by name, telemetry included.
//! assert_eq!(module.param("VisionRun_Active")?, vision_core::ParamValue::Int(0));
//! # Ok::<(), VisionError>(())
//! ```

/// The integrators' guide (`docs/integrators.md`): its minimal `Machine` + `CameraDriver` host
/// runs as a doc-test, so the guide cannot drift from the traits.
#[cfg(doctest)]
#[doc = include_str!("../../docs/integrators.md")]
pub struct IntegratorsGuide;

/// M283's modes and reports (the routine is in `module/m283/`), at the path they had.
pub mod calibrate {
    pub use crate::module::m283::{
        detect_remap, AxisReport, CalReport, Calibrate, CentreReport, DotVerify, KChange, LensReport, QuickReport,
        SheetReport, WalkTarget, BUMP_IN, LENS_GRID_REACH, LIFT_GRID, MAX_SHEET_SCALE_DEV, MIN_BUMP_PX,
        PROBE_FOV_FRACTION, QUICK_SCALE_TOLERANCE,
    };
}
pub mod command;
pub mod controller;
pub mod driver;
mod error;
pub mod kind_error;
pub mod machine;
pub mod module;
pub mod params;
pub mod pound;
pub mod profile;
pub mod registry;
mod ser;
pub mod sheets;
pub mod text;

pub use calibrate::{
    AxisReport, CalReport, Calibrate, CentreReport, DotVerify, KChange, LensReport, QuickReport, SheetReport,
    WalkTarget,
};
pub use command::MachineCommand;
pub use controller::{Controller, CONTROLLERS};
pub use driver::{CameraDriver, Capabilities, DriverError, DriverErrorKind, ImageRequest, Judgment, Reading};
pub use error::VisionError;
pub use kind_error::{Kind, KindError};
pub use machine::{Machine, MachineError, MachineErrorKind, Timestamp};
pub use module::{
    AlignReport, Capture, CaptureStep, Dot, DroppedMark, JobReport, Pieces, PredictedError, ProgressSink, Recentred,
    Reply, Run, RunMode, StepwiseCapture, StepwiseWalk, TelemetrySink, VisionModule, WalkProgress,
};
pub use params::{
    Access, Calibration, Config, DriverSettings, ParamKind, ParamSpec, ParamValue, Params, Section, Setting,
    SettingsTable, Telemetry,
};
pub use pound::{PoundBlock, PoundReport, SlotValues};
pub use profile::{ProfileFs, ProfileStore, StdFs};
pub use registry::{DriverFactory, DriverRegistry};
pub use sheets::{cal_sheet, CalSheet, CAL_SHEETS};
