//! M283: calibrate K (and, for `Cn`, the camera tool offset): the axis-detect bump, quick
//! calibration (`Qd`) and the sheet walk (`Cn`). How the sheet walk solves K, the sheet pose,
//! the camera offset and the optical centre: `docs/calibration-solve.md`.
//!
//! Nothing in the routines commits: `quick` and `sheet_walk` return a `Solution` (K, remap,
//! tool offset, report) and [`VisionModule::m283`] applies it in one place, or nothing.

mod axis;
mod lens;
mod lift;
mod quick;
mod report;
mod sheet;
mod walk;

use vision_math::chain::fixed;
use vision_math::{AlignmentChain, LengthUnit, Point2, Vector2};

pub use axis::{detect_remap, BUMP_IN, MIN_BUMP_PX};
pub use lens::LENS_GRID_REACH;
pub use lift::LIFT_GRID;
pub use quick::QUICK_SCALE_TOLERANCE;
pub use report::{AxisReport, CalReport, CentreReport, DotVerify, KChange, LensReport, QuickReport, SheetReport};
pub use sheet::{MAX_SHEET_SCALE_DEV, PROBE_FOV_FRACTION};
pub use walk::WalkTarget;
pub(crate) use walk::{absolute_move, relative_move};

use super::capture::pixel_chain;
use super::{Reply, VisionModule};
use crate::controller;
use crate::driver::Reading;
use crate::error::VisionError;
use crate::machine::{checked, Machine, MachineError};
use crate::params::Params;
use crate::sheets::{cal_sheet, known_sheets};
use quick::quick;
use report::{LensUpdate, Solution};
use sheet::sheet_walk;
use walk::Walker;

/// Which calibration M283 runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Calibrate {
    /// `Qd`: K = diag(d/width_px, d/height_px) from one trigger over a dot of diameter `d`
    /// (current units).
    Quick {
        /// The printed dot's diameter, current units.
        diameter: f64,
    },
    /// `Cn`: walk calibration sheet `n` of [`crate::sheets::CAL_SHEETS`].
    Sheet {
        /// The sheet number.
        n: u32,
    },
}

/// A calibration failure with `reason`.
fn fail(reason: impl Into<String>) -> VisionError {
    VisionError::Calibration { reason: reason.into() }
}

/// True when `chain` moves no point (within 1e-12).
fn is_identity(chain: &AlignmentChain) -> bool {
    let eps = 1e-12;
    (chain.scale - Vector2::new(1.0, 1.0)).norm() < eps && chain.rotation_deg.abs() < eps && chain.shift.norm() < eps
}

/// M283's walk on `walker`: the quick calibration or the sheet walk (`tool`: whose offset
/// the sheet walk solves). Writes nothing.
fn walk_routine(walker: &mut Walker<'_>, params: &Params, mode: Calibrate, tool: u32) -> Result<Solution, VisionError> {
    match mode {
        Calibrate::Quick { diameter } => quick(walker, params, diameter),
        Calibrate::Sheet { n } => sheet_walk(walker, params, n, tool),
    }
}

/// A stepwise M283 walk in progress ([`VisionModule::m283_begin`]): the mode, where it started,
/// and the readings captured so far with the program positions they were taken at.
#[derive(Debug, Clone, PartialEq)]
pub struct StepwiseWalk {
    mode: Calibrate,
    tool: u32,
    start: Point2<f64>,
    taken: Vec<(Point2<f64>, Reading)>,
    /// The target [`VisionModule::m283_next`] last gave, until it is captured.
    pending: Option<WalkTarget>,
}

impl StepwiseWalk {
    /// The calibration being walked.
    #[must_use]
    pub fn mode(&self) -> Calibrate {
        self.mode
    }

    /// Captures taken so far.
    #[must_use]
    pub fn captures(&self) -> usize {
        self.taken.len()
    }
}

/// What a replay of a stepwise walk came to.
enum Replayed {
    /// It needs a capture at this target.
    Needs(WalkTarget),
    /// It has every reading: the solution to commit, and the last reading.
    Done { solution: Box<Solution>, last: Option<Reading> },
    /// It failed on the readings so far.
    Failed { error: VisionError, last: Option<Reading> },
}

