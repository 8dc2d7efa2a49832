//! [`SimMachine`]: the interpreter as a simulated CNC, moving the simulated head.

use std::cell::RefCell;

use nalgebra::Point3;
use vision_core::{Machine, MachineError, Timestamp};
use vision_gcode::params::WORK_OFFSET_BASE;
use vision_gcode::{Event, EventSink, GcodeError, Interpreter, InterpreterConfig, MCodeHandler, RunOutcome, Tool, Xyz};
use vision_math::{AlignmentChain, LengthUnit, Point2, Vector2};
use vision_mcode::{Clock, ContextMachine};

use crate::error::SimError;
use crate::sim::Sim;

/// Keeps the simulated head where the machine's motion left it.
#[derive(Debug)]
struct Head {
    sim: Sim,
}

impl Head {
    fn follow(&self, event: &Event) {
        let end = match event {
            Event::Linear(mv) => mv.end,
            Event::Arc(arc) => arc.end,
            _ => return,
        };
        self.sim.set_spindle(Point3::new(end.x, end.y, end.z));
    }
}

impl EventSink for Head {
    fn event(&mut self, event: &Event) {
        self.follow(event);
    }
}

/// The head, then another sink.
struct Tee<'a> {
    head: &'a Head,
    next: &'a mut dyn EventSink,
}

impl EventSink for Tee<'_> {
    fn event(&mut self, event: &Event) {
        self.head.follow(event);
        self.next.event(event);
    }
}

#[derive(Debug)]
struct Inner {
    interp: Interpreter,
    head: Head,
}

/// A simulated CNC: the G-code interpreter set up from the world (machine unit = the world's
/// unit, G54 = `machine.work_offset`, the tool table with the world's tools and the camera tool,
/// the spindle at `machine.start`, `machine.start_tool` loaded), whose every move moves the
/// simulated head, so [`crate::SimCamera`] sees what the real camera would.
///
/// It implements [`vision_core::Machine`] through [`vision_mcode::ContextMachine`] (the same
/// bridge the M-code handler uses inside a program), and runs whole programs with
/// [`SimMachine::run_program`].
pub struct SimMachine {
    sim: Sim,
    inner: RefCell<Inner>,
    clock: Clock,
}

impl std::fmt::Debug for SimMachine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimMachine").field("sim", &self.sim).field("inner", &self.inner).finish_non_exhaustive()
    }
}

fn gcode_error(e: &GcodeError) -> SimError {
    SimError::Machine { reason: e.to_string() }
}

impl SimMachine {
    /// The machine of `sim`'s world, telling time by `clock`.
    ///
    /// # Errors
    /// [`SimError::Machine`] if the world's set-up cannot be applied (it can for a validated
    /// world).
    pub fn new(sim: &Sim, clock: Clock) -> Result<SimMachine, SimError> {
        let world = sim.world();
        let unit = world.length_unit();
        let mut config = InterpreterConfig::new(unit);
        for t in &world.machine.tools {
            config
                .tools
                .insert(t.number, Tool { offset: Xyz::new(t.offset[0], t.offset[1], t.offset[2]), outputs: None });
        }
        let camera = world
            .machine
            .camera_table_offset
            .map_or_else(|| sim.true_camera_offset(Vector2::zeros(), unit), Vector2::from);
        config
            .tools
            .insert(world.machine.camera_tool, Tool { offset: Xyz::new(camera.x, camera.y, 0.0), outputs: None });
        let mut interp = Interpreter::new(config);
        for (i, v) in world.machine.work_offset.iter().enumerate() {
            // G54's X, Y, Z at LinuxCNC's addresses.
            let n = WORK_OFFSET_BASE + u32::try_from(i).unwrap_or(0);
            interp.set_param(n, *v).map_err(|e| gcode_error(&e))?;
        }
        let [x, y, z] = world.machine.start;
        interp.set_machine_position(Xyz::new(x, y, z)).map_err(|e| gcode_error(&e))?;
        let mut head = Head { sim: sim.clone() };
        head.sim.set_spindle(Point3::new(x, y, z));
        if world.machine.start_tool != 0 {
            interp
                .context(&mut head)
                .execute(&format!("T{} M6", world.machine.start_tool))
                .map_err(|e| gcode_error(&e))?;
        }
        Ok(SimMachine { sim: sim.clone(), inner: RefCell::new(Inner { interp, head }), clock })
    }

