//! The walker: M283's moves, dwells and triggers, live on the machine or replayed over the
//! readings a stepwise walk captured.

use vision_math::chain::fixed;
use vision_math::{LengthUnit, Matrix2, Point2, Remap};

use super::fail;
use crate::command::MachineCommand;
use crate::driver::{CameraDriver, Reading};
use crate::error::VisionError;
use crate::machine::{checked, Machine};
use crate::module::capture::{centred_px, chain_with, k_in};
use crate::module::dro::{Dro, WalkProgress};
use crate::params::Params;

/// Where a stepwise M283 walk needs its next capture (see
/// [`crate::VisionModule::m283_next`]): the camera tool's X/Y and its height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkTarget {
    /// Program frame, current units.
    pub at: Point2<f64>,
    /// Height above the Z the walk started at, current units (machine +Z, up): 0, or
    /// `VisionCalibrationLift` while the calibration lift reads.
    pub lift: f64,
}

/// A capture during calibration.
#[derive(Debug, Clone, Copy)]
pub(super) struct Shot {
    pub(super) pos: Point2<f64>,
    pub(super) native: Point2<f64>,
    pub(super) reading: Reading,
    pub(super) dot: usize,
    /// Taken by the sheet walk proper (at the calibration height), not by the lift or the
    /// lens grid.
    pub(super) in_fit: bool,
    /// Taken with the head raised by the calibration lift.
    pub(super) lifted: bool,
}

/// An incremental rapid by `d` (program frame), absolute again after it (the Vision M-codes
/// expect absolute programs, as the manual's do).
pub(crate) fn relative_move(d: vision_math::Vector2<f64>) -> MachineCommand {
    MachineCommand::MoveBy(d)
}

/// An absolute rapid to `target` (program frame).
pub(crate) fn absolute_move(target: Point2<f64>) -> MachineCommand {
    MachineCommand::MoveTo(target)
}

/// Where a walker's readings come from.
enum Source<'a> {
    /// The camera, triggered where the walker's moves (run on the machine) left it.
    Live(&'a mut dyn CameraDriver),
    /// Readings taken before, each with the program position it was taken at. Moves are not
    /// run: the walker only tracks where they would have gone (`at`). A trigger past the last
    /// reading stops the walk and records where that capture is `needed`.
    /// `lift`: how far above the walk's start Z the moves so far left the head (current units).
    Replay { taken: &'a [(Point2<f64>, Reading)], next: usize, at: Point2<f64>, lift: f64, needed: Option<WalkTarget> },
}

/// Moves, dwells and triggers; writes every trigger to the DRO as it happens.
pub(crate) struct Walker<'a> {
    pub(super) machine: &'a mut dyn Machine,
    source: Source<'a>,
    params: &'a Params,
    dro: &'a mut Dro,
    pub(super) unit: LengthUnit,
    pub(super) shots: Vec<Shot>,
    pub(super) triggers: usize,
    /// Every line run on the machine (on a replay: that would have run), in order (M283's
    /// reply lists them).
    ran: Vec<String>,
    /// The last trigger's reading (a failed one too), for the `Last*` telemetry.
    last: Option<Reading>,
    /// The best K (current units per pixel) and remap known so far, for the DRO: the module's
    /// calibration at the start, then each one the routine solves.
    pub(super) known: Option<(Matrix2<f64>, Remap)>,
    /// True while the calibration lift or the lens grid reads: its shots stay out of the sheet
    /// fit.
    pub(super) lifting: bool,
    /// How far the walk's moves have raised the head above its start, current units.
    raised: f64,
}

impl<'a> Walker<'a> {
    /// A walker that moves `machine` (whose units are `unit`) and triggers `driver`, dwelling
    /// `VisionTriggerSettleSec` after every move.
    pub(crate) fn new(
        machine: &'a mut dyn Machine,
        driver: &'a mut dyn CameraDriver,
        params: &'a Params,
        dro: &'a mut Dro,
        unit: LengthUnit,
    ) -> Self {
        Walker::with_source(machine, Source::Live(driver), params, dro, unit)
    }

    /// A walker that replays `taken` (readings with the program positions they were taken at)
    /// from `start`: it runs nothing on `machine` and only reads it (units, tool offsets, clock).
    /// Only the newest reading reaches the DRO: the older ones were shown when they were new.
    pub(crate) fn replay(
        machine: &'a mut dyn Machine,
        taken: &'a [(Point2<f64>, Reading)],
        start: Point2<f64>,
        params: &'a Params,
        dro: &'a mut Dro,
        unit: LengthUnit,
    ) -> Self {
        Walker::with_source(
            machine,
            Source::Replay { taken, next: 0, at: start, lift: 0.0, needed: None },
            params,
            dro,
            unit,
        )
    }

    fn with_source(
        machine: &'a mut dyn Machine,
        source: Source<'a>,
        params: &'a Params,
        dro: &'a mut Dro,
        unit: LengthUnit,
    ) -> Self {
        let known = Some((k_in(params, unit), params.remap()));
        Walker {
            machine,
            source,
            params,
            dro,
            unit,
            shots: Vec::new(),
            triggers: 0,
            ran: Vec::new(),
            last: None,
            known,
            lifting: false,
            raised: 0.0,
        }
    }

