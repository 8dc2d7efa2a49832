//! Property tests: random G52/G68/G51/G54–G59/G92/tool-offset combinations put the machine
//! exactly where the hand-computed chain says.
//!
//! Numbers go into the program with Rust's shortest round-trip formatting, so the interpreter
//! reads the very same `f64`s; the expected position is computed in the documented order
//! (`docs/gcode-interpreter.md`, "The frame chain"), so equality is exact.

use proptest::prelude::*;
use vision_core::controller::{linuxcnc, LinuxCnc};
use vision_gcode::{Interpreter, InterpreterConfig, Tool, Xyz};
use vision_math::{AlignmentChain, LengthUnit, Point2, Vector2};

fn xyz(range: f64) -> impl Strategy<Value = Xyz> {
    (-range..range, -range..range, -range..range).prop_map(|(x, y, z)| Xyz::new(x, y, z))
}

fn factor() -> impl Strategy<Value = f64> {
    (0.5..2.0f64, any::<bool>()).prop_map(|(f, mirror)| if mirror { -f } else { f })
}

#[derive(Debug, Clone)]
struct Setup {
    system: u32,
    work: Xyz,
    g92: Xyz,
    tool: Xyz,
    shift: Xyz,
    center: Point2<f64>,
    rotation: f64,
    scale: (f64, f64),
}

fn setup() -> impl Strategy<Value = Setup> {
    (
        1u32..=6,
        xyz(50.0),
        xyz(5.0),
        xyz(3.0),
        xyz(2.0),
        (-10.0..10.0f64, -10.0..10.0f64),
        -180.0..180.0f64,
        factor(),
        factor(),
    )
        .prop_map(|(system, work, g92, tool, shift, (cx, cy), rotation, sx, sy)| Setup {
            system,
            work,
            g92,
            tool,
            shift,
            center: Point2::new(cx, cy),
            rotation,
            scale: (sx, sy),
        })
}

impl Setup {
    fn chain(&self) -> AlignmentChain {
        AlignmentChain {
            scale: Vector2::new(self.scale.0, self.scale.1),
            center: self.center,
            rotation_deg: self.rotation,
            shift: Vector2::new(self.shift.x, self.shift.y),
        }
    }

    /// The program that establishes the setup (machine and program in inches).
    fn program(&self) -> String {
        let (s, w, g, c) = (self.shift, self.work, self.g92, self.center);
        format!(
            "G20 G90\nG10 L2 P{} X{} Y{} Z{}\nG{}\n#5211={} #5212={} #5213={}\nT7 M6\nG52 X{} Y{} Z{}\nG68 X{} Y{} R{}\nG51 X{} Y{}\n",
            self.system,
            w.x,
            w.y,
            w.z,
            53 + self.system,
            g.x,
            g.y,
            g.z,
            s.x,
            s.y,
            s.z,
            c.x,
            c.y,
            self.rotation,
            self.scale.0,
            self.scale.1
        )
    }

    /// Where commanding `p` puts the spindle, by hand.
    fn machine(&self, p: Xyz) -> Xyz {
        let w = self.chain().apply(Point2::new(p.x, p.y));
        Xyz::new(
            w.x + ((self.work.x + self.g92.x) - self.tool.x),
            w.y + ((self.work.y + self.g92.y) - self.tool.y),
            (p.z + self.shift.z) + ((self.work.z + self.g92.z) + self.tool.z),
        )
    }