    /// The simulated world this machine moves in.
    #[must_use]
    pub fn sim(&self) -> &Sim {
        &self.sim
    }

    /// A copy of the interpreter's state (positions, modals, parameters, tool table).
    #[must_use]
    pub fn interpreter(&self) -> Interpreter {
        self.inner.borrow().interp.clone()
    }

    /// The clock.
    #[must_use]
    pub fn clock(&self) -> &Clock {
        &self.clock
    }

    /// Runs a whole program: user M-codes go to `handler` (`None`: reported, not run), every
    /// event moves the head and then reaches `sink`.
    ///
    /// # Errors
    /// The first failing line (see `vision_gcode::Interpreter::run`).
    pub fn run_program(
        &mut self,
        text: &str,
        handler: Option<&mut dyn MCodeHandler>,
        sink: &mut dyn EventSink,
    ) -> Result<RunOutcome, GcodeError> {
        let inner = self.inner.get_mut();
        let mut tee = Tee { head: &inner.head, next: sink };
        inner.interp.run(text, handler, &mut tee)
    }

    /// Runs `f` on the [`ContextMachine`] of this machine.
    fn with<R>(&self, f: impl FnOnce(&mut ContextMachine<'_, '_>) -> R) -> R {
        let mut inner = self.inner.borrow_mut();
        let Inner { interp, head } = &mut *inner;
        let mut ctx = interp.context(head);
        f(&mut ContextMachine::new(&mut ctx, &self.clock))
    }

    /// The machine (spindle) position where commanding program point `p` (current units,
    /// G90, the modal state as it is now) would put it, after first running `setup` (e.g. an
    /// alignment M282 emitted) — on a copy: this machine does not move.
    ///
    /// # Errors
    /// [`SimError::Machine`] if `setup` or the move fails.
    pub fn machine_point_for(&self, setup: &[String], p: Point2<f64>) -> Result<Xyz, SimError> {
        let mut copy = self.interpreter();
        let mut ignore = |_: &Event| {};
        let mut ctx = copy.context(&mut ignore);
        ctx.execute(&setup.join("\n")).map_err(|e| gcode_error(&e))?;
        ctx.execute(&format!("G90 G0 X{} Y{}", p.x, p.y)).map_err(|e| gcode_error(&e))?;
        Ok(copy.machine_position())
    }

    /// The cut error of nominal point `nominal` of fixture `fixture` (work coordinates, world
    /// unit): the distance, in the world unit, between where the active tool's point really goes
    /// when the program commands `nominal` (after `setup`, through the alignment modals) and
    /// where that point of the fixture really lies. The tool's point is the spindle plus the
    /// tool's true offset; for the camera tool, the point imaged at the image centre (what the
    /// camera tool's table offset refers to with `PxCenterOffset` 0).
    ///
    /// # Errors
    /// [`SimError::UnknownFixture`], or [`SimError::Machine`] from the move.
    pub fn cut_error(&self, setup: &[String], fixture: &str, nominal: Point2<f64>) -> Result<f64, SimError> {
        let world = self.sim.world();
        let unit = world.length_unit();
        let f = world.fixtures.iter().find(|f| f.name == fixture).ok_or_else(|| SimError::UnknownFixture {
            name: fixture.to_string(),
            known: world.fixtures.iter().map(|f| f.name.clone()).collect::<Vec<_>>().join(", "),
        })?;
        let units = self.units();
        let spindle = self.machine_point_for(setup, nominal * unit.factor_to(units))?;
        let tool = self.active_tool();
        let tool_offset = if tool == world.machine.camera_tool {
            self.sim.true_camera_offset(Vector2::zeros(), unit)
        } else {
            world
                .machine
                .tools
                .iter()
                .find(|t| t.number == tool)
                .map_or(Vector2::zeros(), |t| Vector2::new(t.offset[0], t.offset[1]))
        };
        let point = spindle.xy() + tool_offset;
        let truth = world.work_to_machine(f.true_point(nominal, unit));
        Ok((point - truth).norm())
    }
}

impl Machine for SimMachine {
    fn program_position(&self) -> Point2<f64> {
        self.with(|m| m.program_position())
    }

