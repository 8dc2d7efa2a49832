//! The Vision module: the typed entry points behind M280–M284.
//!
//! The M-code adapter parses the words and calls [`VisionModule::m280`] … [`VisionModule::m284`]
//! with typed values; each returns a [`Reply`] with a typed report and the G-code lines the
//! module ran. A refused call returns a [`VisionError`] and changes nothing it promises to keep
//! (see each entry point).
//!
//! Decision: every entry point delivers its G-code the same way — it runs its commands itself
//! through [`Machine::command`], in order, while it works (M280's cancel, M282's alignment,
//! M283's moves), and [`Reply::gcode`] lists the lines the machine ran for them. A host never
//! runs a reply's lines again. Running them inside the call is what M283 needs anyway (it
//! moves, then triggers), and it lets M280/M282 commit their state only after the machine took
//! the lines.
//!
//! Common checks, in order, for every entry point: `VisionEnabled` ("Vision is not enabled");
//! for M280–M283 the camera-tool check (`VisionCameraToolNumber` ≠ 0 and another tool active);
//! for M280–M282 the calibration's record (the camera's resolution, driver and tool offset
//! M283 calibrated with, see `record.rs`).

pub(crate) mod capture;
pub(crate) mod dro;
mod height;
mod m280;
mod m281;
mod m282;
pub(crate) mod m283;
mod m284;
mod record;

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests;

use std::path::{Path, PathBuf};

use vision_math::{AlignmentChain, LengthUnit, Point2, ScaleEvidence, Vector2};

use crate::driver::CameraDriver;
use crate::error::VisionError;
use crate::machine::Machine;
use crate::params::{ParamValue, Params, Telemetry};
use crate::profile::ProfileStore;
use crate::registry::DriverRegistry;
use dro::Dro;

pub use capture::{Capture, Recentred};
pub use dro::{ProgressSink, TelemetrySink, WalkProgress};
pub use height::HeightReport;
pub use m280::RunMode;
pub use m281::{CaptureStep, StepwiseCapture};
pub use m282::{AlignReport, DroppedMark, Pieces, PredictedError};
pub use m283::StepwiseWalk;
pub use m284::{JobReport, MAX_JOB};

/// What an entry point hands back: the G-code it ran, then a report.
#[derive(Debug, Clone, PartialEq)]
pub struct Reply<R> {
    /// Lines the module ran on the machine through [`Machine::command`], in order (empty
    /// when none). Informational: the host must not run them again.
    pub gcode: Vec<String>,
    /// What happened.
    pub report: R,
}

/// One capture of the current run: where the camera was commanded and where the mark was seen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dot {
    /// Commanded camera position, program frame, in `unit`.
    pub commanded: Point2<f64>,
    /// Observed mark centre, program frame, in `unit`.
    pub observed: Point2<f64>,
    /// The machine unit at capture time.
    pub unit: LengthUnit,
    /// `observed` less the camera's position at the reading kept (program frame, `unit`): the
    /// length K measured, which a scale error of K at the part's height acts on.
    pub reach: Vector2<f64>,
    /// The mark's measured diameter, the mean of its width and height, `unit`.
    pub mark_size: f64,
    /// How `observed` moves per unit of each lens coefficient `[k1, k2, p1, p2]` at the pixel
    /// it was read at (`unit`; zero without a lens): what the lens's uncertainty costs it.
    pub lens_along: [Vector2<f64>; 4],
}

impl Dot {
    /// The dot converted to `to` (commanded, observed).
    #[must_use]
    pub fn in_unit(&self, to: LengthUnit) -> (Point2<f64>, Point2<f64>) {
        let f = self.unit.factor_to(to);
        (self.commanded * f, self.observed * f)
    }

    /// [`Dot::reach`] converted to `to`.
    #[must_use]
    pub fn reach_in(&self, to: LengthUnit) -> Vector2<f64> {
        self.reach * self.unit.factor_to(to)
    }

    /// [`Dot::lens_along`] converted to `to`.
    #[must_use]
    pub fn lens_along_in(&self, to: LengthUnit) -> [Vector2<f64>; 4] {
        let f = self.unit.factor_to(to);
        self.lens_along.map(|v| v * f)
    }
}

/// The alignment run (SPEC §3): the one place the run's mode, whether it is open, and its dot
/// list live. `VisionRun_Active`, `VisionRun_Mode` and `VisionRun_DotCount` are written from it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Run {
    /// The fit M280 chose (rectangle before the first M280).
    pub mode: RunMode,
    /// True between M280 and a successful M282 (captures join the dot list only then).
    pub active: bool,
    /// The run's captures, in order (all of them, not only the four in the slots); kept after
    /// M282 until the next M280, so a second M282 can emit another selection.
    pub dots: Vec<Dot>,
    /// The image scale at the part's height as the run's camera moves measured it (every M281
    /// since M280 that read its mark from more than one position).
    pub scale: ScaleEvidence,
}

