//! Helpers for the tests of host bridges (feature `testkit`): the simulated machine and camera
//! as `mach-vision run` sets them up ([`Rig`]), the run path of the CLI as the reference
//! ([`reference`]), and a [`Trace`] of a program to compare a bridge's run by.

use crate::machine::{fixed_clock, Clock};
use vision_core::{Params, Timestamp, VisionModule};
use vision_driver_keyence::emulator::{DriverSource, Emulator, EmulatorHandle, NumberStyle, OutputFormat};
use vision_driver_sim::{Sim, SimMachine, World};
use vision_gcode::{MCodeHandler, RunOutcome};
use vision_math::Vector2;

use crate::{ProgramHandler, Session};

/// The clock of every test run, so both paths write the same `VisionCal_Date`.
#[must_use]
pub fn clock() -> Clock {
    fixed_clock(Timestamp::from_unix(1_800_000_000, 0))
}

/// First pound variable of the Vision block (the default `VisionPoundVarBase`).
pub const POUND_BASE: u32 = 500;
/// Variables in the Vision block (5 slots × 8 fields).
pub const POUND_COUNT: u32 = 40;

/// A simulation of the built-in world.
///
/// # Panics
/// Never for the built-in world (it validates).
#[must_use]
pub fn sim() -> Sim {
    Sim::new(World::default_world()).expect("the built-in world validates")
}

/// The parameters `mach-vision run` starts from without `--profile`: a perfect calibration of
/// the world, the simulated camera as the driver.
///
/// # Panics
/// Never for the built-in world.
#[must_use]
pub fn sim_params(sim: &Sim) -> Params {
    let mut params = sim.calibrated_params(&crate::cameras(Some(sim)).params()).expect("the built-in world calibrates");
    params.set("VisionDriver", "Sim").expect("a string parameter");
    params
}

/// Vision enabled with the simulated camera and the world's camera tool, but K never
/// calibrated (all zero).
///
/// # Panics
/// Never: the values are valid.
#[must_use]
pub fn uncalibrated_params(sim: &Sim) -> Params {
    let mut p = crate::cameras(Some(sim)).params();
    p.set("VisionEnabled", true).expect("a yes/no parameter");
    p.set("VisionDriver", "Sim").expect("a string parameter");
    p.set("VisionCameraToolNumber", i64::from(sim.world().machine.camera_tool)).expect("a tool number");
    p
}

/// A program a Vision M-code refuses.
#[derive(Debug, Clone, Copy)]
pub struct Refusal {
    /// The program (the refused M-code is its last Vision call).
    pub program: &'static str,
    /// A piece of the manual's message.
    pub says: &'static str,
    /// Run it with [`uncalibrated_params`] instead of [`sim_params`].
    pub uncalibrated: bool,
}

impl Refusal {
    /// The parameters to run it with (`None`: [`sim_params`]).
    #[must_use]
    pub fn params(&self) -> Option<Params> {
        self.uncalibrated.then(|| uncalibrated_params(&sim()))
    }
}

/// The error paths every host must handle: an NG capture (no mark in view), K not
/// calibrated, the wrong tool in the spindle.
pub const REFUSALS: [Refusal; 3] = [
    Refusal { program: "G90 G20\nT98 M6\nG0 X30 Y30\nM281\nG0 X1\nM30\n", says: "no mark", uncalibrated: false },
    Refusal { program: "G90 G20\nT98 M6\nM281\nM30\n", says: "K matrix is zero", uncalibrated: true },
    Refusal { program: "G90 G20\nT98 M6\nM280\nT1 M6\nM281 D1\nM30\n", says: "tool", uncalibrated: false },
];

/// Which camera answers the triggers in a test run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Camera {
    /// The simulated camera, called directly.
    Sim,
    /// The Keyence driver over TCP to an emulated VS camera on loopback whose results come from
    /// the simulated camera (the recommended 8-field format, fixed-width numbers).
    Keyence,
}

/// A fresh simulation of the built-in world and its camera, as `mach-vision run` sets them up.
pub struct Rig {
    /// The simulation.
    pub sim: Sim,
    /// Keeps the loopback camera alive for the run.
    pub emulator: Option<EmulatorHandle>,
}

impl Rig {
    /// The rig for `camera`, and a Vision module on it with `params` (`None`: [`sim_params`]).
    ///
    /// # Panics
    /// When the loopback emulator cannot start or `params` name another driver (test bugs).
    #[must_use]
    pub fn new(params: Option<Params>, camera: Camera) -> (Rig, VisionModule) {
        Rig::with_sim(sim(), params, camera)
    }

    /// [`Rig::new`] on `sim`'s world instead of the built-in one (a lens, another camera):
    /// `None` for `params` is [`sim_params`] of that world.
    ///
    /// # Panics
    /// As [`Rig::new`], and when `sim`'s world does not calibrate (a test bug).
    #[must_use]
    pub fn with_sim(sim: Sim, params: Option<Params>, camera: Camera) -> (Rig, VisionModule) {
        let registry = crate::cameras(Some(&sim));
        let mut params = params.unwrap_or_else(|| sim_params(&sim));
        let emulator = match camera {
            Camera::Sim => None,
            Camera::Keyence => {
                let emulator = Emulator::builder()
                    .source(DriverSource(Box::new(sim.camera())))
                    .format(OutputFormat::Full)
                    .numbers(NumberStyle::FixedWidth)
                    .bind("127.0.0.1:0")
                    .expect("a loopback port");
                params = params.with_driver_settings(&vision_driver_keyence::settings::SETTINGS);
                params.set("VisionDriver", "Keyence").expect("a string parameter");
                params.set("VisionIP", "127.0.0.1").expect("an address");
                params.set("VisionPort", i64::from(emulator.addr().port())).expect("a port");
                Some(emulator)
            }
        };
        let module = VisionModule::from_registry(params, &registry).expect("the camera's driver");
        (Rig { sim, emulator }, module)
    }

