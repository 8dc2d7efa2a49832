//! [`SimMachine`]: the interpreter as a simulated CNC, moving the simulated head.

use vision_core::Controller;
use vision_gcode::params::WORK_OFFSET_BASE;
use vision_gcode::{
    Context, Dialect, Event, EventSink, GcodeError, Interpreter, InterpreterConfig, MCodeHandler, OffsetParts,
    RunOutcome, Tool, Xyz,
};
use vision_math::{Point2, Vector2};

use crate::error::SimError;
use crate::sim::Sim;

/// The interpreter dialect of `controller`'s G-code ([`vision_core::Controller::dialect`]): the
/// one place a controller becomes a `vision_gcode::Dialect`.
///
/// # Panics
/// When a controller names a dialect the interpreter does not have (a test covers every
/// controller).
#[must_use]
pub fn interpreter_dialect(controller: &dyn Controller) -> Dialect {
    Dialect::from_name(controller.dialect())
        .unwrap_or_else(|| panic!("controller {} names an unknown dialect {}", controller.name(), controller.dialect()))
}

/// A simulated CNC: the G-code interpreter set up from the world (machine unit = the world's
/// unit, G54 = `machine.work_offset`, the tool table with the world's tools and the camera tool,
/// the spindle at `machine.start`, `machine.start_tool` loaded). The head is where the
/// interpreter is: [`crate::SimCamera`] reads the interpreter's published machine position
/// ([`Interpreter::watch_position`]), so it sees what the real camera would, also when
/// triggered from inside an M-code handler.
///
/// It is not itself a [`vision_core::Machine`]: the one bridge from an interpreter to that trait
/// is `vision_host::ContextMachine`, which a host wraps around [`SimMachine::context`]. This
/// crate stays below the M-code layer.
#[derive(Debug)]
pub struct SimMachine {
    sim: Sim,
    interp: Interpreter,
}

fn gcode_error(e: &GcodeError) -> SimError {
    SimError::Machine { reason: e.to_string() }
}

impl SimMachine {
    /// The machine of `sim`'s world; from now on `sim`'s head follows it (a later machine on the
    /// same `sim` takes the head over).
    ///
    /// # Errors
    /// [`SimError::Machine`] if the world's set-up cannot be applied (it can for a validated
    /// world).
    pub fn new(sim: &Sim) -> Result<SimMachine, SimError> {
        let world = sim.world();
        let unit = world.length_unit();
        let mut config = InterpreterConfig::new(unit);
        let controller = world.machine.controller();
        config.dialect = interpreter_dialect(controller);
        // The world gives where each tool's point lies from the spindle; the table holds that
        // with the controller's sign.
        let sign = controller.tool_table_sign();
        for t in &world.machine.tools {
            let offset = Xyz::new(sign * t.offset[0], sign * t.offset[1], t.offset[2]);
            config.tools.insert(t.number, Tool { offset, outputs: None });
        }
        let camera = world.machine.camera_table_offset.map_or_else(|| sim.calibrated_table_offset(unit), Vector2::from);
        let camera = Xyz::new(sign * camera.x, sign * camera.y, 0.0);
        config.tools.insert(world.machine.camera_tool, Tool { offset: camera, outputs: None });
        let mut interp = Interpreter::new(config);
        for (i, v) in world.machine.work_offset.iter().enumerate() {
            // G54's X, Y, Z at LinuxCNC's addresses.
            let n = WORK_OFFSET_BASE + u32::try_from(i).unwrap_or(0);
            interp.set_param(n, *v).map_err(|e| gcode_error(&e))?;
        }
        let [x, y, z] = world.machine.start;
        interp.set_machine_position(Xyz::new(x, y, z)).map_err(|e| gcode_error(&e))?;
        if world.machine.start_tool != 0 {
            let mut ignore = |_: &Event| {};
            interp
                .context(&mut ignore)
                .execute(&format!("T{} M6", world.machine.start_tool))
                .map_err(|e| gcode_error(&e))?;
        }
        sim.follow(interp.watch_position());
        Ok(SimMachine { sim: sim.clone(), interp })
    }