/// The Vision module: the profile's parameters, the current run, the telemetry it writes, the
/// camera driver and the profile store it persists to.
pub struct VisionModule {
    pub(crate) params: Params,
    pub(crate) dro: Dro,
    pub(crate) driver: Option<Box<dyn CameraDriver>>,
    pub(crate) run: Run,
    pub(crate) profile: Option<ProfileStore>,
    pub(crate) images_dir: PathBuf,
    /// The alignment this module's last M282 applied (`None` after M280 or before any), as
    /// the controller reports it at the last call ([`crate::Controller::active_alignment`]).
    pub(crate) alignment: Option<AlignmentChain>,
}

impl std::fmt::Debug for VisionModule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VisionModule")
            .field("params", &self.params)
            .field("dro", &self.dro)
            .field("driver", &self.driver.as_ref().map(|d| d.name().to_string()))
            .field("run", &self.run)
            .field("profile", &self.profile)
            .field("images_dir", &self.images_dir)
            .field("alignment", &self.alignment)
            .finish()
    }
}

/// Default folder M281 D1 copies images into (relative to the working directory).
pub const DEFAULT_IMAGES_DIR: &str = "Images";

impl VisionModule {
    /// A module with `params`, no driver, no profile, images under [`DEFAULT_IMAGES_DIR`].
    #[must_use]
    pub fn new(params: Params) -> VisionModule {
        VisionModule {
            params,
            dro: Dro::default(),
            driver: None,
            run: Run::default(),
            profile: None,
            images_dir: PathBuf::from(DEFAULT_IMAGES_DIR),
            alignment: None,
        }
    }

    /// A module whose driver comes from `registry` by `VisionDriver`, when Vision is enabled
    /// (when disabled no driver is loaded, as the manual says).
    ///
    /// # Errors
    /// [`VisionError::UnknownDriver`], or the factory's [`VisionError::Driver`].
    pub fn from_registry(params: Params, registry: &DriverRegistry) -> Result<VisionModule, VisionError> {
        let driver = if params.enabled() { Some(registry.create(params.driver(), &params)?) } else { None };
        Ok(VisionModule { driver, ..VisionModule::new(params) })
    }

    /// Uses `driver` as the camera.
    #[must_use]
    pub fn with_driver(mut self, driver: Box<dyn CameraDriver>) -> VisionModule {
        self.driver = Some(driver);
        self
    }

    /// Replaces the camera driver (`None` unloads it).
    pub fn set_driver(&mut self, driver: Option<Box<dyn CameraDriver>>) {
        self.driver = driver;
    }

    /// The camera driver, if loaded.
    #[must_use]
    pub fn driver(&self) -> Option<&dyn CameraDriver> {
        self.driver.as_deref()
    }

    /// Persists calibration and configuration to `store` (M283 and M284 save on success). The
    /// module's parameters now are what a save compares with: it writes only what changed
    /// since ([`ProfileStore::save_changes`]).
    #[must_use]
    pub fn with_profile(mut self, mut store: ProfileStore) -> VisionModule {
        store.mark_synced(&self.params);
        self.profile = Some(store);
        self
    }

    /// The profile store, if any.
    #[must_use]
    pub fn profile(&self) -> Option<&ProfileStore> {
        self.profile.as_ref()
    }

    /// Sets the folder M281 D1 copies images into.
    pub fn set_images_dir(&mut self, dir: impl Into<PathBuf>) {
        self.images_dir = dir.into();
    }

    /// The folder M281 D1 copies images into.
    #[must_use]
    pub fn images_dir(&self) -> &Path {
        &self.images_dir
    }

    /// The profile's parameters: configuration and calibration (read-only view).
    #[must_use]
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// The telemetry written after the last operation (read-only view).
    #[must_use]
    pub fn telemetry(&self) -> &Telemetry {
        self.dro.values()
    }

    /// Hands the telemetry to `sink` each time the module writes it, during a call as well as
    /// at its end (see [`TelemetrySink`]); `None` removes the sink.
    pub fn set_telemetry_sink(&mut self, sink: Option<TelemetrySink>) {
        self.dro.set_sink(sink);
    }

    /// Hands M283's [`WalkProgress`] to `sink` as the walk reaches each dot (see
    /// [`ProgressSink`]); `None` removes the sink.
    pub fn set_progress_sink(&mut self, sink: Option<ProgressSink>) {
        self.dro.set_progress_sink(sink);
    }

    /// Reads any parameter by its manual name (case-insensitive): configuration, calibration or
    /// telemetry, as a host DRO shows them.
    ///
    /// # Errors
    /// [`VisionError::UnknownParam`].
    pub fn param(&self, name: &str) -> Result<ParamValue, VisionError> {
        self.params.get(name).or_else(|e| self.dro.values().get(name).ok_or(e))
    }

