//! The Vision module of a CNC control: parameters, alignment runs (M280–M282), calibration
//! (M283), job switching (M284), pound variables, and the traits a host implements:
//! [`CameraDriver`] for the camera and [`Machine`] for the CNC.
//!
//! * [`driver`]: the camera trait; drivers return native pixels, all math lives here.
//! * [`machine`]: the host trait (positions, G-code, tools, units, pound variables, clock).
//! * [`params`]: the OEM parameters under the manual's names, in three parts ([`Config`],
//!   [`Calibration`], [`Telemetry`]); [`profile`]: the TOML file of the first two ([`Params`]).
//! * [`module`]: [`VisionModule`] with the typed entry points `m280` … `m284`.
//! * [`pound`]: the pound-variable block.
//! * [`calibrate`]: M283's axis detect, quick calibration and sheet walk; [`sheets`]: `CAL_SHEETS`.
//! * [`registry`]: the camera drivers by name, with their settings tables.
//! * [`linuxcnc`]: where a LinuxCNC host keeps the alignment's state (persistent parameters).
//! * [`text`]: messages and reports made safe to show a person (control characters, huge input).
//!
//! The crate depends on `vision-math` only (plus `thiserror`, `serde`, `toml`); it knows no
//! driver, no G-code interpreter and no CLI.
//!
//! # How a host uses it
//!
//! The M-code adapter (`vision-mcode`) parses `M280 P3`, `M281 D1`, … into typed values
//! ([`RunMode`], [`Pieces`], [`Calibrate`], a job number, a keep-image flag), calls
//! [`VisionModule::m280`] … [`VisionModule::m284`] with the host's [`Machine`] and shows the
//! report. The module runs its own G-code through [`Machine::run_gcode`] (M280's cancel line,
//! M282's four modal lines, M283's moves); [`Reply::gcode`] lists what it ran. The run's state is typed ([`Run`]); the `Last*` / `Run_*` telemetry is written
//! from it after each operation and never read back. The CLI picks the driver by `VisionDriver` through a [`DriverRegistry`] and
//! loads/saves parameters with a [`ProfileStore`].
//!
//! # Decisions where the spec is open
//!
//! * Failed triggers (driver error, NG / no mark) update `LastJudgment` and `LastStatus` only;
//!   refusals before the trigger (disabled, wrong tool, reserved base, zero K) change nothing.
//! * Mark width/height use the column of `K·R` for the camera's native axis (identical to the
//!   manual's `width_px × ‖K column 1‖` unless `SwapXY`); `M283 Q` likewise divides by the size
//!   along the remapped axes.
//! * M282 `P1`/`P2`/`P3` emit the least-squares optimum of a shift-only / rotation-only (about
//!   the commanded centroid) / scale-only (about the centroid) transform, always as the same four
//!   lines with the other pieces at identity ([`Pieces`]). Quality gates judge the run's full fit;
//!   the shift gate measures the centroid displacement.
//! * M282 needs the run mode's 4 (rectangle) or 3 (similarity) captures; more are fitted by least
//!   squares, slots keep the first four; the dot list stays until the next M280.
//! * Pound fields 6–7 are never written. `Run_*` hold the **emitted** chain.
//! * M284's job above 999 is refused as an invalid `VisionActiveJob` before the camera is
//!   contacted; word syntax (`P1.5`) is the adapter's to refuse.
//! * M283 refuses while an alignment is active and leaves the machine in G90. The walk commits
//!   nothing; M283 then writes the offset to `VisionCameraToolNumber` (or the active tool when
//!   that is 0), saves the profile, and takes the new calibration — all or nothing, the tool
//!   table first (see [`VisionModule::m283`]). See [`calibrate`] for the solve.
//! * M284 with job 0 (stored or given) does not contact the camera; the tool check does not
//!   apply to M284. M281 D1 asks the driver to keep the image ([`CameraDriver::grab_image`]).
//! * The `VisionFitMax*` gates are in percent and inches (converted under G21).
//! * On a LinuxCNC host ([`Controller::LinuxCnc`]) M280/M282 write `G52` and `G10 L2 P0 R`
//!   (no G68/G51; a scale beyond `VisionFitMaxScaleDev` is refused, a smaller one left out and
//!   reported), θ₀ and the alignment flag live in persistent parameters ([`linuxcnc`]), camera
//!   vectors along the machine axes are turned by −θ₀ into the program frame, M281 does not
//!   re-centre, and M283 can run stepwise ([`VisionModule::m283_begin`]).
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

pub mod calibrate;
pub mod driver;
mod error;
pub mod linuxcnc;
pub mod machine;
pub mod module;
pub mod params;
pub mod pound;
pub mod profile;
pub mod registry;
mod ser;
pub mod sheets;
pub mod text;

pub use calibrate::{AxisReport, CalReport, Calibrate, DotVerify, QuickReport, SheetReport};
pub use driver::{CameraDriver, Capabilities, DriverError, DriverErrorKind, ImageRequest, Judgment, Reading};
pub use error::VisionError;
pub use machine::{Controller, Machine, MachineError, Timestamp};
pub use module::{
    AlignReport, Capture, Dot, DroppedMark, JobReport, Pieces, PredictedError, Recentred, Reply, Run, RunMode,
    StepwiseWalk, TelemetrySink, VisionModule,
};
pub use params::{
    Access, Calibration, Config, DriverSettings, ParamKind, ParamSpec, ParamValue, Params, Section, Setting,
    SettingsTable, Telemetry,
};
pub use pound::{PoundBlock, PoundReport, SlotValues};
pub use profile::{ProfileFs, ProfileStore, StdFs};
pub use registry::{DriverFactory, DriverRegistry};
pub use sheets::{cal_sheet, CalSheet, CAL_SHEETS};