    /// The simulated world this machine moves in.
    #[must_use]
    pub fn sim(&self) -> &Sim {
        &self.sim
    }

    /// The interpreter: the machine's state (positions, modals, parameters, tool table). Clone
    /// it to ask "where would this go?" without moving the machine.
    #[must_use]
    pub fn interpreter(&self) -> &Interpreter {
        &self.interp
    }

    /// Puts the machine at `machine` (machine coordinates, machine units) without a move: where
    /// a real controller that this machine mirrors reports it is.
    ///
    /// # Errors
    /// [`SimError::Machine`] for a NaN or infinite coordinate.
    pub fn set_machine_position(&mut self, machine: Xyz) -> Result<(), SimError> {
        self.interp.set_machine_position(machine).map_err(|e| gcode_error(&e))
    }

    /// Writes parameter `#n` (offsets in machine units) as a controller's own table would: a
    /// real controller's work offsets, mirrored. Offsets take effect at once.
    ///
    /// # Errors
    /// [`SimError::Machine`] for a read-only or unknown parameter or a value out of range.
    pub fn set_param(&mut self, n: u32, value: f64) -> Result<(), SimError> {
        self.interp.set_param(n, value).map_err(|e| gcode_error(&e))
    }

    /// The interpreter, to change the machine's state outside a program.
    pub(crate) fn interpreter_mut(&mut self) -> &mut Interpreter {
        &mut self.interp
    }

    /// Host access to the machine outside a program: G-code, dwells, parameters, tool offsets
    /// (events go to `sink`). `vision_host::ContextMachine::new(&mut machine.context(sink),
    /// &clock)` makes it a [`vision_core::Machine`].
    pub fn context<'a>(&'a mut self, sink: &'a mut dyn EventSink) -> Context<'a> {
        self.interp.context(sink)
    }

    /// Runs a whole program: user M-codes go to `handler` (`None`: reported, not run), events
    /// go to `sink`.
    ///
    /// # Errors
    /// The first failing line (see `vision_gcode::Interpreter::run`).
    pub fn run_program(
        &mut self,
        text: &str,
        handler: Option<&mut dyn MCodeHandler>,
        sink: &mut dyn EventSink,
    ) -> Result<RunOutcome, GcodeError> {
        self.interp.run(text, handler, sink)
    }

    /// The machine (spindle) position where commanding program point `p` (current units,
    /// G90, the modal state as it is now) would put it, after first running `setup` (e.g. an
    /// alignment M282 emitted) — on a copy: this machine does not move.
    ///
    /// # Errors
    /// [`SimError::Machine`] if `setup` or the move fails.
    pub fn machine_point_for(&self, setup: &[String], p: Point2<f64>) -> Result<Xyz, SimError> {
        self.aligned_point_for(setup, None, p)
    }

    /// [`SimMachine::machine_point_for`], with the moves after `setup` mapped through `host`
    /// (current units), the alignment a host applies to the moves it sends (Grbl).
    ///
    /// # Errors
    /// As [`SimMachine::machine_point_for`]; a chain the interpreter refuses.
    pub fn aligned_point_for(
        &self,
        setup: &[String],
        host: Option<vision_math::AlignmentChain>,
        p: Point2<f64>,
    ) -> Result<Xyz, SimError> {
        let mut copy = self.interp.clone();
        let mut ignore = |_: &Event| {};
        let mut ctx = copy.context(&mut ignore);
        ctx.execute(&setup.join("\n")).map_err(|e| gcode_error(&e))?;
        if host.is_some() {
            ctx.set_host_alignment(host).map_err(|e| gcode_error(&e))?;
        }
        ctx.execute(&format!("G90 G0 X{} Y{}", p.x, p.y)).map_err(|e| gcode_error(&e))?;
        Ok(copy.machine_position())
    }

