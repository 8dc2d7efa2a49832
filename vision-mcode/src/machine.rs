//! [`ContextMachine`]: the interpreter, seen by the Vision module as its host.

use std::sync::Arc;
use std::time::SystemTime;

use vision_core::{Machine, MachineError, Timestamp};
use vision_gcode::Context;
use vision_math::{AlignmentChain, LengthUnit, Point2, Vector2};

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

/// [`vision_core::Machine`] over an interpreter [`Context`]: inside an M-code handler, or around
/// a standalone interpreter (`Interpreter::context`).
///
/// Every length is in the interpreter's current units (G20/G21), as the trait asks. G-code runs
/// synchronously through [`Context::execute`], so calibration moves, then triggers, then reads
/// the new position.
pub struct ContextMachine<'c, 'a> {
    ctx: &'c mut Context<'a>,
    clock: &'c Clock,
}

impl<'c, 'a> ContextMachine<'c, 'a> {
    /// The machine behind `ctx`, telling time by `clock`.
    pub fn new(ctx: &'c mut Context<'a>, clock: &'c Clock) -> ContextMachine<'c, 'a> {
        ContextMachine { ctx, clock }
    }
}

fn host<E: std::fmt::Display>(e: E) -> MachineError {
    MachineError::new(e.to_string())
}

impl Machine for ContextMachine<'_, '_> {
    fn program_position(&self) -> Point2<f64> {
        self.ctx.program_position().xy()
    }

    fn active_alignment(&self) -> Option<AlignmentChain> {
        self.ctx.active_alignment()
    }

    fn run_gcode(&mut self, lines: &[String]) -> Result<(), MachineError> {
        self.ctx.execute(&lines.join("\n")).map_err(host)
    }

    fn active_tool(&self) -> u32 {
        self.ctx.active_tool()
    }

    fn tool_offset(&self, tool: u32) -> Result<Vector2<f64>, MachineError> {
        let o = self.ctx.tool_offset(tool).map_err(host)?;
        Ok(Vector2::new(o.x, o.y))
    }

    fn set_tool_offset(&mut self, tool: u32, offset: Vector2<f64>) -> Result<(), MachineError> {
        self.ctx.set_tool_offset(tool, offset.x, offset.y).map_err(host)
    }

    fn units(&self) -> LengthUnit {
        self.ctx.units()
    }

    fn pound(&self, index: u32) -> Result<f64, MachineError> {
        self.ctx.pound(index).map_err(host)
    }

    fn set_pound(&mut self, index: u32, value: f64) -> Result<(), MachineError> {
        self.ctx.set_pound(index, value).map_err(host)
    }

    fn dwell(&mut self, seconds: f64) {
        // The core dwells `VisionTriggerSettleSec`, validated finite and ≥ 0; anything else is
        // not a wait, so it is skipped rather than turned into an error the trait cannot carry.
        let _ = self.ctx.dwell(seconds);
    }

    fn now(&self) -> Timestamp {
        (self.clock)()
    }
}
