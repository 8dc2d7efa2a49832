//! The G-code CAM post-processors and LinuxCNC programs use, checked against LinuxCNC's own
//! interpreter: every expected position below is what `rs274` (LinuxCNC 2.9) printed for the
//! same program (`tools/linuxcnc-oracle`), with its offsets applied.

#![expect(clippy::float_cmp, reason = "tests compare exact values")]

use vision_gcode::{
    ArcDirection, Coolant, Dialect, Event, GcodeError, Interpreter, InterpreterConfig, Rate, RunOutcome, RunProblem,
    SpindleCommand, SyntaxProblem, Tool, ToolTable, Xyz,
};
use vision_math::LengthUnit;

use crate::common;
use common::moves;

fn machine(unit: LengthUnit) -> Interpreter {
    let tools = ToolTable::numbered(1, 20).with(1, Tool { offset: Xyz::new(0.0, 0.0, 0.5), outputs: None });
    Interpreter::new(InterpreterConfig { tools, ..InterpreterConfig::new(unit) })
}

fn run(interp: &mut Interpreter, program: &str) -> Vec<Event> {
    let mut events = Vec::new();
    interp.run(program, None, &mut events).unwrap_or_else(|e| panic!("{e}\n{program}"));
    events
}

fn problem(interp: &mut Interpreter, program: &str) -> RunProblem {
    match interp.run(program, None, &mut Vec::new()) {
        Err(GcodeError::Run { problem, .. }) => problem,
        other => panic!("expected a run error for {program:?}, got {other:?}"),
    }
}

fn assert_moves(got: &[(bool, [f64; 3])], want: &[(bool, [f64; 3])]) {
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (g, w) in got.iter().zip(want) {
        assert_eq!(g.0, w.0, "{got:?}");
        assert!((0..3).all(|i| (g.1[i] - w.1[i]).abs() < 1e-9), "{g:?} != {w:?}");
    }
}

const R: bool = true;
const F: bool = false;

#[test]
fn g81_and_g83_expand_as_linuxcnc_does() {
    let mut interp = machine(LengthUnit::Millimetre);
    let events = run(&mut interp, "G21 G0 Z5\nG81 X1 Y1 Z-2 R1 F100\nX2\nG0 Z10\nG83 X3 Z-2.5 R1 Q1");
    #[rustfmt::skip]
    let want = [
        (R, [0.0, 0.0, 5.0]),
        (R, [1.0, 1.0, 5.0]), (R, [1.0, 1.0, 1.0]), (F, [1.0, 1.0, -2.0]), (R, [1.0, 1.0, 1.0]),
        (R, [2.0, 1.0, 1.0]), (F, [2.0, 1.0, -2.0]), (R, [2.0, 1.0, 1.0]),
        (R, [2.0, 1.0, 10.0]),
        (R, [3.0, 1.0, 10.0]), (R, [3.0, 1.0, 1.0]),
        (F, [3.0, 1.0, 0.0]), (R, [3.0, 1.0, 1.0]), (R, [3.0, 1.0, 0.254]),
        (F, [3.0, 1.0, -1.0]), (R, [3.0, 1.0, 1.0]), (R, [3.0, 1.0, -0.746]),
        (F, [3.0, 1.0, -2.0]), (R, [3.0, 1.0, 1.0]), (R, [3.0, 1.0, -1.746]),
        (F, [3.0, 1.0, -2.5]), (R, [3.0, 1.0, 1.0]),
    ];
    assert_moves(&moves(&events), &want);
}

#[test]
fn g73_with_g98_and_incremental_repeats() {
    let mut interp = machine(LengthUnit::Millimetre);
    let events = run(&mut interp, "G21 G0 Z5\nG98 G73 X3 Z-2.5 R1 Q1 F10\nG91 X1 Z-1 R-1 L2");
    #[rustfmt::skip]
    let want = [
        (R, [0.0, 0.0, 5.0]),
        (R, [3.0, 0.0, 5.0]), (R, [3.0, 0.0, 1.0]),
        (F, [3.0, 0.0, 0.0]), (R, [3.0, 0.0, 0.254]), (F, [3.0, 0.0, -1.0]), (R, [3.0, 0.0, -0.746]),
        (F, [3.0, 0.0, -2.0]), (R, [3.0, 0.0, -1.746]), (F, [3.0, 0.0, -2.5]), (R, [3.0, 0.0, 5.0]),
        (R, [4.0, 0.0, 5.0]), (R, [4.0, 0.0, 4.0]), (F, [4.0, 0.0, 3.0]), (R, [4.0, 0.0, 5.0]),
        (R, [5.0, 0.0, 5.0]), (R, [5.0, 0.0, 4.0]), (F, [5.0, 0.0, 3.0]), (R, [5.0, 0.0, 5.0]),
    ];
    assert_moves(&moves(&events), &want);
    // The cycle's own moves stop exactly; the program's path mode is back afterwards.
    assert!(matches!(events.last(), Some(Event::Linear(m)) if m.path == vision_gcode::PathMode::ExactStop));
    assert_eq!(interp.path_mode(), vision_gcode::PathMode::Blend { tolerance: None });
}

#[test]
fn cycles_refuse_what_linuxcnc_refuses() {
    let mut interp = machine(LengthUnit::Inch);
    assert!(matches!(problem(&mut interp, "F10 G81 X1 Z-1"), RunProblem::MissingWord { letter: 'R', .. }));
    assert!(matches!(problem(&mut interp, "F10 G81 X1 R0.1"), RunProblem::MissingWord { letter: 'Z', .. }));
    assert!(matches!(problem(&mut interp, "F10 G83 X1 R0.1 Z-1"), RunProblem::MissingWord { letter: 'Q', .. }));
    assert!(matches!(problem(&mut interp, "F10 G82 X1 R0.1 Z-1"), RunProblem::MissingWord { letter: 'P', .. }));
    assert!(matches!(problem(&mut interp, "F10 G81 X1 R-1 Z0"), RunProblem::CycleRBelowZ { code: "G81" }));
    assert!(matches!(problem(&mut interp, "F10 G81 X1 R0 Z-1 L0"), RunProblem::OutOfRange { letter: 'L', .. }));
    assert!(matches!(problem(&mut interp, "F10 G18 G81 X1 R0 Z-1"), RunProblem::Unsupported { .. }));
    assert_eq!(problem(&mut interp, "G80 X1"), RunProblem::G80AxisWords);
    // G82 dwells at the bottom; G89 also feeds out.
    let events = run(&mut interp, "F10 G89 X1 R0.1 Z-1 P0.25");
    assert!(events.iter().any(|e| matches!(e, Event::Dwell { seconds, .. } if *seconds == 0.25)));
    assert!(matches!(events.last(), Some(Event::Linear(m)) if matches!(m.rate, Rate::Feed(_))));
}