    /// The cut error of nominal point `nominal` of fixture `fixture` (work coordinates, world
    /// unit) for the active tool: [`SimMachine::tool_cut_error`] with the tool loaded now.
    ///
    /// # Errors
    /// As [`SimMachine::tool_cut_error`].
    pub fn cut_error(&self, setup: &[String], fixture: &str, nominal: Point2<f64>) -> Result<f64, SimError> {
        self.tool_cut_error(setup, self.interp.active_tool(), fixture, nominal)
    }

    /// The cut error of nominal point `nominal` of fixture `fixture` (work coordinates, world
    /// unit) for tool `tool`: the distance, in the world unit, between where that tool's point
    /// really goes when the program commands `nominal` (after `setup`, through the alignment
    /// modals) and where that point of the fixture really lies. The tool's point is the spindle
    /// plus the tool's true offset; for the camera tool, the point imaged at the image centre
    /// (what the camera tool's table offset refers to with `PxCenterOffset` 0).
    ///
    /// A `tool` other than the loaded one is loaded after `setup` (on the copy) with its
    /// offsets applied as a program applies them to cut: `T M6`, and on Mach4 and LinuxCNC
    /// `G43 H` (LinuxCNC applies a tool's X/Y offset only with G43; seed 002 has no G43). The
    /// loaded tool is measured with the offsets the machine applies now.
    ///
    /// # Errors
    /// [`SimError::UnknownFixture`], or [`SimError::Machine`] from the move.
    pub fn tool_cut_error(
        &self,
        setup: &[String],
        tool: u32,
        fixture: &str,
        nominal: Point2<f64>,
    ) -> Result<f64, SimError> {
        self.aligned_cut_error(setup, None, tool, fixture, nominal)
    }