    fn active_alignment(&self) -> Option<AlignmentChain> {
        self.with(|m| m.active_alignment())
    }

    fn run_gcode(&mut self, lines: &[String]) -> Result<(), MachineError> {
        self.with(|m| m.run_gcode(lines))
    }

    fn active_tool(&self) -> u32 {
        self.with(|m| m.active_tool())
    }

    fn tool_offset(&self, tool: u32) -> Result<Vector2<f64>, MachineError> {
        self.with(|m| m.tool_offset(tool))
    }

    fn set_tool_offset(&mut self, tool: u32, offset: Vector2<f64>) -> Result<(), MachineError> {
        self.with(|m| m.set_tool_offset(tool, offset))
    }

    fn units(&self) -> LengthUnit {
        self.with(|m| m.units())
    }

    fn pound(&self, index: u32) -> Result<f64, MachineError> {
        self.with(|m| m.pound(index))
    }

    fn set_pound(&mut self, index: u32, value: f64) -> Result<(), MachineError> {
        self.with(|m| m.set_pound(index, value))
    }

    fn dwell(&mut self, seconds: f64) {
        self.with(|m| m.dwell(seconds));
    }

    fn now(&self) -> Timestamp {
        (self.clock)()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::World;
    use vision_core::CameraDriver;
    use vision_mcode::fixed_clock;

    fn machine() -> (Sim, SimMachine) {
        let sim = Sim::new(World::default_world()).expect("sim");
        let m = SimMachine::new(&sim, fixed_clock(Timestamp::from_unix(1_800_000_000, 0))).expect("machine");
        (sim, m)
    }

    #[test]
    fn starts_where_the_world_says_and_moves_the_head() {
        let (sim, mut m) = machine();
        assert_eq!(m.active_tool(), 1);
        // Spindle at (10.9, 2.15) machine = (0.9, −5.85) in G54 work (zero at (10, 8)).
        assert!((m.program_position() - Point2::new(0.9, -5.85)).norm() < 1e-12);
        m.run_gcode(&["T98 M6".into(), "G90 G0 X0 Y0".into()]).expect("moves");
        // With the calibrated camera tool active, (0, 0) puts the camera's reference pixel over
        // work zero: sheet dot 5 images at the image centre.
        let r = sim.camera().trigger().expect("reading");
        let want = sim.optics().resolution() * 0.5;
        assert!((r.x_px - want.x).abs() < 0.5 && (r.y_px - want.y).abs() < 0.5, "{r:?}");
        assert_eq!(m.units(), LengthUnit::Inch);
        m.run_gcode(&["G21".into()]).expect("mm");
        assert!(m.program_position().coords.norm() < 1e-9);
        assert!(
            (m.tool_offset(98).expect("tool").x - sim.true_camera_offset(Vector2::zeros(), LengthUnit::Millimetre).x)
                .abs()
                < 1e-9
        );
    }

    #[test]
    fn cut_error_is_zero_for_a_perfect_alignment_and_the_pose_without_one() {
        let (sim, mut m) = machine();
        m.run_gcode(&["T1 M6".into()]).expect("cutter");
        let f = &sim.world().fixtures[0];
        let p = Point2::new(6.0, 4.0);
        let truth = f.true_point(p, LengthUnit::Inch);
        // No alignment: the error is how far the fixture lies from nominal.
        let e = m.cut_error(&[], "demo target", p).expect("cut");
        assert!((e - (truth - p).norm()).abs() < 1e-12, "{e}");
        // The exact pose as G51/G68/G52 (scale about the origin = the pivot, rotate about it).
        let chain = AlignmentChain {
            scale: Vector2::new(f.scale[0], f.scale[1]),
            center: Point2::origin(),
            rotation_deg: f.rotation_deg,
            shift: Vector2::zeros(),
        };
        let setup = chain.gcode().expect("finite").to_vec();
        assert!(m.cut_error(&setup, "demo target", p).expect("cut") < 1e-6);
        assert!(matches!(m.cut_error(&[], "nope", p), Err(SimError::UnknownFixture { .. })));
        assert!(matches!(m.cut_error(&["G6".into()], "demo target", p), Err(SimError::Machine { .. })));
        assert_eq!(m.active_tool(), 1, "the question ran on a copy");
    }
}
