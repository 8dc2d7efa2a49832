//! [`ContextMachine`]: the interpreter, seen by the Vision module as its host.

use std::sync::Arc;
use std::time::SystemTime;

use vision_core::{Controller, Machine, MachineCommand, MachineError, MachineErrorKind, Timestamp};
use vision_gcode::params::{TOOL_OFFSET, WORK_OFFSET_STRIDE, WORK_ROTATION};
use vision_gcode::{Context, GcodeError};
use vision_math::{LengthUnit, Point2, Vector2};

/// The host's clock, shared by whoever needs it.
pub type Clock = Arc<dyn Fn() -> Timestamp + Send + Sync>;

/// The system clock, in UTC (the standard library has no time-zone database, so `Cal_Date`
/// carries `+00:00`).
#[must_use]
pub fn system_clock() -> Clock {
    Arc::new(|| Timestamp { time: SystemTime::now(), utc_offset_s: 0 })
}

/// A clock that always reads `t` (deterministic runs and tests).
#[must_use]
pub fn fixed_clock(t: Timestamp) -> Clock {
    Arc::new(move || t)
}

/// [`vision_core::Machine`] over an interpreter [`Context`] — the simulated machine: inside an
/// M-code handler, or around a standalone interpreter (`Interpreter::context`).
///
/// Every length is in the interpreter's current units (G20/G21), as the trait asks. The
/// commands run in the controller's text (`vision_mcode::gcode`), synchronously through
/// [`Context::execute`], so calibration moves, then triggers, then reads
/// the new position. The interpreter knows its alignment exactly, so it answers
/// [`Machine::alignment_active`]; the G5x rotation and the G92 offset are its own.
pub struct ContextMachine<'c, 'a> {
    ctx: &'c mut Context<'a>,
    clock: &'c Clock,
    controller: &'static dyn Controller,
}

impl<'c, 'a> ContextMachine<'c, 'a> {
    /// The machine behind `ctx`, a `controller` (whose dialect the interpreter follows), telling
    /// time by `clock`.
    pub fn new(
        ctx: &'c mut Context<'a>,
        clock: &'c Clock,
        controller: &'static dyn Controller,
    ) -> ContextMachine<'c, 'a> {
        ContextMachine { ctx, clock, controller }
    }

    /// The current units per machine unit.
    fn per_machine_unit(&self) -> f64 {
        self.ctx.interpreter().machine_unit().factor_to(self.ctx.units())
    }
}

/// The interpreter's error as a [`MachineError`] of `kind`, the error kept as the cause.
fn host(kind: MachineErrorKind) -> impl Fn(GcodeError) -> MachineError {
    move |e| MachineError::new(kind, e)
}

impl Machine for ContextMachine<'_, '_> {
    fn controller(&self) -> &'static dyn Controller {
        self.controller
    }

    fn gcode(&self, command: &MachineCommand) -> Result<Vec<String>, MachineError> {
        Ok(vision_mcode::gcode(self.controller, command)?)
    }

    /// [`MachineCommand::AlignMoves`] and [`MachineCommand::CancelMoveAlignment`] set the
    /// interpreter's alignment directly (the host maps the moves; no line runs); every other
    /// command runs its text.
    fn command(&mut self, command: &MachineCommand) -> Result<Vec<String>, MachineError> {
        let chain = match *command {
            MachineCommand::AlignMoves(chain) => Some(chain),
            MachineCommand::CancelMoveAlignment => None,
            _ => {
                let lines = self.gcode(command)?;
                lines.iter().try_for_each(|line| self.execute(line))?;
                return Ok(lines);
            }
        };
        self.ctx.set_host_alignment(chain).map_err(host(MachineErrorKind::RefusedGcode))?;
        Ok(Vec::new())
    }

    fn execute(&mut self, line: &str) -> Result<(), MachineError> {
        self.ctx.execute(line).map_err(host(MachineErrorKind::RefusedGcode))
    }

    fn save_modal_state(&mut self) -> Result<(), MachineError> {
        self.ctx.push_modal_state().map_err(host(MachineErrorKind::Other))
    }

    fn restore_modal_state(&mut self) -> Result<(), MachineError> {
        self.ctx.pop_modal_state().map_err(host(MachineErrorKind::Other))
    }

    fn program_position(&self) -> Result<Point2<f64>, MachineError> {
        Ok(self.ctx.program_position().xy())
    }

    fn alignment_active(&self) -> Result<Option<bool>, MachineError> {
        Ok(Some(self.ctx.active_alignment().is_some()))
    }

    fn xy_rotation_deg(&self) -> Result<f64, MachineError> {
        let system = self.ctx.interpreter().coordinate_system().max(1);
        self.ctx.pound(WORK_ROTATION + WORK_OFFSET_STRIDE * (system - 1)).map_err(host(MachineErrorKind::OutOfRange))
    }

    fn g92_offset(&self) -> Result<Vector2<f64>, MachineError> {
        let g92 = self.ctx.interpreter().g92_offset();
        Ok(Vector2::new(g92.x, g92.y) * self.per_machine_unit())
    }

    fn active_tool(&self) -> Result<u32, MachineError> {
        Ok(self.ctx.active_tool())
    }

    fn tool_offset(&self, tool: u32) -> Result<Vector2<f64>, MachineError> {
        let o = self.ctx.tool_offset(tool).map_err(host(MachineErrorKind::UnknownTool))?;
        Ok(Vector2::new(o.x, o.y))
    }

    fn set_tool_offset(&mut self, tool: u32, offset: Vector2<f64>) -> Result<(), MachineError> {
        self.ctx.set_tool_offset(tool, offset.x, offset.y).map_err(host(MachineErrorKind::UnknownTool))
    }

    /// `#5401`/`#5402`: the interpreter mirrors there the X/Y offset it applies, in the
    /// table's form and current units (under LinuxCNC's rules zero until `G43`).
    fn applied_tool_offset(&self) -> Result<Option<Vector2<f64>>, MachineError> {
        let read = |n| self.ctx.pound(n).map_err(host(MachineErrorKind::OutOfRange));
        Ok(Some(Vector2::new(read(TOOL_OFFSET)?, read(TOOL_OFFSET + 1)?)))
    }

    fn units(&self) -> Result<LengthUnit, MachineError> {
        Ok(self.ctx.units())
    }

    fn pound(&self, index: u32) -> Result<f64, MachineError> {
        self.ctx.pound(index).map_err(host(MachineErrorKind::OutOfRange))
    }

    fn set_pound(&mut self, index: u32, value: f64) -> Result<(), MachineError> {
        self.ctx.set_pound(index, value).map_err(host(MachineErrorKind::OutOfRange))
    }

    fn dwell(&mut self, seconds: f64) -> Result<(), MachineError> {
        self.ctx.dwell(seconds).map_err(host(MachineErrorKind::OutOfRange))
    }

    fn now(&self) -> Timestamp {
        (self.clock)()
    }
}