    /// [`SimMachine::tool_cut_error`] of an alignment the host applies: the moves after `setup`
    /// (and the tool change) mapped through `host` (current units).
    ///
    /// # Errors
    /// As [`SimMachine::tool_cut_error`]; a chain the interpreter refuses.
    pub fn aligned_cut_error(
        &self,
        setup: &[String],
        host: Option<vision_math::AlignmentChain>,
        tool: u32,
        fixture: &str,
        nominal: Point2<f64>,
    ) -> Result<f64, SimError> {
        let world = self.sim.world();
        let unit = world.length_unit();
        let f = world.fixtures.iter().find(|f| f.name == fixture).ok_or_else(|| SimError::UnknownFixture {
            name: fixture.to_string(),
            known: world.fixtures.iter().map(|f| f.name.clone()).collect::<Vec<_>>().join(", "),
        })?;
        let mut setup = setup.to_vec();
        if tool != self.interp.active_tool() {
            // G43 applies what M6 leaves out of the offset.
            setup.push(match self.interp.config().rules().tool_change_applies {
                OffsetParts::Whole => format!("T{tool} M6"),
                OffsetParts::Xy | OffsetParts::Length | OffsetParts::Nothing => format!("T{tool} M6 G43 H{tool}"),
            });
        }
        let units = self.interp.units();
        let spindle = self.aligned_point_for(&setup, host, nominal * unit.factor_to(units))?;
        let tool_offset = if tool == world.machine.camera_tool {
            self.sim.calibrated_table_offset(unit)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::World;
    use vision_core::{CameraDriver, Reading};
    use vision_gcode::{HandlerError, UserMCode};
    use vision_math::{AlignmentChain, LengthUnit};

    #[test]
    fn every_controller_names_a_dialect_of_the_interpreter() {
        for c in vision_core::CONTROLLERS {
            assert_eq!(interpreter_dialect(c).name(), c.dialect(), "{}", c.name());
        }
    }

    fn machine() -> (Sim, SimMachine) {
        let sim = Sim::new(World::default_world()).expect("sim");
        let m = SimMachine::new(&sim).expect("machine");
        (sim, m)
    }

    fn execute(m: &mut SimMachine, gcode: &str) {
        let mut ignore = |_: &Event| {};
        m.context(&mut ignore).execute(gcode).expect("runs");
    }

    /// The reading of a centred mark: the image centre, to half a pixel (noise).
    /// The reading is at the optical centre (the reference pixel of a perfect calibration).
    fn centred(sim: &Sim, r: &Reading) -> bool {
        let want = sim.optics().resolution() * 0.5 + sim.optics().bias();
        (r.x_px - want.x).abs() < 0.5 && (r.y_px - want.y).abs() < 0.5
    }

    #[test]
    fn the_world_names_the_controls_dialect() {
        let (_, m) = machine();
        assert_eq!(m.interpreter().config().dialect, vision_gcode::Dialect::Mach4);
        // Mach4 applies the camera's X/Y offset at M6, as the manual's programs expect.
        let mut mach4 = m;
        execute(&mut mach4, "G90 G0 X0 Y0");
        let spindle_tool = mach4.interpreter().machine_position();
        execute(&mut mach4, "T98 M6\nG0 X0 Y0");
        let camera = mach4.interpreter().machine_position();
        assert!((camera - spindle_tool).norm() > 1.0, "{spindle_tool:?} {camera:?}");
        // LinuxCNC applies a tool's offsets at G43 only: T98 M6 leaves the spindle where it is.
        let toml = crate::DEFAULT_WORLD_TOML.replace("dialect = \"mach4\"", "dialect = \"linuxcnc\"");
        let sim = Sim::new(World::from_toml(&toml).expect("world")).expect("sim");
        let mut linuxcnc = SimMachine::new(&sim).expect("machine");
        assert_eq!(linuxcnc.interpreter().config().dialect, vision_gcode::Dialect::LinuxCnc);
        execute(&mut linuxcnc, "G90 G0 X0 Y0\nT98 M6\nG0 X0 Y0");
        let after_m6 = linuxcnc.interpreter().machine_position();
        execute(&mut linuxcnc, "G43 H98\nG0 X0 Y0");
        assert!((after_m6 - linuxcnc.interpreter().machine_position()).norm() > 1.0, "{after_m6:?}");
        // Its table holds the negated offset, which LinuxCNC adds: the camera lands as on Mach4.
        assert!((linuxcnc.interpreter().machine_position() - camera).norm() < 1e-9);
        let bad = crate::DEFAULT_WORLD_TOML.replace("dialect = \"mach4\"", "dialect = \"fanuc\"");
        assert!(World::from_toml(&bad).is_err());
    }

    #[test]
    fn starts_where_the_world_says_and_moves_the_head() {
        let (sim, mut m) = machine();
        assert_eq!(m.interpreter().active_tool(), 1);
        // Spindle at (10.9, 2.15) machine = (0.9, −5.85) in G54 work (zero at (10, 8)).
        assert!((m.interpreter().program_position().xy() - Point2::new(0.9, -5.85)).norm() < 1e-12);
        execute(&mut m, "T98 M6\nG90 G0 X0 Y0");
        // With the calibrated camera tool active, (0, 0) puts the optical axis over work zero:
        // sheet dot 5 images at the optical centre.
        let r = sim.camera().trigger().expect("reading");
        assert!(centred(&sim, &r), "{r:?}");
        assert_eq!(m.interpreter().units(), LengthUnit::Inch);
        execute(&mut m, "G21");
        assert!(m.interpreter().program_position().norm() < 1e-9);
        let camera = m.interpreter().tool_offset(98).expect("tool");
        assert!((camera.x - sim.calibrated_table_offset(LengthUnit::Millimetre).x).abs() < 1e-9);
    }

    /// Moves the camera over work zero, then triggers: what a calibration does inside M283.
    struct MoveAndTrigger(crate::SimCamera, Vec<Reading>);

    impl MCodeHandler for MoveAndTrigger {
        fn call(&mut self, _call: &UserMCode<'_>, ctx: &mut Context<'_>) -> Result<Vec<String>, HandlerError> {
            ctx.execute("T98 M6\nG90 G0 X0 Y0")?;
            let reading = self.0.trigger().map_err(|e| HandlerError::Failed(e.to_string()))?;
            self.1.push(reading);
            Ok(Vec::new())
        }
    }

    #[test]
    fn the_camera_sees_where_the_interpreter_is_inside_a_handler_and_questions_move_nothing() {
        let (sim, mut m) = machine();
        let mut handler = MoveAndTrigger(sim.camera(), Vec::new());
        m.run_program("M300", Some(&mut handler), &mut Vec::new()).expect("runs");
        assert!(centred(&sim, &handler.1[0]), "{:?}", handler.1);
        // A question on a copy of the interpreter does not move the head.
        let far = m.machine_point_for(&[], Point2::new(-50.0, -50.0)).expect("moves");
        assert!((far.xy() - m.interpreter().machine_position().xy()).norm() > 10.0);
        assert!(centred(&sim, &sim.camera().trigger().expect("reading")));
    }

    #[test]
    fn cut_error_is_zero_for_a_perfect_alignment_and_the_pose_without_one() {
        let (sim, mut m) = machine();
        execute(&mut m, "T1 M6");
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
        let setup =
            vec![format!("G51 X{} Y{}", chain.scale.x, chain.scale.y), format!("G68 X0 Y0 R{}", chain.rotation_deg)];
        assert!(m.cut_error(&setup, "demo target", p).expect("cut") < 1e-6);
        assert!(matches!(m.cut_error(&[], "nope", p), Err(SimError::UnknownFixture { .. })));
        assert!(matches!(m.cut_error(&["G6".into()], "demo target", p), Err(SimError::Machine { .. })));
        assert_eq!(m.interpreter().active_tool(), 1, "the question ran on a copy");
    }

    /// A tool other than the loaded one is measured as a program loads it to cut: on every
    /// dialect the same as loading it for real, also on LinuxCNC, whose G43 applies its X/Y.
    #[test]
    fn a_tool_not_loaded_is_measured_with_its_offsets_applied_as_for_a_cut() {
        for dialect in ["mach4", "linuxcnc", "machinemotion"] {
            let toml = crate::DEFAULT_WORLD_TOML
                .replace("dialect = \"mach4\"", &format!("dialect = \"{dialect}\""))
                .replace("offset = [0.0, 0.0, 0.0]", "offset = [0.5, -0.25, 0.0]");
            let sim = Sim::new(World::from_toml(&toml).expect("world")).expect("sim");
            let mut m = SimMachine::new(&sim).expect("machine");
            let load = |tool: u32| match dialect {
                "machinemotion" => format!("T{tool} M6"),
                _ => format!("T{tool} M6 G43 H{tool}"),
            };
            execute(&mut m, &load(98));
            let p = Point2::new(6.0, 4.0);
            let camera = m.cut_error(&[], "demo target", p).expect("camera");
            let cutter = m.tool_cut_error(&[], 1, "demo target", p).expect("cutter");
            assert_eq!(m.interpreter().active_tool(), 98, "{dialect}: the question ran on a copy");
            execute(&mut m, &load(1));
            let loaded = m.cut_error(&[], "demo target", p).expect("loaded");
            assert!((cutter - loaded).abs() < 1e-12, "{dialect}: {cutter} vs loaded {loaded}");
            // Both miss by the fixture's own pose alone (no alignment: 0.04 in at this corner);
            // a cutter measured with the camera's offsets would be 3.6 in off.
            let pose = (sim.world().fixtures[0].true_point(p, LengthUnit::Inch) - p).norm();
            assert!((camera - pose).abs() < 1e-6 && (loaded - pose).abs() < 1e-9, "{dialect}: {camera} {loaded}");
        }
    }
}