    /// The alignment active on the machine as of the last call: the one this module's last
    /// M282 applied (`None` after M280 or before any), or what the controller reported
    /// ([`crate::Controller::active_alignment`]). Program frame → work frame, current units.
    #[must_use]
    pub fn alignment(&self) -> Option<&AlignmentChain> {
        self.alignment.as_ref()
    }

    /// Brings [`VisionModule::alignment`] up to date with what `machine`'s controller reports,
    /// and returns it.
    pub(crate) fn refresh_alignment(&mut self, machine: &dyn Machine) -> Result<Option<AlignmentChain>, VisionError> {
        self.alignment = machine.controller().active_alignment(machine, self.alignment)?;
        Ok(self.alignment)
    }

    /// The alignment run: mode, open or not, dot list.
    #[must_use]
    pub fn run(&self) -> &Run {
        &self.run
    }

    /// Writes configuration parameter `name` (validated; telemetry refused). Call
    /// [`VisionModule::save_profile`] to persist it.
    ///
    /// # Errors
    /// As [`Params::set`].
    pub fn set_param(&mut self, name: &str, value: impl Into<ParamValue>) -> Result<(), VisionError> {
        self.params.set(name, value)
    }

    /// The current run's captures, in order (all of them, not only the four in the slots).
    #[must_use]
    pub fn dots(&self) -> &[Dot] {
        &self.run.dots
    }

    /// Saves what this module changed to the attached profile (atomically, merged with what
    /// other processes saved meanwhile, which the module takes in memory); no-op without a
    /// profile.
    ///
    /// # Errors
    /// [`VisionError::Profile`]; the previous file is intact and the parameters unchanged.
    pub fn save_profile(&mut self) -> Result<(), VisionError> {
        self.commit_params(self.params.clone())
    }

    /// Makes `next` the module's parameters: saved to the attached profile first (atomically,
    /// with what other processes saved meanwhile: [`ProfileStore::save_changes`]), then taken in
    /// memory, so the file and the module never disagree. On a failed save nothing changes.
    pub(crate) fn commit_params(&mut self, next: Params) -> Result<(), VisionError> {
        self.params = match self.profile.as_mut() {
            Some(store) => store.save_changes(&next)?,
            None => next,
        };
        Ok(())
    }

    /// Writes the run's telemetry (`Run_Active`, `Run_Mode`, `Run_DotCount`) from [`Run`].
    pub(crate) fn publish_run(&mut self) {
        let run = &self.run;
        self.dro.write(|t| {
            t.run_active = i64::from(run.active);
            t.run_mode = run.mode.code();
            t.run_dot_count = i64::try_from(run.dots.len()).unwrap_or(i64::MAX);
        });
    }

    /// Records a failed operation (see [`Dro::failure`]).
    pub(crate) fn publish_failure(&mut self, judgment: Option<i64>, e: &VisionError) {
        self.dro.failure(judgment, e);
    }

    /// Refuses when Vision is disabled.
    pub(crate) fn check_enabled(&self) -> Result<(), VisionError> {
        if self.params.enabled() {
            Ok(())
        } else {
            Err(VisionError::NotEnabled)
        }
    }

    /// Refuses when the camera tool is set and another tool is active.
    pub(crate) fn check_tool(&self, machine: &dyn Machine) -> Result<(), VisionError> {
        let Some(camera) = self.params.camera_tool() else { return Ok(()) };
        match machine.active_tool()? {
            active if active != camera => Err(VisionError::WrongTool { camera, active }),
            _ => Ok(()),
        }
    }

    /// Refuses when the machine tells which X/Y tool offset it applies and that is not the
    /// camera tool's table entry (a LinuxCNC program without `G43`): a capture would measure
    /// from where the camera is not.
    pub(crate) fn check_camera_offset(&self, machine: &dyn Machine) -> Result<(), VisionError> {
        let Some(camera) = self.params.camera_tool() else { return Ok(()) };
        let Some(applied) = machine.applied_tool_offset()? else { return Ok(()) };
        let table = machine.tool_offset(camera)?;
        // Both come from the same table entry when the offset is applied: a difference beyond
        // rounding is another offset.
        let tolerance = 1e-6 * table.norm().max(1.0);
        if (table - applied).norm() <= tolerance {
            return Ok(());
        }
        Err(VisionError::ToolOffsetNotApplied { camera, table: [table.x, table.y], applied: [applied.x, applied.y] })
    }

    /// The loaded driver, or [`VisionError::NoDriver`].
    pub(crate) fn driver_mut(&mut self) -> Result<&mut (dyn CameraDriver + 'static), VisionError> {
        let name = self.params.driver().to_string();
        self.driver.as_deref_mut().ok_or(VisionError::NoDriver { name })
    }
}