#[test]
fn tool_length_offsets_and_machine_coordinates() {
    let mut interp = machine(LengthUnit::Inch);
    // rs274: G53 G0 Z0 X0 prints (-1, -2, -3.5) before G54 (1, 2, 3) and a 0.5 tool length.
    let events = run(&mut interp, "G20 G10 L2 P1 X1 Y2 Z3\nG43 H1\nG53 G0 Z0 X0\nG0 X0");
    assert_moves(&moves(&events), &[(R, [0.0, 0.0, 0.0]), (R, [1.0, 0.0, 0.0])]);
    assert_eq!(interp.program_position(), Xyz::new(0.0, -2.0, -3.5));
    assert_eq!(problem(&mut interp, "G91 G53 G0 X1"), RunProblem::G53Form { hint: "switch to G90 first" });
    assert!(matches!(problem(&mut interp, "G2 G53 X1 I1"), RunProblem::G53Form { .. }));

    // G43 (the loaded tool), G43.1 (a length given), G49 (none): the Z the next move reaches.
    let mut interp = machine(LengthUnit::Inch);
    let events = run(&mut interp, "G20 T1 M6 G49\nG0 X1\nG43\nG0 X2 Z0\nG43.1 Z0.2\nG0 X3 Z0\nG49\nG0 X4 Z0");
    assert_moves(
        &moves(&events),
        &[(R, [1.0, 0.0, 0.0]), (R, [2.0, 0.0, 0.5]), (R, [3.0, 0.0, 0.2]), (R, [4.0, 0.0, 0.0])],
    );
    assert_eq!(interp.param(5403), 0.0);
}

#[test]
fn arcs_follow_linuxcnc_rules() {
    // Full circle from centre words alone; R with P turns (rs274: centre (0.5, -0.866), -2).
    let mut interp = machine(LengthUnit::Inch);
    let events = run(&mut interp, "G20 F10\nG2 I1\nG2 X1 R1 P2");
    let arcs: Vec<_> = events.iter().filter_map(|e| if let Event::Arc(a) = e { Some(*a) } else { None }).collect();
    assert_eq!(arcs.len(), 2);
    assert_eq!((arcs[0].end, arcs[0].center), (Xyz::ZERO, Xyz::new(1.0, 0.0, 0.0)));
    assert!((arcs[0].angle - std::f64::consts::TAU).abs() < 1e-12);
    assert_eq!((arcs[1].direction, arcs[1].extra_turns()), (ArcDirection::Clockwise, 1));
    assert!((arcs[1].center.x - 0.5).abs() < 1e-12 && (arcs[1].center.y + 0.75_f64.sqrt()).abs() < 1e-12);

    // Radius difference: within 0.1 % passes even beyond the absolute tolerance; beyond both,
    // refused (rs274 accepts 0.02 mm of 5 mm, refuses 0.03 mm and 0.02 in of 5 in).
    let mut mm = machine(LengthUnit::Millimetre);
    run(&mut mm, "G21 F10\nG2 X10.02 Y0 I5 J0");
    run(&mut mm, "G0 X0 Y0\nG2 X2000.5 I1000 J0");
    assert!(matches!(problem(&mut mm, "G0 X0 Y0\nG2 X10.03 Y0 I5 J0"), RunProblem::ArcRadiusMismatch { .. }));
    assert!(matches!(problem(&mut mm, "G20 G0 X0 Y0\nG2 X10.02 Y0 I5 J0"), RunProblem::ArcRadiusMismatch { .. }));
    // Never more than 100 times the tolerance (0.2828 in), even on a huge arc.
    let mut inch = machine(LengthUnit::Inch);
    assert!(matches!(problem(&mut inch, "G20 F10 G2 X1000.3 I500 J0"), RunProblem::ArcRadiusMismatch { .. }));
    run(&mut inch, "G20 F10 G2 X1000.2 I500 J0");
    // Radius too small: below 0.00005 in (rs274: "Zero-radius arc"), named as such.
    let mut inch = machine(LengthUnit::Inch);
    assert_eq!(problem(&mut inch, "G20 F10 G2 X0.00008 I0.00004 J0"), RunProblem::ArcZeroRadius);
    run(&mut inch, "G20 F10 G2 X0.0021 I0.001 J0");
    assert_eq!(problem(&mut mm, "G21 G0 X0 Y0\nG2 X0.002 I0.001 J0"), RunProblem::ArcZeroRadius);
    assert!(RunProblem::ArcZeroRadius.to_string().contains("radius too small"));
}

#[test]
fn cam_preamble_spindle_and_coolant() {
    let mut interp = machine(LengthUnit::Inch);
    let program = "%\nG17 G40 G49 G80 G90 G20 G94 G97\nM3 S12000 M8\nG64 P0.001 Q0.001\nM7 M8\nM9 M5\n%\nG0 X5";
    let mut events = Vec::new();
    let outcome = interp.run(program, None, &mut events).expect("runs");
    // The closing `%` ends the program: G0 X5 never runs.
    assert_eq!(outcome, RunOutcome::Completed { lines: 7 });
    assert!(events.iter().all(|e| !matches!(e, Event::Linear(_))));
    let kinds: Vec<String> = events
        .iter()
        .map(|e| match e {
            Event::Spindle { command, speed, .. } => format!("{} {speed:?}", command.gcode()),
            Event::Coolant { coolant, .. } => coolant.gcode().to_string(),
            other => format!("{other:?}"),
        })
        .collect();
    assert_eq!(kinds, ["M3 Some(12000.0)", "M8", "M7", "M8", "M5 Some(12000.0)", "M9"]);
    assert_eq!(problem(&mut interp, "M8 M9"), RunProblem::ModalConflict { first: "M8".into(), second: "M9".into() });
    // With a tool loaded, M3 still drives that tool's outputs (seed 002).
    let events = run(&mut interp, "T1 M6\nM3");
    assert!(matches!(&events[1], Event::Output(o) if o.tool == Some(1) && o.command == SpindleCommand::Clockwise));
    assert!(!matches!(events[1], Event::Coolant { coolant: Coolant::Off, .. }));
}