    /// Runs `program` on a fresh machine of the rig with `handler`; the machine afterwards (for
    /// [`Trace::collect`]) and how the program ended.
    ///
    /// # Panics
    /// Never for the built-in world.
    pub fn run(&self, program: &str, handler: &mut dyn MCodeHandler) -> (SimMachine, Result<RunOutcome, String>) {
        let mut machine = SimMachine::new(&self.sim).expect("the built-in machine");
        let end = machine.run_program(program, Some(handler), &mut |_: &vision_gcode::Event| {});
        (machine, end.map_err(|e| e.to_string()))
    }
}

/// One Vision M-code of a program: the G-code it emitted, or the operator's message.
#[derive(Debug, Clone, PartialEq)]
pub struct Call {
    /// The M number.
    pub mcode: u32,
    /// The emitted G-code lines, or the error message.
    pub result: Result<Vec<String>, String>,
}

/// What a program did, in the terms every path can be compared by.
#[derive(Debug, Clone, PartialEq)]
pub struct Trace {
    /// Every Vision M-code, in order.
    pub calls: Vec<Call>,
    /// How the program ended: `completed`, `ended`, or the error.
    pub end: Result<&'static str, String>,
    /// `#500`…`#539` at the end.
    pub pound: Vec<f64>,
    /// The camera tool's X/Y table offset at the end, current units (M283 writes it).
    pub camera_offset: Vector2<f64>,
    /// The machine (spindle) position at the end, world unit.
    pub position: [f64; 3],
    /// Per present fixture: the largest cut error (world unit) over its nominal marks under the
    /// last M282's G-code, measured with the tool active at the end.
    pub cut_errors: Vec<(String, f64)>,
}

impl Trace {
    /// Compares with `want`: the Vision calls (emitted G-code text, messages) and the end
    /// exactly, every number within `1e-9` (a session knows the alignment it emitted exactly,
    /// the interpreter as the G-code's fixed decimals, so a capture in the aligned frame can
    /// differ in the last bits).
    ///
    /// # Panics
    /// On the first difference, showing both.
    pub fn assert_matches(&self, want: &Trace) {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 || (a.is_nan() && b.is_nan());
        assert_eq!(self.calls, want.calls);
        assert_eq!(self.end, want.end);
        let numbers = |t: &Trace| {
            let mut v = t.pound.clone();
            v.extend([t.camera_offset.x, t.camera_offset.y]);
            v.extend(t.position);
            v.extend(t.cut_errors.iter().map(|c| c.1));
            v
        };
        let (got, wanted) = (numbers(self), numbers(want));
        assert!(
            got.len() == wanted.len() && got.iter().zip(&wanted).all(|(a, b)| close(*a, *b)),
            "got {self:?}\nwant {want:?}"
        );
        assert!(self.cut_errors.iter().zip(&want.cut_errors).all(|(a, b)| a.0 == b.0));
    }

    /// The trace of a program that ended with `end` on `machine`, Vision calls `calls`.
    #[must_use]
    pub fn collect(machine: &SimMachine, calls: Vec<Call>, end: Result<RunOutcome, String>) -> Trace {
        let sim = machine.sim();
        let world = sim.world();
        let unit = world.length_unit();
        let pound = (POUND_BASE..POUND_BASE + POUND_COUNT).map(|n| machine.interpreter().param(n)).collect();
        let camera_offset = machine
            .interpreter()
            .tool_offset(world.machine.camera_tool)
            .map_or_else(Vector2::zeros, |o| Vector2::new(o.x, o.y));
        let p = machine.interpreter().machine_position();
        let last_m282 = calls.iter().rev().find(|c| c.mcode == 282).and_then(|c| c.result.clone().ok());
        let cut_errors = last_m282.map_or_else(Vec::new, |gcode| {
            world
                .fixtures
                .iter()
                .filter(|f| f.present)
                .map(|f| {
                    let worst = f
                        .nominal_marks(unit)
                        .into_iter()
                        .map(|n| machine.cut_error(&gcode, &f.name, n).unwrap_or(f64::NAN))
                        .fold(0.0, f64::max);
                    (f.name.clone(), worst)
                })
                .collect()
        });
        let end = end.map(|o| match o {
            RunOutcome::Completed { .. } => "completed",
            RunOutcome::Ended { .. } => "ended",
        });
        Trace { calls, end, pound, camera_offset, position: [p.x, p.y, p.z], cut_errors }
    }
}

/// `program` as `mach-vision run` runs it (a [`ProgramHandler`] through a [`Session`] on the
/// simulated machine) on a fresh [`Rig`].
#[must_use]
pub fn reference(program: &str, params: Option<Params>, camera: Camera) -> Trace {
    let (rig, module) = Rig::new(params, camera);
    let controller = rig.sim.world().machine.controller();
    let mut handler = ProgramHandler::new(Session::new(module), controller, clock());
    let (machine, end) = rig.run(program, &mut handler);
    let calls = handler
        .take_records()
        .into_iter()
        .map(|r| Call { mcode: r.mcode, result: r.result.map(|o| o.gcode().to_vec()).map_err(|e| e.to_string()) })
        .collect();
    Trace::collect(&machine, calls, end)
}

/// The text of example program `name` (e.g. `04-rectangle-fit.nc`).
///
/// # Panics
/// When the file is missing (a test bug).
#[must_use]
pub fn example(name: &str) -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/programs").join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}