impl VisionModule {
    /// **M283**: calibrates. Both modes start with the axis-detect bump (+0.1″ X, trigger,
    /// +0.1″ Y, trigger, back; 2.54 mm under G21) that finds `VisionCameraSwapXY` /
    /// `InvertX` / `InvertY`.
    ///
    /// * [`Calibrate::Quick`]: K = diag(d/width_px, d/height_px) (width and height along the
    ///   remapped axes), then re-triggers to confirm; no tool offset is written.
    /// * [`Calibrate::Sheet`]: walks the sheet, solves the full K, measures the optical centre
    ///   by the calibration lift (`VisionCalibrationLift`; Z comes back before the verify),
    ///   solves the sheet pose and the camera tool's X/Y offset at it by least squares, re-walks
    ///   every dot in G90 and reports. The offset goes to `VisionCameraToolNumber`, or to the
    ///   active tool when that is 0.
    ///
    /// The walk writes nothing; its solution (the new [`crate::Calibration`], the camera tool's
    /// offset) is applied here, in one place, or not at all; every trigger updates the `Last*`
    /// telemetry as it happens and the reply lists every line run through
    /// [`Machine::command`]. The commit order and the telemetry: `docs/calibration-solve.md`.
    ///
    /// # Errors
    /// [`VisionError::NotEnabled`], [`VisionError::WrongTool`], [`VisionError::UnknownSheet`],
    /// [`VisionError::AlignmentActive`] (calibration moves must not be scaled or rotated),
    /// [`VisionError::NoDriver`], an unwritable profile — nothing changes but `LastStatus`; then [`VisionError::Calibration`],
    /// [`VisionError::Driver`], [`VisionError::Machine`] or [`VisionError::Profile`] during the
    /// routine: K, the remap flags, `Cal_*` and the tool offset keep their values, the machine is
    /// sent back to its start position (best effort) and `LastStatus` holds the error.
    pub fn m283(&mut self, machine: &mut dyn Machine, mode: Calibrate) -> Result<Reply<CalReport>, VisionError> {
        let tool = self.check_m283(machine, mode)?;
        let (start, unit) = self.before_walk(machine)?;
        // The walk's moves must leave the program's modal state as it was (G90/G91, G0/G1, …).
        if let Err(e) = machine.save_modal_state() {
            let e = VisionError::from(e);
            self.publish_failure(None, &e);
            return Err(e);
        }
        let (outcome, ran) = {
            let Some(driver) = self.driver.as_deref_mut() else {
                let _ = machine.restore_modal_state();
                return Err(VisionError::NoDriver { name: self.params.driver().to_string() });
            };
            let mut walker = Walker::new(machine, driver, &self.params, &mut self.dro, unit);
            let outcome = walk_routine(&mut walker, &self.params, mode, tool);
            (outcome, walker.into_ran())
        };
        let (ran, last) = ran;
        self.commit_walk(machine, outcome, ran, last, start, true)
    }

    /// M283's checks before the walk moves or triggers anything (see [`VisionModule::m283`]'s
    /// errors); returns the tool whose offset a sheet walk writes. A refusal is shown in
    /// `LastStatus` (the DRO says why nothing was triggered).
    fn check_m283(&mut self, machine: &dyn Machine, mode: Calibrate) -> Result<u32, VisionError> {
        self.m283_checks(machine, mode).inspect_err(|e| self.publish_failure(None, e))
    }

    fn m283_checks(&mut self, machine: &dyn Machine, mode: Calibrate) -> Result<u32, VisionError> {
        self.check_enabled()?;
        self.check_tool(machine)?;
        if let Calibrate::Sheet { n } = mode {
            if cal_sheet(n).is_none() {
                return Err(VisionError::UnknownSheet { sheet: n, known: known_sheets() });
            }
        }
        if self.refresh_alignment(machine)?.is_some_and(|a| !is_identity(&a)) {
            return Err(VisionError::AlignmentActive);
        }
        self.driver_mut()?;
        // The new calibration is made at the size of the frames the camera delivers.
        self.adopt_frame_size()?;
        // A profile that cannot be saved is found before the walk moves the machine.
        if let Some(store) = &self.profile {
            store.check_writable()?;
        }
        match self.params.camera_tool() {
            Some(tool) => Ok(tool),
            None => Ok(machine.active_tool()?),
        }
    }

    /// Where the walk starts (program frame) and the machine's units, or the read's failure
    /// (shown in `LastStatus`; nothing moved).
    fn before_walk(&mut self, machine: &dyn Machine) -> Result<(Point2<f64>, LengthUnit), VisionError> {
        let read = || -> Result<_, VisionError> { Ok((checked::program_position(machine)?, machine.units()?)) };
        read().inspect_err(|e| self.publish_failure(None, e))
    }