#[test]
fn motion_codes_alone_move_as_in_linuxcnc() {
    // rs274 prints a traverse to the current point for a bare `G0`, and G28's first leg.
    let mut interp = machine(LengthUnit::Inch);
    let events = run(&mut interp, "G0 X1\nG0\nG28");
    assert_moves(&moves(&events), &[(R, [1.0, 0.0, 0.0]), (R, [1.0, 0.0, 0.0]), (R, [1.0, 0.0, 0.0]), (R, [0.0; 3])]);
    // `G80 G0` (a common safety line) is one motion code: G0 wins.
    run(&mut interp, "G80 G0 X2");
    assert_eq!(interp.machine_position().x, 2.0);
    // Block delete off (default): the `/` is ignored; on: the line is skipped.
    run(&mut interp, "/G0 X3");
    assert_eq!(interp.machine_position().x, 3.0);
    let mut skip = Interpreter::new(InterpreterConfig { block_delete: true, ..InterpreterConfig::default() });
    run(&mut skip, "/N10 G0 X3\nG0 Y1");
    assert_eq!(skip.machine_position(), Xyz::new(0.0, 1.0, 0.0));
}

#[test]
fn unsupported_features_are_named() {
    let mut interp = machine(LengthUnit::Inch);
    for (text, feature) in [
        ("G7", "lathe"),
        ("G33 Z1 K0.1", "spindle-synchronised"),
        ("G76 P0.1", "threading"),
        ("G96 S100", "constant surface speed"),
        ("G5.2 X1 Y1", "NURBS"),
        ("G6.2", "NURBS"),
        ("G41 D1", "cutter radius compensation"),
        ("G38.2 Z-1", "probing"),
        ("G93", "inverse-time"),
        ("M66 P0", "HAL"),
        ("G10 L2 P1 R30", "rotation"),
    ] {
        let message = problem(&mut interp, text).to_string();
        assert!(message.contains(feature), "{text}: {message}");
    }
}