    fn interpreter(&self, unit: LengthUnit) -> Interpreter {
        let mut interp = Interpreter::new(InterpreterConfig::new(unit));
        let k = LengthUnit::Inch.factor_to(unit);
        interp.set_tool(7, Tool { offset: self.tool.scaled(k), outputs: None });
        interp
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn moves_land_exactly_where_the_chain_says(
        s in setup(),
        start in xyz(100.0),
        steps in prop::collection::vec(xyz(10.0), 0..4),
    ) {
        let mut interp = s.interpreter(LengthUnit::Inch);
        let mut program = s.program();
        program.push_str(&format!("G0 X{} Y{} Z{}\nG91\n", start.x, start.y, start.z));
        for d in &steps {
            program.push_str(&format!("G1 X{} Y{} Z{} F100\n", d.x, d.y, d.z));
        }
        let mut ends = Vec::new();
        interp.run(&program, None, &mut |e: &vision_gcode::Event| ends.extend(e.end())).expect("runs");
        // G91 increments are increments of the program point.
        let mut p = start;
        let mut expected = vec![s.machine(p)];
        for d in &steps {
            p = p + *d;
            expected.push(s.machine(p));
        }
        prop_assert_eq!(&ends, &expected);
        prop_assert_eq!(interp.program_position(), p);
        let w = s.chain().apply(Point2::new(p.x, p.y));
        prop_assert_eq!(interp.work_position(), Xyz::new(w.x, w.y, p.z + s.shift.z));
        prop_assert_eq!(interp.active_alignment(), Some(s.chain()));
    }

    #[test]
    fn a_millimetre_program_lands_where_the_inch_program_does(s in setup(), p in xyz(100.0)) {
        let mut inch = s.interpreter(LengthUnit::Inch);
        inch.run(&format!("{}G0 X{} Y{} Z{}", s.program(), p.x, p.y, p.z), None, &mut Vec::new()).expect("inch");
        // The same setup written in millimetres, on a millimetre machine.
        let mut mm = s.interpreter(LengthUnit::Millimetre);
        let scaled = Setup {
            work: s.work.scaled(25.4),
            g92: s.g92.scaled(25.4),
            shift: s.shift.scaled(25.4),
            center: Point2::new(s.center.x * 25.4, s.center.y * 25.4),
            ..s.clone()
        };
        let p_mm = p.scaled(25.4);
        mm.run(&format!("{}G0 X{} Y{} Z{}", scaled.program().replace("G20", "G21"), p_mm.x, p_mm.y, p_mm.z), None, &mut Vec::new())
            .expect("mm");
        let a = inch.machine_position().scaled(25.4);
        let b = mm.machine_position();
        prop_assert!((a - b).norm() <= 1e-9 * (1.0 + a.norm()), "{:?} vs {:?}", a, b);
    }

    #[test]
    fn g92_makes_the_point_read_the_values_and_moves_stay_in_the_frame(
        s in setup(),
        start in xyz(50.0),
        v in xyz(50.0),
        d in xyz(5.0),
    ) {
        let mut interp = s.interpreter(LengthUnit::Inch);
        interp.run(&format!("{}G0 X{} Y{} Z{}", s.program(), start.x, start.y, start.z), None, &mut Vec::new()).expect("setup");
        let before = interp.machine_position();
        interp.run(&format!("G92 X{} Y{} Z{}", v.x, v.y, v.z), None, &mut Vec::new()).expect("G92");
        prop_assert_eq!(interp.program_position(), v);
        prop_assert_eq!(interp.machine_position(), before);
        // Commanding the same point does not move the machine (beyond rounding).
        interp.run(&format!("G0 X{} Y{} Z{}", v.x, v.y, v.z), None, &mut Vec::new()).expect("move");
        prop_assert!((interp.machine_position() - before).norm() <= 1e-9 * (1.0 + before.norm()));
        // A step in the program frame is the chain's linear part applied to it.
        let q = v + d;
        interp.run(&format!("G0 X{} Y{} Z{}", q.x, q.y, q.z), None, &mut Vec::new()).expect("move");
        let linear = s.chain().rotation_matrix() * Vector2::new(s.scale.0 * d.x, s.scale.1 * d.y);
        let moved = interp.machine_position() - before;
        prop_assert!((moved - Xyz::new(linear.x, linear.y, d.z)).norm() <= 1e-9 * (1.0 + before.norm()));
    }
}

proptest! {
    /// LinuxCNC's canon (emccanon.cc, `rotate_and_offset_pos`): `machine = g5x + R(p + g52)`,
    /// written out here independently of the interpreter's placement; G53 ignores all of it.
    #[test]
    fn linuxcnc_rotation_applies_g52_before_rotating(
        system in 1u32..=6,
        work in xyz(50.0),
        g52 in xyz(5.0),
        degrees in -360.0..360.0f64,
        p in xyz(20.0),
    ) {
        let config = InterpreterConfig { dialect: vision_gcode::Dialect::LinuxCnc, ..InterpreterConfig::new(LengthUnit::Millimetre) };
        let mut interp = Interpreter::new(config);
        let program = format!(
            "G21\nG10 L2 P{system} X{} Y{} Z{} R{degrees}\nG{}\nG52 X{} Y{} Z{}\nG0 X{} Y{} Z{}\nM2",
            work.x, work.y, work.z, 53 + system, g52.x, g52.y, g52.z, p.x, p.y, p.z
        );
        let mut events = Vec::new();
        interp.run(&program, None, &mut events).map_err(|e| TestCaseError::fail(e.to_string()))?;
        let (s, c) = degrees.to_radians().sin_cos();
        let (qx, qy) = (p.x + g52.x, p.y + g52.y);
        let want = Xyz::new(work.x + (c * qx - s * qy), work.y + (s * qx + c * qy), work.z + p.z + g52.z);
        prop_assert!((interp.machine_position() - want).norm() < 1e-9, "{:?} != {:?}", interp.machine_position(), want);
        interp.run("G53 G0 X1 Y2\nM2", None, &mut events).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert_eq!(interp.machine_position().xy(), Point2::new(1.0, 2.0));
    }
}

proptest! {
    /// M282 on LinuxCNC emits `G10 L2 P0 R…` and `G52 X… Y…` (vision-math's
    /// `LinuxCncAlignment`): run by the interpreter under LinuxCNC's rules they put every program
    /// point where the fit's chain does, on a system with its own origin and base rotation; a
    /// second M282 replaces the first, and the cancel lines restore the base rotation.
    #[test]
    fn m282_linuxcnc_lines_execute_the_chain(
        origin in xyz(50.0),
        base in -30.0..30.0f64,
        theta in -5.0..5.0f64,
        (cx, cy) in (-10.0..10.0f64, -10.0..10.0f64),
        (tx, ty) in (-1.0..1.0f64, -1.0..1.0f64),
        p in xyz(20.0),
    ) {
        use vision_math::linuxcnc::LinuxCncAlignment;
        let config = InterpreterConfig { dialect: vision_gcode::Dialect::LinuxCnc, ..InterpreterConfig::new(LengthUnit::Millimetre) };
        let mut interp = Interpreter::new(config);
        let chain = AlignmentChain {
            scale: Vector2::new(1.0, 1.0),
            center: Point2::new(cx, cy),
            rotation_deg: theta,
            shift: Vector2::new(tx, ty),
        };
        let fail = |e: vision_math::MathError| TestCaseError::fail(e.to_string());
        let text = |commands: &[vision_core::MachineCommand]| vision_mcode::lines(&LinuxCnc, commands).expect("text");
        let first = LinuxCncAlignment::from_chain(&AlignmentChain { rotation_deg: -theta, ..chain }, base, 0.0)
            .and_then(|a| linuxcnc::alignment_commands(&a))
            .map_err(fail)?;
        let first = text(&first);
        let alignment = LinuxCncAlignment::from_chain(&chain, base, 0.0).map_err(fail)?;
        let lines = text(&linuxcnc::alignment_commands(&alignment).map_err(fail)?);
        let cancel = text(&linuxcnc::cancel_commands(alignment.base_rotation_deg).map_err(fail)?);
        let setup = format!("G21\nG10 L2 P1 X{} Y{} Z{} R{base}\nG54", origin.x, origin.y, origin.z);
        let program = format!("{setup}\n{}\n{}\n{}\n{}\nG0 X{} Y{} Z{}\n%", first[0], first[1], lines[0], lines[1], p.x, p.y, p.z);
        let mut events = Vec::new();
        interp.run(&format!("%\n{program}"), None, &mut events).map_err(|e| TestCaseError::fail(e.to_string()))?;
        // Where the unaligned program would put chain.apply(p): the base-rotated system.
        let a = chain.apply(p.xy());
        let (s, c) = base.to_radians().sin_cos();
        let want = Xyz::new(origin.x + c * a.x - s * a.y, origin.y + s * a.x + c * a.y, origin.z + p.z);
        // The lines carry 7 decimals of position and 9 of angle.
        prop_assert!((interp.machine_position() - want).norm() < 1e-5, "{:?} != {:?}", interp.machine_position(), want);
        let text = format!("%\n{}\n{}\nG0 X{} Y{} Z{}\n%", cancel[0], cancel[1], p.x, p.y, p.z);
        interp.run(&text, None, &mut events).map_err(|e| TestCaseError::fail(e.to_string()))?;
        let want = Xyz::new(origin.x + c * p.x - s * p.y, origin.y + s * p.x + c * p.y, origin.z + p.z);
        prop_assert!((interp.machine_position() - want).norm() < 1e-5, "{:?} != {:?}", interp.machine_position(), want);
    }
}