    /// M283's one commit path, for the one-shot walk and the stepwise one: applies the walk's
    /// `outcome` (lines `ran`, last reading `last`) or, on any failure, sends the machine back to
    /// `start` (best effort) and records the failure. With `modal_saved` (the one-shot walk
    /// saved the modal state before moving) the program's modal state is restored last, on
    /// either path.
    fn commit_walk(
        &mut self,
        machine: &mut dyn Machine,
        outcome: Result<Solution, VisionError>,
        ran: Vec<String>,
        last: Option<Reading>,
        start: Point2<f64>,
        modal_saved: bool,
    ) -> Result<Reply<CalReport>, VisionError> {
        match outcome.and_then(|solution| self.apply_calibration(machine, solution)) {
            Ok(report) => {
                if modal_saved {
                    if let Err(e) = machine.restore_modal_state() {
                        let e = VisionError::Machine(MachineError::new(
                            e.kind(),
                            format!(
                                "the calibration was saved, but the program's modal state could not be restored \
                                 ({e}) — check G90/G91 and G0/G1 before the next move"
                            ),
                        ));
                        self.publish_failure(None, &e);
                        return Err(e);
                    }
                }
                // The last trigger again, as M281 would show it with the K just written.
                if let Some(reading) = last.filter(Reading::found) {
                    if let Ok(chain) =
                        machine.units().map_err(VisionError::from).and_then(|u| pixel_chain(&self.params, u))
                    {
                        let centred = chain.centred(Point2::new(reading.x_px, reading.y_px));
                        self.dro.reading(Some(&chain), centred, &reading);
                    }
                }
                self.dro.ok(report.warning());
                Ok(Reply { gcode: ran, report })
            }
            Err(e) => {
                let _ = machine.command(&absolute_move(start));
                if modal_saved {
                    // Best effort, as the move back: the error already says what failed.
                    let _ = machine.restore_modal_state();
                }
                // A failed trigger was shown (and its stale values cleared) as it happened.
                self.publish_failure(None, &e);
                Err(e)
            }
        }
    }

    /// **M283, stepwise** (a controller whose M-code cannot both move and trigger, LinuxCNC):
    /// M283's checks, with nothing moved; the walk then goes [`VisionModule::m283_next`] (where
    /// to go) → the host moves there → [`VisionModule::m283_capture`], until `m283_next` answers
    /// `None`, then [`VisionModule::m283_finish`] solves and commits.
    ///
    /// Decision: the walk is replayed. The routine of [`VisionModule::m283`] runs again at every
    /// step over the readings captured so far, moving nothing, and stops where it needs the next
    /// one; it is deterministic given its readings, so one routine serves both ways, and the
    /// stepwise walk solves and commits exactly as the one-shot one for the same readings (a
    /// sheet walk is ~30 captures, so the O(n²) replays cost nothing).
    ///
    /// # Errors
    /// As [`VisionModule::m283`] before its walk: nothing changes.
    pub fn m283_begin(&mut self, machine: &mut dyn Machine, mode: Calibrate) -> Result<StepwiseWalk, VisionError> {
        let tool = self.check_m283(machine, mode)?;
        let (start, _) = self.before_walk(machine)?;
        Ok(StepwiseWalk { mode, tool, start, taken: Vec::new(), pending: None })
    }

    /// The next target the stepwise walk must capture at (program frame X/Y and the height
    /// above the walk's start Z, current units), or `None` when it has every reading it needs.
    /// The host moves Z first, then X/Y: the lift rises and comes down over the last dot.
    ///
    /// # Errors
    /// The walk failed on the readings so far (as [`VisionModule::m283`] would: e.g. the axis
    /// detect saw no motion); `LastStatus` holds the error and nothing is written.
    pub fn m283_next(
        &mut self,
        machine: &mut dyn Machine,
        walk: &mut StepwiseWalk,
    ) -> Result<Option<WalkTarget>, VisionError> {
        walk.pending = match self.replay(machine, walk) {
            Replayed::Needs(at) => Some(at),
            Replayed::Done { .. } => None,
            Replayed::Failed { error, .. } => return Err(self.walk_failed(error)),
        };
        Ok(walk.pending)
    }

    /// Triggers where the machine is now (after `VisionTriggerSettleSec`), for the point
    /// [`VisionModule::m283_next`] gave, and records the reading.
    ///
    /// # Errors
    /// [`VisionError::WalkOrder`] when no capture is pending; the driver's error; the walk's
    /// failure on this reading (an NG: "the camera lost the mark …", as [`VisionModule::m283`]).
    /// `LastStatus` holds the error and nothing is written.
    pub fn m283_capture(&mut self, machine: &mut dyn Machine, walk: &mut StepwiseWalk) -> Result<(), VisionError> {
        if walk.pending.take().is_none() {
            return Err(VisionError::WalkOrder {
                what: "no capture is pending: ask for the next point (o<vision_walk_next>) and move there first",
            });
        }
        let settled = machine.dwell(self.params.trigger_settle_s()).map_err(VisionError::from);
        let reading = match settled.and_then(|()| Ok(self.driver_mut()?.trigger()?)) {
            Ok(r) => r,
            Err(e) => return Err(self.walk_failed(e)),
        };
        let at = match checked::program_position(machine) {
            Ok(at) => at,
            Err(e) => return Err(self.walk_failed(e.into())),
        };
        walk.taken.push((at, reading));
        match self.replay(machine, walk) {
            Replayed::Failed { error, .. } => Err(self.walk_failed(error)),
            _ => Ok(()),
        }
    }