    /// Moves the head by `dz` along machine Z (current units, relative, then absolute again)
    /// and settles. `Err(true)`: the move ran but the settle failed (the head moved);
    /// `Err(false)`: the controller refused the move (it did not).
    pub(super) fn move_z(&mut self, dz: f64) -> Result<(), (bool, VisionError)> {
        let command = MachineCommand::MoveZBy(dz);
        if let Source::Replay { lift, .. } = &mut self.source {
            *lift += dz;
            self.ran.extend(self.machine.gcode(&command).map_err(|e| (false, e.into()))?);
            self.raised += dz;
            return Ok(());
        }
        let lines = self.machine.command(&command).map_err(|e| (false, e.into()))?;
        self.ran.extend(lines);
        self.raised += dz;
        self.machine.dwell(self.params.trigger_settle_s()).map_err(|e| (true, e.into()))
    }

    /// The lines run so far, in order, and the last trigger's reading.
    pub(crate) fn into_ran(self) -> (Vec<String>, Option<Reading>) {
        (self.ran, self.last)
    }

    /// On a replay that ran out of readings: where the next capture must be taken (program
    /// frame).
    pub(crate) fn needed(&self) -> Option<WalkTarget> {
        match self.source {
            Source::Replay { needed, .. } => needed,
            Source::Live(_) => None,
        }
    }

    /// Runs `command` (a move to `target`, program frame) on the machine, records its lines,
    /// settles.
    fn run(&mut self, command: MachineCommand, target: Point2<f64>) -> Result<(), VisionError> {
        let lines = if let Source::Replay { at, .. } = &mut self.source {
            *at = target;
            self.machine.gcode(&command)?
        } else {
            let lines = self.machine.command(&command)?;
            self.machine.dwell(self.params.trigger_settle_s())?;
            lines
        };
        self.ran.extend(lines);
        Ok(())
    }

    pub(super) fn position(&self) -> Result<Point2<f64>, VisionError> {
        match self.source {
            Source::Replay { at, .. } => Ok(at),
            Source::Live(_) => Ok(checked::program_position(self.machine)?),
        }
    }

    /// Incremental move to `target` (program frame), then back to G90, then settle.
    pub(super) fn move_to(&mut self, target: Point2<f64>) -> Result<(), VisionError> {
        self.run(relative_move(target - self.position()?), target)
    }

    /// Absolute G90 move to `target`, then settle.
    pub(super) fn move_abs(&mut self, target: Point2<f64>) -> Result<(), VisionError> {
        self.run(absolute_move(target), target)
    }

    /// Triggers and records a shot of walk dot `dot`; returns its index. The DRO shows the
    /// reading at once (through the best K known so far), or the failure.
    pub(super) fn shoot(&mut self, dot: usize) -> Result<usize, VisionError> {
        self.take(dot, false).map(Option::unwrap_or_default)
    }

    /// [`Walker::shoot`] where a camera that finds no mark is an answer, not a failure (the
    /// lens grid's far positions): `None` then, and nothing recorded but the trigger.
    pub(super) fn try_shoot(&mut self, dot: usize) -> Result<Option<usize>, VisionError> {
        self.take(dot, true)
    }

    fn take(&mut self, dot: usize, may_miss: bool) -> Result<Option<usize>, VisionError> {
        self.triggers += 1;
        let (reading, pos, newest) = match &mut self.source {
            Source::Live(driver) => match driver.trigger() {
                Ok(r) => (r, checked::program_position(self.machine)?, true),
                Err(e) => {
                    let e = VisionError::from(e);
                    self.dro.failure(Some(-1), &e);
                    return Err(e);
                }
            },
            Source::Replay { taken, next, at, lift, needed } => {
                let Some(&(pos, reading)) = taken.get(*next) else {
                    *needed = Some(WalkTarget { at: *at, lift: *lift });
                    return Err(fail("a capture is needed to go on (the stepwise M283 walk)"));
                };
                *next += 1;
                (reading, pos, *next == taken.len())
            }
        };
        self.last = Some(reading);
        if !reading.found() && may_miss {
            return Ok(None);
        }
        if !reading.found() {
            let why = match &self.source {
                Source::Live(driver) => driver.miss_reason().map(|r| format!(" ({r})")).unwrap_or_default(),
                Source::Replay { .. } => String::new(),
            };
            let e = fail(format!(
                "the camera lost the mark (NG / no mark{why}) at X{} Y{} — keep the dot in view, check lighting \
                 and the camera job",
                fixed(pos.x, 4),
                fixed(pos.y, 4)
            ));
            if newest {
                self.dro.failure(Some(i64::from(reading.judgment.code())), &e);
            }
            return Err(e);
        }
        let native = Point2::new(reading.x_px, reading.y_px);
        if newest {
            let chain = self.known.and_then(|(k, remap)| chain_with(self.params, k, remap).ok());
            self.dro.reading(chain.as_ref(), centred_px(self.params, native), &reading);
        }
        self.shots.push(Shot { pos, native, reading, dot, in_fit: !self.lifting, lifted: self.raised != 0.0 });
        Ok(Some(self.shots.len() - 1))
    }

    /// Tells the host's progress sink where the walk is; a replay (the stepwise walk) tells
    /// nothing, its stages were told when they ran.
    pub(super) fn progress(&mut self, progress: WalkProgress) {
        if matches!(self.source, Source::Live(_)) {
            self.dro.progress(progress);
        }
    }
}