#[test]
fn dialects_differ_where_the_controllers_do() {
    let with = |dialect| {
        let tools = ToolTable::numbered(1, 20).with(1, Tool { offset: Xyz::new(0.0, 0.0, 0.5), outputs: None });
        Interpreter::new(InterpreterConfig { tools, dialect, ..InterpreterConfig::default() })
    };
    // LinuxCNC refuses a file that ends without M2/M30 or a closing `%` (as rs274 does); the
    // snippets below are delimited so that the program end's resets do not hide the state.
    let delimited = |text: &str| format!("%\n{text}\n%");
    assert_eq!(problem(&mut with(Dialect::LinuxCnc), "G0 X1\nG0 X2"), RunProblem::NoProgramEnd);
    run(&mut with(Dialect::Mach4), "G0 X1\nG0 X2");
    run(&mut with(Dialect::LinuxCnc), "G0 X1\nM2");
    // G92 on some axes: seed 002 zeroes the others, Mach4 and LinuxCNC keep them.
    for (dialect, y) in [(Dialect::MachineMotion, 0.0), (Dialect::Mach4, -1.0), (Dialect::LinuxCnc, -1.0)] {
        let mut interp = with(dialect);
        run(&mut interp, &delimited("G0 X1 Y1\nG92 X0 Y0\nG92 X5"));
        assert_eq!(interp.g92_offset().y, -y, "{dialect:?}");
    }
    // Tool length: from M6 in seed 002, from G43 on Mach4 and LinuxCNC (Mach4's X/Y offset is
    // the loaded tool's, from M6: `mach4_applies_the_tool_xy_at_m6_and_the_length_at_g43`).
    for (dialect, z) in [(Dialect::MachineMotion, 0.5), (Dialect::Mach4, 0.0), (Dialect::LinuxCnc, 0.0)] {
        let mut interp = with(dialect);
        run(&mut interp, &delimited("T1 M6\nG0 Z0"));
        assert_eq!(interp.machine_position().z, z, "{dialect:?}");
        run(&mut interp, &delimited("G43\nG0 Z0"));
        assert_eq!(interp.machine_position().z, 0.5, "{dialect:?}");
    }
    // Comments: seed 002 nests; Mach4 nests where the line balances the comment, else ends it
    // at its first `)`; LinuxCNC refuses a `(` inside a comment, as rs274 does
    // (`close_and_downcase`: "Nested comment found").
    for dialect in [Dialect::MachineMotion, Dialect::Mach4] {
        let mut interp = with(dialect);
        run(&mut interp, "G0 X1 (a (b) c) Y2");
        assert_eq!(interp.machine_position().y, 2.0, "{dialect:?}");
    }
    let mut mach4 = with(Dialect::Mach4);
    run(&mut mach4, "G0 X1 (a (b) Y3");
    assert_eq!(mach4.machine_position().y, 3.0);
    let err = mach4.run("G0 X1 (a (b) c", None, &mut Vec::new()).expect_err("c has no value");
    assert!(
        matches!(
            err,
            GcodeError::Syntax { column: 14, problem: SyntaxProblem::CommentEndedEarly { open: 7, close: 12, .. }, .. }
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("the comment opened at column 7 ended at the `)` at column 12"), "{err}");
    let err = with(Dialect::LinuxCnc).run(&delimited("G0 X1 (a (b c) Y2"), None, &mut Vec::new()).expect_err("nested");
    assert!(
        matches!(err, GcodeError::Syntax { problem: SyntaxProblem::NestedComment { open: 7, inner: 10 }, .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("nested comments"), "{err}");
    // Grbl ends a comment at its first `)`, a `(` inside included.
    let mut grbl = with(Dialect::Grbl);
    run(&mut grbl, "G0 X1 (a (b) Y3");
    assert_eq!(grbl.machine_position().y, 3.0);
    assert!(grbl.run("G0 X1 (a (b) c", None, &mut Vec::new()).is_err(), "c has no value");
    // G68/G51 are Mach codes.
    run(&mut with(Dialect::Mach4), "G68 X0 Y0 R30\nG69");
    let refused = problem(&mut with(Dialect::LinuxCnc), "G68 X0 Y0 R30");
    assert_eq!(
        refused.to_string(),
        "G68 is not supported: scaling and rotation (G50/G51, G68/G69: Mach and Fanuc codes LinuxCNC does not have) is not available on this machine; remove it from the program (or post-process for a 3-axis mill)"
    );
    assert_eq!(Dialect::LinuxCnc.name(), "linuxcnc");
    // Grbl has none of G68, G51 and G52, and the refusal names it; G52 stays elsewhere.
    for line in ["G68 X0 Y0 R30", "G51 X2 Y2", "G52 X1 Y1"] {
        let refused = problem(&mut with(Dialect::Grbl), line).to_string();
        assert!(refused.contains("codes Grbl does not have (error:20 on the firmware)"), "{line}: {refused}");
        assert!(refused.starts_with(&line[..3]), "{refused}");
    }
    run(&mut with(Dialect::Mach4), "G52 X1 Y1");
}

#[test]
fn polar_words_and_rotary_axes_are_named_not_misread() {
    let mut interp = Interpreter::new(InterpreterConfig { dialect: Dialect::LinuxCnc, ..InterpreterConfig::default() });
    for (text, why) in [
        ("G1 @1 X1 F10", "X or Y"),
        ("G18 G0 @1 ^30", "G17"),
        ("G0 @1", "angle"),
        ("G91 G0 ^10", "origin"),
        ("G53 G0 @1 ^10", "G53"),
        ("G81 @1 X1 Z-1 R1 F10", "X or Y"),
    ] {
        let message = problem(&mut interp, text).to_string();
        assert!(message.contains("polar") && message.contains(why), "{text}: {message}");
    }
    let mut mach4 = Interpreter::new(InterpreterConfig { dialect: Dialect::Mach4, ..InterpreterConfig::default() });
    assert!(problem(&mut mach4, "G0 @1 ^30").to_string().contains("LinuxCNC feature"));
    // Under LinuxCNC a lone A beside M3 is the rotary axis, not seed 002's output device.
    assert_eq!(problem(&mut interp, "G0 A90 M3"), RunProblem::AxisNotSupported { letter: 'A' });
    let mut seed = machine(LengthUnit::Inch);
    assert_eq!(problem(&mut seed, "M3 A1"), RunProblem::OutputForm { code: "M3" });
}

fn linuxcnc_mm() -> Interpreter {
    Interpreter::new(InterpreterConfig { dialect: Dialect::LinuxCnc, ..InterpreterConfig::new(LengthUnit::Millimetre) })
}

#[test]
fn g10_l2_rotation_rotates_the_system_about_its_origin_as_rs274_does() {
    // Every end point and the arc centre are what rs274 printed, its offsets applied
    // (compare.py on this program: agree). Line 6 changes the rotation with a G52 offset in
    // force: rs274's current point leaves G52 out there, and the G91 move starts from it.
    let program = "G21 G90 G17 F100
G10 L2 P1 X-2 Y1 R60
G0 X1 Y0 Z0
G52 X1 Y0.5
G0 X0 Y0
G10 L2 P0 R90
G91 G1 X1
G90 G3 X0 Y1 I-1 J0
G53 G0 X0 Y0
G10 L2 P2 X3 R-30
G55 G0 X1 Y0
G54 G0 X0 Y0
M2";
    let mut interp = linuxcnc_mm();
    let events = run(&mut interp, program);
    #[rustfmt::skip]
    let want = [
        (R, [-1.5, 1.866_025, 0.0]), (R, [-1.933_013, 2.116_025, 0.0]), (F, [-2.5, 3.0, 0.0]),
        (R, [0.0, 0.0, 0.0]), (R, [4.982_051, -0.566_987, 0.0]), (R, [-2.5, 2.0, 0.0]),
    ];
    let got = moves(&events);
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (g, w) in got.iter().zip(&want) {
        assert!(g.0 == w.0 && (0..3).all(|i| (g.1[i] - w.1[i]).abs() < 1e-6), "{g:?} != {w:?}");
    }
    let arc = events.iter().find_map(|e| if let Event::Arc(a) = e { Some(a) } else { None }).expect("an arc");
    assert!((arc.end - Xyz::new(-3.5, 2.0, 0.0)).norm() < 1e-9, "{arc:?}");
    assert!((arc.center.xy() - Xyz::new(-2.5, 2.0, 0.0).xy()).norm() < 1e-9, "{arc:?}");
    assert_eq!(arc.direction, ArcDirection::CounterClockwise);
    // The rotation is stored per system, at #5230 + 20·(n − 1).
    assert_eq!(interp.param(5230), 90.0);
    assert_eq!(interp.param(5250), -30.0);
}

#[test]
fn a_rotated_side_plane_arc_becomes_segments_on_the_true_arc() {
    let mut interp = linuxcnc_mm();
    let events = run(&mut interp, "G10 L2 P0 X-2 Y1 R60\nG0 X0 Y0 Z0\nG1 X1.5 Z0.5 F100\nG18 G2 X0.5 Z1.5 K1\nM2");
    let segments: Vec<_> = events
        .iter()
        .filter_map(|e| if let Event::Linear(m) = e { (m.line == 4).then_some(m.end) } else { None })
        .collect();
    assert!(segments.len() > 10, "{segments:?}");
    assert!(!events.iter().any(|e| matches!(e, Event::Arc(_))));
    // The centre is program (1.5, 0, 1.5); the arc's plane is program Y = 0, rotated by 60°.
    let (s, c) = 60f64.to_radians().sin_cos();
    let centre = Xyz::new(-2.0 + 1.5 * c, 1.0 + 1.5 * s, 1.5);
    for p in &segments {
        assert!(((*p - centre).norm() - 1.0).abs() < 0.0025 + 1e-9, "{p:?}");
        let along_normal = (p.x - (-2.0)) * -s + (p.y - 1.0) * c;
        assert!(along_normal.abs() < 1e-9, "{p:?} leaves the rotated XZ plane");
    }
}

#[test]
fn g10_rotation_is_refused_where_the_dialect_has_none_or_the_form_has_none() {
    assert_eq!(problem(&mut linuxcnc_mm(), "G10 L20 P0 X1 R30"), RunProblem::G10RotationL20);
    assert!(matches!(
        problem(&mut linuxcnc_mm(), "G10 L2 P0 R400"),
        RunProblem::OutOfRange { code: "G10", letter: 'R', .. }
    ));
    let mut mach4 = Interpreter::new(InterpreterConfig { dialect: Dialect::Mach4, ..InterpreterConfig::default() });
    let message = problem(&mut mach4, "G10 L2 P1 R30").to_string();
    assert!(message.contains("rotation") && message.contains("G68"), "{message}");
    run(&mut mach4, "G10 L2 P1 X1 R0\nG0 X0");
    assert_eq!(mach4.machine_position(), Xyz::new(1.0, 0.0, 0.0));
}

#[test]
fn polar_words_move_as_in_rs274() {
    // rs274 printed these end points for the same program (X/Y, mm; compare.py: agree).
    let program = "G21 G0 @10 ^90\nG0 ^0\nG0 @5\nG91 G0 ^90\nG0 @2.5\nG90 G2 @7.5 ^0 I0 J-7.5 F100\nM2";
    let events = run(&mut linuxcnc_mm(), program);
    let want = [(0.0, 10.0), (10.0, 0.0), (5.0, 0.0), (0.0, 5.0), (0.0, 7.5)];
    let got = moves(&events);
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (g, w) in got.iter().zip(want) {
        assert!((g.1[0] - w.0).abs() < 1e-9 && (g.1[1] - w.1).abs() < 1e-9, "{g:?} != {w:?}");
    }
    let arc = events.iter().find_map(|e| if let Event::Arc(a) = e { Some(a) } else { None }).expect("an arc");
    assert!((arc.end.xy() - Xyz::new(7.5, 0.0, 0.0).xy()).norm() < 1e-9, "{arc:?}");
}

#[test]
fn g95_feeds_per_revolution_at_the_spindle_speed() {
    let feeds = |events: &[Event]| -> Vec<f64> {
        events
            .iter()
            .filter_map(|e| match e {
                Event::Linear(m) => match m.rate {
                    Rate::Feed(f) => Some(f),
                    Rate::Rapid => None,
                },
                _ => None,
            })
            .collect()
    };
    // 0.01 in per revolution at 1000 rpm: 10 in/min; at 1500 rpm, 15; back under G94, F per minute.
    let mut interp = machine(LengthUnit::Inch);
    let events = run(&mut interp, "G20 M3 S1000\nG95 G1 X0.1 F0.01\nS1500 X0.2\nG94 G1 X0.3 F20\nM2");
    assert_eq!(feeds(&events), vec![10.0, 15.0, 20.0]);
    // In a millimetre program on an inch machine the feed per revolution converts like any length.
    let events = run(&mut machine(LengthUnit::Inch), "G21 S100 G95 G1 X25.4 F2.54\nM2");
    assert!((feeds(&events)[0] - 10.0).abs() < 1e-12, "{:?}", feeds(&events));
    // No spindle speed: refused with the reason, not a move at some feed.
    for text in ["G95 G1 X1 F0.01", "S0 G95 G1 X1 F0.01", "G95 G81 X1 Z-1 R1 F0.01"] {
        let message = problem(&mut machine(LengthUnit::Inch), text).to_string();
        assert!(message.contains("G95") && message.contains("spindle speed"), "{text}: {message}");
    }
    // A change of feed mode needs a new F (LinuxCNC: any G94/G95 sets F to 0).
    assert!(matches!(problem(&mut machine(LengthUnit::Inch), "S1000 F10\nG95 G1 X1"), RunProblem::ZeroFeedRate { .. }));
    run(&mut machine(LengthUnit::Inch), "F10\nG94 G1 X1\nM2");
    assert!(matches!(problem(&mut linuxcnc_mm(), "F10\nG94 G1 X1"), RunProblem::ZeroFeedRate { .. }));
    run(&mut linuxcnc_mm(), "G94 F10 G1 X1\nM2");
}

#[test]
fn a_written_origin_takes_effect_per_dialect() {
    // rs274 (and LinuxCNC 2.9.0 to 2.9.10, whose convert_coordinate_system is the same) loads
    // a system's parameters only when it becomes active or a G10 sets it; compare.py on this
    // program (inch machine) agrees. Mach4 and seed 002 apply the write from that line on.
    let program = "G20 G0 X1\n#5221=10\n#5222=2\nG1 X2 F100\nG54\nG1 X3\nG10 L2 P1 X5\nG1 X3.5\nG55\nG54\nG1 X4\nM2";
    let xs = |dialect| {
        let mut interp = Interpreter::new(InterpreterConfig { dialect, ..InterpreterConfig::default() });
        moves(&run(&mut interp, program)).iter().map(|m| m.1[0]).collect::<Vec<_>>()
    };
    assert_eq!(xs(Dialect::LinuxCnc), vec![1.0, 2.0, 3.0, 8.5, 9.0]);
    for dialect in [Dialect::Mach4, Dialect::MachineMotion] {
        assert_eq!(xs(dialect), vec![1.0, 12.0, 13.0, 8.5, 9.0], "{dialect:?}");
    }
    // A host's write stands for the control's offset table: at once, in every dialect.
    let mut interp = Interpreter::new(InterpreterConfig { dialect: Dialect::LinuxCnc, ..InterpreterConfig::default() });
    interp.set_param(5221, 3.0).expect("writable");
    run(&mut interp, "G0 X1\nM2");
    assert_eq!(interp.machine_position().x, 4.0);
}

#[test]
fn the_parameter_range_is_the_dialects() {
    // rs274 refuses #5602 ("Parameter number out of range"); #5601 is its last.
    let mut interp = linuxcnc_mm();
    run(&mut interp, "#5601 = 2\nG0 X#5601\nM2");
    assert_eq!(interp.machine_position().x, 2.0);
    for text in ["#5602 = 1", "G0 X#5602", "#[5600 + 2] = 1"] {
        let p = problem(&mut linuxcnc_mm(), text);
        assert_eq!(p, RunProblem::BadParameter { index: 5602.0, last: 5601, dialect: "linuxcnc" }, "{text}");
        assert!(p.to_string().contains("1 to 5601"), "{p}");
    }
    assert!(linuxcnc_mm().set_param(6000, 1.0).is_err());
    for dialect in [Dialect::Mach4, Dialect::MachineMotion] {
        let mut interp = Interpreter::new(InterpreterConfig { dialect, ..InterpreterConfig::default() });
        run(&mut interp, "#9999 = 3\nG0 X#9999\nM2");
        assert_eq!(interp.machine_position().x, 3.0);
        assert!(matches!(problem(&mut interp, "#10000 = 1"), RunProblem::BadParameter { last: 9999, .. }));
    }
}

#[test]
fn linuxcnc_predefined_named_parameters_read_as_in_rs274() {
    // rs274 printed these end points for the same program (compare.py: agree). A line reads
    // before it executes: `_absolute` on the G90 line still reads G91's 0.
    let program = "G21 G91\nG0 X[#<_task> + 1]\nG0 X[#<_vmajor>] Y[#<_vminor>] Z[#<_incremental>]
G90 G0 X[#<_x> + 1] Y[#<_imperial>*10 + #<_metric>] Z[#<_absolute>]\nF250 S1200 T3
G0 X[#<_feed>] Y[#<_rpm>] Z[#<_selected_tool>]\nM6\nG0 X[#<_current_tool>] Y[#<_y>] Z[#<_z>]\nM2";
    let events = run(&mut linuxcnc_mm(), program);
    let want = [[1.0, 0.0, 0.0], [3.9, 0.0, 1.0], [4.9, 1.0, 0.0], [250.0, 1200.0, 3.0], [3.0, 1200.0, 3.0]];
    let got = moves(&events);
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (g, w) in got.iter().zip(want) {
        assert!((0..3).all(|i| (g.1[i] - w[i]).abs() < 1e-9), "{g:?} != {w:?}");
    }
    assert_eq!(problem(&mut linuxcnc_mm(), "#<_x> = 1"), RunProblem::ReadOnlyName { name: "_x".into() });
    // Elsewhere they are ordinary (undefined) globals.
    let mut mach4 = Interpreter::new(InterpreterConfig { dialect: Dialect::Mach4, ..InterpreterConfig::default() });
    assert!(matches!(problem(&mut mach4, "G0 X#<_task>"), RunProblem::UndefinedName { .. }));
}

#[test]
fn a_hosts_rotation_write_takes_effect_at_once() {
    let mut interp = linuxcnc_mm();
    interp.set_param(5230, 90.0).expect("writable");
    run(&mut interp, "G0 X1 Y0\nM2");
    assert!((interp.machine_position() - Xyz::new(0.0, 1.0, 0.0)).norm() < 1e-12, "{:?}", interp.machine_position());
    // A program's write waits, as rs274's does, for the system to be selected again
    // (compare.py on this program: agree).
    let xs: Vec<_> =
        moves(&run(&mut linuxcnc_mm(), "#5230 = 90\nG0 X1 Y0\nG55\nG54\nG0 X2 Y0\nM2")).iter().map(|m| m.1).collect();
    assert!((xs[0][0] - 1.0).abs() < 1e-12 && (xs[1][1] - 2.0).abs() < 1e-12, "{xs:?}");
}

#[test]
fn mach4_applies_the_tool_xy_at_m6_and_the_length_at_g43() {
    let tools = ToolTable::numbered(1, 20).with(7, Tool { offset: Xyz::new(1.5, -2.0, 0.5), outputs: None });
    let mut interp = Interpreter::new(InterpreterConfig {
        tools,
        dialect: Dialect::Mach4,
        ..InterpreterConfig::new(LengthUnit::Inch)
    });
    let at = |interp: &Interpreter| interp.machine_position();
    run(&mut interp, "T7 M6\nG0 X0 Y0 Z0");
    assert_eq!(at(&interp), Xyz::new(-1.5, 2.0, 0.0), "X/Y from M6, no length yet");
    run(&mut interp, "G43 H7\nG0 X0 Y0 Z0");
    assert_eq!(at(&interp), Xyz::new(-1.5, 2.0, 0.5), "G43 adds the length only");
    run(&mut interp, "G49\nG0 X0 Y0 Z0");
    assert_eq!(at(&interp), Xyz::new(-1.5, 2.0, 0.0), "G49 cancels the length only");
    run(&mut interp, "T1 M6\nG0 X0 Y0 Z0");
    assert_eq!(at(&interp), Xyz::new(0.0, 0.0, 0.0), "tool 1 has no X/Y offset");
}

// Issue 25: four programs where we differed from rs274, each with rs274's numbers.

fn inch_machine(dialect: Dialect) -> Interpreter {
    Interpreter::new(InterpreterConfig { dialect, ..InterpreterConfig::new(LengthUnit::Inch) })
}

#[test]
fn g10_l20_in_a_rotated_system_makes_the_point_read_the_value_there() {
    // rs274: after the G10 L20 the current point reads X5 in the system rotated by 30°, so
    // both X and Y of the origin change; the G0 ends at (1.616, 0.933) (we ended at Y 2.5).
    let mut interp = inch_machine(Dialect::LinuxCnc);
    let events = run(&mut interp, "G20 G90\nG0 X1 Y2\nG10 L2 P1 R30\nG10 L20 P1 X5\nG0 X5 Y0\nM2");
    let got = moves(&events);
    let (s, c) = 30f64.to_radians().sin_cos();
    let y = 2.0 * c - s; // the Y the point read in the rotated system before the G10 L20
    assert_moves(&got, &[(R, [1.0, 2.0, 0.0]), (R, [1.0 + y * s, 2.0 - y * c, 0.0])]);
    assert!((got[1].1[0] - 1.6160).abs() < 1e-4 && (got[1].1[1] - 0.9330).abs() < 1e-4, "{got:?}");
    // The origin moved on both axes; the system's rotation stays.
    assert!((interp.param(5221) - (1.0 - 5.0 * c + y * s)).abs() < 1e-9);
    assert!((interp.param(5222) - (2.0 - 5.0 * s - y * c)).abs() < 1e-9);
    assert_eq!(interp.param(5230), 30.0);
}

#[test]
fn g53_ends_a_series_of_cycles_like_any_other_motion() {
    // rs274: the second G81 starts a new series at the Z the G53 move left (Z2): it traverses
    // at Z2 and, under G98, retracts there (we dropped to R at the old X/Y and traversed there).
    let mut interp = inch_machine(Dialect::LinuxCnc);
    let program = "G20 G90 F20\nG90 G81 X0 Y0 Z-0.5 R0.1\nG53 G0 Z2\nG90 G98 G81 X1 Y0 Z-0.5 R0.1\nM2";
    let events = run(&mut interp, program);
    #[rustfmt::skip]
    let want = [
        (R, [0.0, 0.0, 0.1]), (R, [0.0, 0.0, 0.1]), (F, [0.0, 0.0, -0.5]), (R, [0.0, 0.0, 0.1]),
        (R, [0.0, 0.0, 2.0]),
        (R, [1.0, 0.0, 2.0]), (R, [1.0, 0.0, 0.1]), (F, [1.0, 0.0, -0.5]), (R, [1.0, 0.0, 2.0]),
    ];
    assert_moves(&moves(&events), &want);
    // The same with G0 Z2 (no G53), where we always agreed, and under the other dialects.
    for dialect in [Dialect::LinuxCnc, Dialect::Mach4, Dialect::MachineMotion] {
        let mut interp = inch_machine(dialect);
        assert_moves(&moves(&run(&mut interp, program)), &want);
        let mut interp = inch_machine(dialect);
        assert_moves(&moves(&run(&mut interp, &program.replace("G53 G0", "G0"))), &want);
    }
}

#[test]
fn a_full_circle_whose_end_is_off_by_rounding_makes_every_turn() {
    // An inch machine, a millimetre program: #5420/#5421 read back the current point through
    // the units, one rounding step off it. rs274 prints ARC_FEED(…, 2, …): two turns.
    let mut interp = inch_machine(Dialect::LinuxCnc);
    let program = "G21 G90 G17 F500\nG0 X2.8884 Y1.8253\nG0 @4.1685 ^-124.2100\nG1 ^-156.0546\n\
                   G99 G83 @4.2127 ^150.4638 Z-2 R1 Q0.7\nG80\nG3 X[#5420] Y[#5421] I-2.2923 J3.1370 P2\nM2";
    let events = run(&mut interp, program);
    let arc = events.iter().find_map(|e| if let Event::Arc(a) = e { Some(a) } else { None }).expect("the arc");
    assert_eq!(arc.direction, ArcDirection::CounterClockwise);
    assert_eq!(arc.extra_turns(), 1, "{arc:?}");
    assert!((arc.angle - 2.0 * std::f64::consts::TAU).abs() < 1e-9, "{arc:?}");
    // rs274's end (inches): (-0.14430, 0.08176, 0.03937).
    assert!((arc.end - Xyz::new(-0.144_30, 0.081_76, 0.039_37)).norm() < 1e-5, "{arc:?}");
    assert!((arc.end - arc.start).norm() < 1e-12);
}

#[test]
fn a_percent_line_inside_a_program_is_refused_as_rs274_does() {
    // rs274: "Bad character '%' used". The opening and closing % stay fine.
    let program = "G21\nG0 X1 Y1\n%\nG0 X2\nM2";
    let mut interp = linuxcnc_mm();
    match interp.run(program, None, &mut Vec::new()) {
        Err(GcodeError::Run { line: 3, problem: RunProblem::PercentInside }) => {}
        other => panic!("{other:?}"),
    }
    let message = RunProblem::PercentInside.to_string();
    assert!(message.contains("Bad character '%'"), "{message}");
    run(&mut linuxcnc_mm(), "%\nG21\nG0 X1 Y1\n%\nG0 X2");
    run(&mut linuxcnc_mm(), "\n%\nG21 G0 X1\nM2\n%");
    // The same inside control flow.
    assert_eq!(problem(&mut linuxcnc_mm(), "o1 if [1]\nG0 X1\no1 endif\n%\nM2"), RunProblem::PercentInside);
    // Mach4 ignores it (the change is LinuxCNC's).
    let config = InterpreterConfig { dialect: Dialect::Mach4, ..InterpreterConfig::new(LengthUnit::Millimetre) };
    let mut mach4 = Interpreter::new(config);
    run(&mut mach4, program);
    assert_eq!(mach4.machine_position(), Xyz::new(2.0, 1.0, 0.0));
}

// Issue 33: rs274's current point after a change of system.

#[test]
fn a_change_of_system_carries_rs274s_current_point_not_the_machine_position() {
    // rs274 (interp_convert.cc `convert_coordinate_system` → interp_find.cc
    // `find_current_in_system`) moves its current point into the new system: the point plus the
    // G92/G52 offset, rotated by the old system's rotation, moved from the old origin to the
    // new one, rotated back, the offset taken off again. After `G10 L2 P0 R90` with G52 X10 in
    // force that point no longer reads the machine position (the rotation turned the point,
    // not the offset), and G55 carries the discrepancy over: G28's first leg (to the current
    // point) goes to machine (0, 10), not (10, 0) where the machine stands. rs274 printed
    // STRAIGHT_TRAVERSE(-10, 10, 0) there, under G55 with G52 X10 (compare.py: agree).
    let program = "G21 G90\nG52 X10\nG0 X0 Y0\nG10 L2 P0 R90\nG55\nG28\nM2";
    let events = run(&mut linuxcnc_mm(), program);
    assert_moves(&moves(&events), &[(R, [10.0, 0.0, 0.0]), (R, [0.0, 10.0, 0.0]), (R, [0.0, 0.0, 0.0])]);
    // An incremental move after the change starts from that point too: X+1 from (-10, 10).
    let events = run(&mut linuxcnc_mm(), "G21 G90\nG52 X10\nG0 X0 Y0\nG10 L2 P0 R90\nG55\nG91 G0 X1\nM2");
    assert_moves(&moves(&events), &[(R, [10.0, 0.0, 0.0]), (R, [1.0, 10.0, 0.0])]);
    // Without an offset in force, or without a rotation change, the point reads the machine
    // and the change of system moves nothing.
    let events = run(&mut linuxcnc_mm(), "G21 G90\nG0 X10 Y0\nG10 L2 P0 R90\nG55\nG28\nM2");
    assert_moves(&moves(&events), &[(R, [10.0, 0.0, 0.0]), (R, [10.0, 0.0, 0.0]), (R, [0.0, 0.0, 0.0])]);
}

#[test]
fn a_parameter_write_leaves_rs274s_current_point_alone() {
    // rs274's parameters are storage: writing a work offset (or a rotation) changes neither the
    // frame in use nor its current point. After `G10 L2 P0 R90` with G52 X10 in force that point
    // is (0, 0) while the machine stands at (10, 0); `#5241 = 0` keeps it, so G91 X1 goes to
    // program (1, 0), machine (0, 11). rs274 printed STRAIGHT_TRAVERSE(1, 0, 0) (compare.py:
    // agree); re-deriving the point from the machine went to (10, 1).
    let events = run(&mut linuxcnc_mm(), "G21 G90\nG52 X10\nG0 X0 Y0\nG10 L2 P0 R90\n#5241 = 0\nG91 G0 X1\nM2");
    assert_moves(&moves(&events), &[(R, [10.0, 0.0, 0.0]), (R, [0.0, 11.0, 0.0])]);
    // Mach4 applies a written offset of the active system at once; the machine stays put.
    let mut mach4 = Interpreter::new(InterpreterConfig {
        dialect: Dialect::Mach4,
        ..InterpreterConfig::new(LengthUnit::Millimetre)
    });
    let events = run(&mut mach4, "G21 G90\nG0 X1 Y0\n#5221 = 5\nG91 G0 X1\nM2");
    assert_moves(&moves(&events), &[(R, [1.0, 0.0, 0.0]), (R, [2.0, 0.0, 0.0])]);
}

#[test]
fn a_tool_length_moves_rs274s_current_point_by_the_change_only() {
    // rs274 (`convert_tool_length_offset`) adds the change of tool offset, rotated into the
    // system, to its current point. After `G10 L2 P0 R90` with G52 X10 in force the point is
    // (0, 0) while the machine stands at (10, 0), so G91 X1 goes to machine (0, 11) after
    // either line. rs274 printed STRAIGHT_TRAVERSE(1, 0, z) for both (compare.py: agree);
    // re-deriving the point from the machine went to (10, 1).
    let before = |line: &str| format!("G21 G90\nG52 X10\nG0 X0 Y0\nG10 L2 P0 R90\n{line}\nG91 G0 X1\nM2");
    for line in ["G43.1 Z1", "G49"] {
        let events = run(&mut linuxcnc_mm(), &before(line));
        assert_moves(&moves(&events), &[(R, [10.0, 0.0, 0.0]), (R, [0.0, 11.0, 0.0])]);
    }
    // A tool change is where LinuxCNC's task re-reads the point from the machine
    // (emccanon.cc `GET_EXTERNAL_POSITION`): X1 from there reaches (10, 1). The standalone
    // rs274 reads back its last printed point instead, unrotated (saicanon.cc), and printed a
    // move to (0, 11): an artefact of the oracle, not LinuxCNC's behaviour.
    let events = run(&mut linuxcnc_mm(), &before("T1 M6"));
    assert_moves(&moves(&events), &[(R, [10.0, 0.0, 0.0]), (R, [10.0, 1.0, 0.0])]);
    // A length in a rotated system: the point moves along Z only, the machine stays.
    let mut interp = linuxcnc_mm();
    run(&mut interp, "%\nG21 G90\nG10 L2 P0 R30\nG0 X1 Y2 Z3\nG43.1 Z0.5\n%");
    assert!((interp.program_position() - Xyz::new(1.0, 2.0, 2.5)).norm() < 1e-12, "{:?}", interp.program_position());
}

#[test]
fn g28_with_axis_words_homes_those_program_axes_in_a_rotated_system() {
    // rs274 (`convert_home`): the stored position (machine coordinates) is read in the current
    // system (`find_relative`), and the named axes of the waypoint take its program coordinates;
    // the others keep the waypoint's. In a system rotated by 90° homing X alone therefore moves
    // the machine's Y. rs274 printed, program coordinates: G28 X0 → (0, 2), (0, 2); G30 Y1 →
    // (3, 1), (3, 2) with #5181-#5183 = machine (-2, 1, 1) (compare.py: agree).
    let program = "G21 G90\nG10 L2 P0 R90\nG0 X1 Y2\nG28 X0\nG0 X1 Y2 Z1\nG30.1\nG0 X3 Y1 Z0\nG30 Y1\nM2";
    let events = run(&mut linuxcnc_mm(), program);
    #[rustfmt::skip]
    let want = [
        (R, [-2.0, 1.0, 0.0]), (R, [-2.0, 0.0, 0.0]), (R, [-2.0, 0.0, 0.0]),
        (R, [-2.0, 1.0, 1.0]), (R, [-1.0, 3.0, 0.0]), (R, [-1.0, 3.0, 0.0]), (R, [-2.0, 3.0, 0.0]),
    ];
    assert_moves(&moves(&events), &want);
    // Unrotated, the same as homing the machine axis (the other dialects' rule).
    let events = run(&mut linuxcnc_mm(), "G21 G90\nG10 L2 P1 X5 Y6\nG0 X1 Y2\nG28 X0\nM2");
    assert_moves(&moves(&events), &[(R, [6.0, 8.0, 0.0]), (R, [5.0, 8.0, 0.0]), (R, [0.0, 8.0, 0.0])]);
}