    /// Solves the stepwise walk and commits it through the same path as
    /// [`VisionModule::m283`] (K, the camera tool's offset, the profile; all or nothing). The
    /// reply lists no G-code: the host ran the walk's moves. On a failure the machine is sent
    /// back to the walk's start (best effort), as after a failed [`VisionModule::m283`].
    ///
    /// # Errors
    /// [`VisionError::WalkOrder`] when the walk still needs captures; otherwise as
    /// [`VisionModule::m283`].
    pub fn m283_finish(
        &mut self,
        machine: &mut dyn Machine,
        walk: &StepwiseWalk,
    ) -> Result<Reply<CalReport>, VisionError> {
        match self.replay(machine, walk) {
            Replayed::Done { solution, last } => {
                self.commit_walk(machine, Ok(*solution), Vec::new(), last, walk.start, false)
            }
            Replayed::Needs(_) => Err(VisionError::WalkOrder {
                what: "the walk is not done: capture at every point o<vision_walk_next> gives before finishing",
            }),
            Replayed::Failed { error, last } => {
                self.commit_walk(machine, Err(error), Vec::new(), last, walk.start, false)
            }
        }
    }

    /// Replays `walk` over its readings, moving nothing.
    fn replay(&mut self, machine: &mut dyn Machine, walk: &StepwiseWalk) -> Replayed {
        let unit = match machine.units() {
            Ok(unit) => unit,
            Err(e) => return Replayed::Failed { error: e.into(), last: None },
        };
        let mut walker = Walker::replay(machine, &walk.taken, walk.start, &self.params, &mut self.dro, unit);
        let outcome = walk_routine(&mut walker, &self.params, walk.mode, walk.tool);
        let needed = walker.needed();
        let (_, last) = walker.into_ran();
        match (outcome, needed) {
            (_, Some(at)) => Replayed::Needs(at),
            (Ok(solution), None) => Replayed::Done { solution: Box::new(solution), last },
            (Err(error), None) => Replayed::Failed { error, last },
        }
    }

    /// Records a failed stepwise step as M283 records a failure (a failed trigger was shown as
    /// it happened); returns the error.
    fn walk_failed(&mut self, error: VisionError) -> VisionError {
        self.publish_failure(None, &error);
        error
    }

    /// Applies a calibration solution: all of it, or nothing (see [`VisionModule::m283`]).
    fn apply_calibration(&mut self, machine: &mut dyn Machine, solution: Solution) -> Result<CalReport, VisionError> {
        let mut calibration =
            self.params.calibration.solved(solution.k, solution.remap, machine.units()?, solution.report.date())?;
        if let Some((offset, sigma)) = solution.centre {
            calibration = calibration.with_centre(offset, sigma)?;
        }
        if let LensUpdate::Write(lens) = solution.lens {
            calibration = calibration.with_lens(lens)?;
        }
        let restore = match solution.tool_offset {
            Some((tool, offset)) => {
                let before = controller::tool_offset(machine, tool)?;
                controller::set_tool_offset(machine, tool, offset)?;
                Some((tool, before))
            }
            None => None,
        };
        // The record: what the tool table holds now (as the table rounds it), for the tool the
        // walk wrote, or the camera tool whose offset a quick calibration is used with.
        let recorded_tool = match restore {
            Some((tool, _)) => Some(tool),
            None => match self.params.camera_tool() {
                Some(tool) => Some(tool),
                None => Some(machine.active_tool()?).filter(|t| *t != 0),
            },
        };
        // `solved` made `Cal_Units` the machine's units, which the offset is read in.
        let record = self.with_record(machine, recorded_tool, &calibration);
        let committed =
            record.and_then(|calibration| self.commit_params(Params { calibration, ..self.params.clone() }));
        if let Err(save) = committed {
            let Some((tool, before)) = restore else { return Err(save) };
            if let Err(e) = controller::set_tool_offset(machine, tool, before) {
                return Err(VisionError::Machine(MachineError::new(
                    e.kind(),
                    format!(
                        "{save}; restoring tool {tool}'s offset then failed too ({e}) — set its X/Y offset back to \
                     X{} Y{} by hand",
                        fixed(before.x, 6),
                        fixed(before.y, 6)
                    ),
                )));
            }
            return Err(save);
        }
        // The run's evidence of the image scale measured the old K's error, not the new one's.
        self.run.scale = vision_math::ScaleEvidence::default();
        Ok(solution.report)
    }
}
