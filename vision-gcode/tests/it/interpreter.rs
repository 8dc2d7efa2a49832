//! The interpreter's modal state, frame chain, arcs, tools and errors.

#![expect(clippy::float_cmp, reason = "tests compare exact values")]

use vision_gcode::{
    ArcDirection, Event, GcodeError, Interpreter, InterpreterConfig, LinearMove, PathMode, Rate, RunOutcome,
    RunProblem, Tool, Xyz,
};
use vision_math::{AlignmentChain, LengthUnit, Point2, Vector2};

fn inch() -> Interpreter {
    Interpreter::new(InterpreterConfig::default())
}

fn run(interp: &mut Interpreter, program: &str) -> Vec<Event> {
    let mut events = Vec::new();
    interp.run(program, None, &mut events).unwrap_or_else(|e| panic!("{e}\n{program}"));
    events
}

fn run_err(interp: &mut Interpreter, program: &str) -> (u32, RunProblem) {
    match interp.run(program, None, &mut Vec::new()) {
        Err(GcodeError::Run { line, problem }) => (line, problem),
        other => panic!("expected a run error for {program:?}, got {other:?}"),
    }
}

fn close(a: Xyz, b: Xyz) -> bool {
    (a - b).norm() < 1e-12
}

#[test]
fn program_units_convert_to_the_machine_unit() {
    let mut interp = inch();
    run(&mut interp, "G21 G90 G0 X25.4 Y-50.8 Z12.7");
    assert!(close(interp.machine_position(), Xyz::new(1.0, -2.0, 0.5)));
    assert!(close(interp.program_position(), Xyz::new(25.4, -50.8, 12.7)));
    assert_eq!(interp.param(5420), 25.4, "#5420 reports current units");
    run(&mut interp, "G20");
    assert!(close(interp.program_position(), Xyz::new(1.0, -2.0, 0.5)));
    // A millimetre machine running an inch program.
    let mut mm = Interpreter::new(InterpreterConfig::new(LengthUnit::Millimetre));
    run(&mut mm, "G20 G91 G0 X1\nG1 X1 F10");
    assert!(close(mm.machine_position(), Xyz::new(50.8, 0.0, 0.0)));
    assert_eq!(mm.feed(), Some(254.0));
    assert_eq!(mm.units(), LengthUnit::Inch);
}

#[test]
fn work_offsets_g10_and_g54_to_g59() {
    let mut interp = inch();
    run(&mut interp, "G10 L2 P2 X1 Y2 Z3\nG55 G0 X0 Y0 Z0");
    assert!(close(interp.machine_position(), Xyz::new(1.0, 2.0, 3.0)));
    assert_eq!(interp.coordinate_system(), 2);
    assert_eq!(interp.param(5241), 1.0);
    assert_eq!(interp.param(5220), 2.0);
    // G10 L20: make the current point read (5, 5) in G55.
    run(&mut interp, "G10 L20 P0 X5 Y5");
    assert_eq!(interp.program_position(), Xyz::new(5.0, 5.0, 0.0));
    assert!(close(interp.work_offset(2), Xyz::new(-4.0, -3.0, 3.0)));
    // Switching systems does not move the machine; the program position changes.
    run(&mut interp, "G54");
    assert!(close(interp.machine_position(), Xyz::new(1.0, 2.0, 3.0)));
    assert!(close(interp.program_position(), Xyz::new(1.0, 2.0, 3.0)));
    // A G21 G10 stores machine units.
    run(&mut interp, "G21 G10 L2 P3 X25.4");
    assert_eq!(interp.work_offset(3).x, 1.0);
    // Writing the offset parameter moves the origin for the next line.
    run(&mut interp, "G20 #5221 = 10\nG0 X0");
    assert_eq!(interp.machine_position().x, 10.0);
}

#[test]
fn alignment_chain_is_vision_math_exactly_and_reads_back_in_current_units() {
    let mut interp = inch();
    run(&mut interp, "G90 G20\nG52 X0.1 Y-0.2\nG68 X3 Y2 R0.5\nG51 X1.001 Y0.999\nG0 X6 Y4");
    let chain = AlignmentChain {
        scale: Vector2::new(1.001, 0.999),
        center: Point2::new(3.0, 2.0),
        rotation_deg: 0.5,
        shift: Vector2::new(0.1, -0.2),
    };
    let w = chain.apply(Point2::new(6.0, 4.0));
    assert_eq!(interp.machine_position(), Xyz::new(w.x, w.y, 0.0));
    assert_eq!(interp.work_position(), Xyz::new(w.x, w.y, 0.0));
    assert_eq!(interp.program_position(), Xyz::new(6.0, 4.0, 0.0));
    assert_eq!(interp.active_alignment(), Some(chain));
    run(&mut interp, "G21");
    let mm = interp.active_alignment().expect("active");
    assert!((mm.center.x - 76.2).abs() < 1e-12 && (mm.shift.y + 5.08).abs() < 1e-12);
    run(&mut interp, "G20 G69 G50 G52 X0 Y0");
    assert_eq!(interp.active_alignment(), None);
    // Cancelling does not move the machine: the program position now reads the machine point.
    assert_eq!(interp.program_position(), Xyz::new(w.x, w.y, 0.0));
}

#[test]
fn incremental_moves_are_increments_in_the_program_frame() {
    let mut interp = inch();
    run(&mut interp, "G90 G0 X1 Y0\nG68 X0 Y0 R90\nG91 G0 X1");
    // G68 re-expresses the machine point (1, 0) as program (0, −1); +1 in program X is (1, −1),
    // which the rotation puts at (1, 1).
    assert!(close(interp.machine_position(), Xyz::new(1.0, 1.0, 0.0)));
    assert!(close(interp.program_position(), Xyz::new(1.0, -1.0, 0.0)));
}

#[test]
fn g68_without_a_centre_rotates_about_the_current_point() {
    let mut interp = inch();
    run(&mut interp, "G0 X2 Y1\nG68 R90");
    assert!(close(interp.program_position(), Xyz::new(2.0, 1.0, 0.0)), "nothing jumps");
    run(&mut interp, "G0 X3 Y1");
    assert!(close(interp.machine_position(), Xyz::new(2.0, 2.0, 0.0)));
}

#[test]
fn tool_offsets_put_the_tool_on_the_point() {
    let mut interp = inch();
    interp.set_tool(98, Tool { offset: Xyz::new(1.0, 0.5, 2.0), outputs: None });
    let events = run(&mut interp, "T98 M6\nG0 X0 Y0 Z0");
    assert_eq!(events[0], Event::ToolChange { line: 1, tool: 98, offset: Xyz::new(1.0, 0.5, 2.0) });
    assert!(close(interp.machine_position(), Xyz::new(-1.0, -0.5, 2.0)), "spindle = P − offset, Z + length");
    assert_eq!(interp.param(5400), 98.0);
    assert_eq!(interp.param(5401), 1.0);
    // Writing the active tool's offset re-derives the program position; the machine stays.
    interp.set_tool_offset(98, 2.0, 0.0).expect("tool exists");
    assert!(close(interp.program_position(), Xyz::new(1.0, -0.5, 0.0)));
    assert!(close(interp.machine_position(), Xyz::new(-1.0, -0.5, 2.0)));
    assert_eq!(interp.tool_offset(98), Some(Xyz::new(2.0, 0.0, 2.0)));
    assert!(interp.set_tool_offset(0, 1.0, 1.0).is_err());
    assert!(interp.set_tool_offset(9999, 1.0, 1.0).is_err());
    // Unknown tools are refused at T.
    assert_eq!(run_err(&mut interp, "T300"), (1, RunProblem::UnknownTool { tool: 300 }));
}

#[test]
fn g92_semantics() {
    let mut interp = inch();
    run(&mut interp, "G0 X4 Y3 Z1\nG92 X7");
    assert_eq!(interp.program_position(), Xyz::new(7.0, 3.0, 1.0));
    assert_eq!(interp.g92_offset(), Xyz::new(-3.0, 0.0, 0.0));
    run(&mut interp, "G92 Y0");
    // Seed 002: the X offset not named goes back to zero.
    assert_eq!(interp.g92_offset(), Xyz::new(0.0, 3.0, 0.0));
    assert_eq!(interp.program_position(), Xyz::new(4.0, 0.0, 1.0));
    assert_eq!(run_err(&mut interp, "G92"), (1, RunProblem::NoAxisWords { code: "G92" }));
}

#[test]
fn a_failing_line_changes_nothing_and_emits_nothing() {
    let mut interp = inch();
    run(&mut interp, "G0 X1 Y1\n#1 = 3");
    let before = (interp.machine_position(), interp.program_position(), interp.param(1), interp.units());
    let mut events = Vec::new();
    // Units, a parameter, a work offset, a tool change and a move, then an arc that cannot be.
    let err = interp.run("G21 #1=9 T2 M6 G55 F10 G2 X10 Y10 I0 J0", None, &mut events).expect_err("zero radius arc");
    assert!(matches!(err, GcodeError::Run { line: 1, problem: RunProblem::ArcZeroRadius }));
    assert!(events.is_empty());
    assert_eq!((interp.machine_position(), interp.program_position(), interp.param(1), interp.units()), before);
    assert_eq!(interp.coordinate_system(), 1);
    assert_eq!(interp.active_tool(), 0);
    assert_eq!(interp.feed(), None);
    // Later lines do not run.
    let err = interp.run("G0 X2\nG0 Q1\nG0 X3", None, &mut events).expect_err("unused Q");
    assert_eq!(err, GcodeError::Run { line: 2, problem: RunProblem::UnusedWord { letter: 'Q' } });
    assert_eq!(interp.machine_position().x, 2.0);
}

#[test]
fn assignments_take_effect_after_the_reads_of_their_line() {
    let mut interp = inch();
    run(&mut interp, "#1 = 1\n#1 = 2 #2 = #1 G0 X#1");
    assert_eq!(interp.param(2), 1.0);
    assert_eq!(interp.machine_position().x, 1.0);
    run(&mut interp, "G0 X#1");
    assert_eq!(interp.machine_position().x, 2.0);
    // Indirection and expressions in words.
    run(&mut interp, "#10 = 3 #3 = 0.5\nG0 X[#10 * 2] Y#[#10] Z-[1 + 1]");
    assert_eq!(interp.machine_position(), Xyz::new(6.0, 0.5, -2.0));
}

#[test]
fn errors_name_the_line_and_the_problem() {
    let cases: &[(&str, RunProblem)] = &[
        ("G12", RunProblem::Unsupported { code: "G12".into(), feature: "circular pocket cycles (G12/G13)" }),
        ("G41", RunProblem::Unsupported { code: "G41".into(), feature: "cutter radius compensation (G41/G42)" }),
        ("M62 P1", RunProblem::Unsupported { code: "M62".into(), feature: "HAL digital/analog I/O (M62-M68)" }),
        ("G6", RunProblem::UnknownGCode { code: vision_gcode::GCode(60) }),
        ("M11", RunProblem::UnknownMCode { code: 11, user_low: 100, user_high: 999 }),
        ("G1.25", RunProblem::BadGCode { value: 1.25 }),
        ("G0 G1 X1", RunProblem::ModalConflict { first: "G0".into(), second: "G1".into() }),
        ("G52 X1 G92", RunProblem::ModalConflict { first: "G52".into(), second: "G92".into() }),
        ("G52 X1 G68 R1", RunProblem::AxisWordConflict { first: "G52".into(), second: "G68".into() }),
        ("G0 G92 X1", RunProblem::AxisWordConflict { first: "G0".into(), second: "G92".into() }),
        ("G1 G52 X1", RunProblem::AxisWordConflict { first: "G1".into(), second: "G52".into() }),
        ("G2 G92 X3 I1", RunProblem::AxisWordConflict { first: "G2".into(), second: "G92".into() }),
        ("X1", RunProblem::NoMotionMode),
        ("G1 X1", RunProblem::NoFeedRate { code: "G1" }),
        ("G0 X1 H1", RunProblem::UnusedWord { letter: 'H' }),
        ("F0 G1 X1", RunProblem::ZeroFeedRate { code: "G1" }),
        ("G0 X1 R2", RunProblem::UnusedWord { letter: 'R' }),
        ("G0 A1", RunProblem::AxisNotSupported { letter: 'A' }),
        ("G4", RunProblem::MissingWord { code: "G4", letter: 'P', hint: "the dwell time in seconds, e.g. G4 P0.5" }),
        ("G4 P-1", RunProblem::Negative { code: "G4", letter: 'P', value: -1.0 }),
        ("G4 G64 P2", RunProblem::WordConflict { letter: 'P', first: "G4", second: "G64" }),
        ("#5420 = 1", RunProblem::ReadOnlyParameter { index: 5420, what: "the current position" }),
        ("#0 = 1", RunProblem::BadParameter { index: 0.0, last: 9999, dialect: "machinemotion" }),
        ("G0 X[1/0]", RunProblem::DivisionByZero),
        ("G0 X[10**400]", RunProblem::NonFinite { what: "**" }),
        (
            "G0 X[-1**0.5]",
            RunProblem::Domain {
                function: "**",
                argument: -1.0,
                hint: "a negative number has no real non-integer power",
            },
        ),
        (
            "G0 XSQRT[-1]",
            RunProblem::Domain { function: "SQRT", argument: -1.0, hint: "the argument must not be negative" },
        ),
        ("G51 X0", RunProblem::ZeroScale { letter: 'X' }),
        ("G51 Z2", RunProblem::ScaleAxis { letter: 'Z' }),
        (
            "G68 X1 Y1",
            RunProblem::MissingWord {
                code: "G68",
                letter: 'R',
                hint: "the rotation in degrees, counter-clockwise, e.g. G68 X0 Y0 R30",
            },
        ),
        ("G10 L1 P1 X1", RunProblem::G10Form { l: 1.0 }),
        ("T1.5", RunProblem::NotWhole { letter: 'T', value: 1.5 }),
        ("M3 $0", RunProblem::NoSpindleTool { code: "M3" }),
        ("M3 A1", RunProblem::OutputForm { code: "M3" }),
        ("G2 X1 F10", RunProblem::ArcNoCentre { code: "G2", centre: "I and J" }),
        ("G2 X1 I1 K1 F10", RunProblem::ArcCentreWord { letter: 'K', plane: "G17", centre: "I and J" }),
        ("G2 X1 R1 I1 F10", RunProblem::ArcBothForms { code: "G2" }),
        ("G2 R1 F10", RunProblem::ArcRFullCircle),
        ("G2 X1 Y1 R0.1 F10", RunProblem::ArcRadiusTooSmall { radius: 0.1, half_chord: 0.5_f64.hypot(0.5) }),
        (
            "G90.1 G2 X2 I1 F10",
            RunProblem::MissingWord {
                code: "G2",
                letter: 'J',
                hint: "under G90.1 both centre coordinates are absolute and required",
            },
        ),
        ("M281 G0", RunProblem::UserMCodeNotAlone { code: 281, other: "G0".into() }),
        ("M281 M3", RunProblem::UserMCodeNotAlone { code: 281, other: "M3".into() }),
        ("M3 M4", RunProblem::ModalConflict { first: "M3".into(), second: "M4".into() }),
    ];
    for (text, problem) in cases {
        let mut interp = inch();
        let program = format!("G90\n{text}");
        assert_eq!(run_err(&mut interp, &program), (2, problem.clone()), "{text}");
        let message = GcodeError::Run { line: 2, problem: problem.clone() }.to_string();
        assert!(message.starts_with("line 2: "), "{message}");
    }
}

#[test]
fn syntax_errors_stop_the_run_with_line_and_column() {
    let mut interp = inch();
    let err = interp.run("G0 X1\nG0 X[1 +\nG0 X3", None, &mut Vec::new()).expect_err("syntax");
    assert_eq!(err.line(), 2);
    assert_eq!(err.column(), Some(9));
    assert_eq!(interp.machine_position().x, 1.0);
}

#[test]
fn program_end_stops_the_run_and_resets_the_modes() {
    let mut interp = inch();
    let mut events = Vec::new();
    let outcome = interp.run("G91 G18 G92 X1\nG68 R30\nG51 X2 Y2\nM30\nG0 X100", None, &mut events).expect("runs");
    assert_eq!(outcome, RunOutcome::Ended { line: 4, code: 30 });
    assert_eq!(events, vec![Event::ProgramEnd { line: 4, code: 30 }]);
    assert!(interp.is_absolute());
    assert_eq!(interp.plane(), vision_gcode::Plane::Xy);
    assert_eq!(interp.active_alignment(), None);
    assert_eq!(interp.g92_offset(), Xyz::ZERO);
    assert_eq!(interp.machine_position(), Xyz::ZERO);
    let outcome = interp.run("G0 X1\n\n", None, &mut events).expect("runs");
    assert_eq!(outcome, RunOutcome::Completed { lines: 3 });
    let mut stops = Vec::new();
    interp.run("M0\nM1", None, &mut stops).expect("stops are events");
    assert_eq!(stops, vec![Event::Stop { line: 1, optional: false }, Event::Stop { line: 2, optional: true }]);
}

fn linears(events: &[Event]) -> Vec<LinearMove> {
    events.iter().filter_map(|e| if let Event::Linear(m) = e { Some(*m) } else { None }).collect()
}

#[test]
fn arcs_under_non_uniform_scale_become_polylines_within_tolerance() {
    let mut interp = inch();
    let chain = AlignmentChain {
        scale: Vector2::new(1.002, 0.998),
        center: Point2::new(1.0, 1.0),
        rotation_deg: 3.0,
        shift: Vector2::new(0.2, 0.1),
    };
    let events = run(
        &mut interp,
        "G90 G20 G61 F20\nG52 X0.2 Y0.1\nG68 X1 Y1 R3\nG51 X1.002 Y0.998\nG0 X3 Y0 Z1\nG3 X-3 Y0 Z0 I-3 J0",
    );
    let segments: Vec<LinearMove> = linears(&events).into_iter().filter(|m| m.line == 6).collect();
    assert!(segments.len() > 100, "{} segments", segments.len());
    assert!(segments.iter().all(|m| m.rate == Rate::Feed(20.0)));
    // Interior vertices blend within the chord tolerance; the programmed end keeps G61.
    let (last, interior) = segments.split_last().expect("segments");
    assert_eq!(last.path, PathMode::ExactStop);
    assert!(interior.iter().all(|m| m.path == PathMode::Blend { tolerance: Some(interp.config().chord_tolerance) }));
    // Consecutive segments chain, and the last one ends exactly at the mapped end.
    for pair in segments.windows(2) {
        assert_eq!(pair[0].end, pair[1].start);
    }
    let end = chain.apply(Point2::new(-3.0, 0.0));
    assert_eq!(segments.last().map(|m| m.end), Some(Xyz::new(end.x, end.y, 0.0)));
    // Every vertex is on the mapped circle, and every chord stays within the tolerance of it.
    let tol = interp.config().chord_tolerance;
    for m in &segments {
        for t in [0.0, 0.25, 0.5, 0.75] {
            let q = Point2::new(m.start.x + t * (m.end.x - m.start.x), m.start.y + t * (m.end.y - m.start.y));
            let p = chain.inverse(q).expect("invertible");
            let off_circle = (p.coords.norm() - 3.0).abs() * 1.002;
            let bound = if t == 0.0 { 1e-12 } else { tol };
            assert!(off_circle <= bound, "{off_circle} > {bound}");
        }
    }
    assert!(close(interp.machine_position(), Xyz::new(end.x, end.y, 0.0)));
}

#[test]
fn arcs_under_rotation_and_uniform_or_mirrored_scale_stay_exact() {
    let mut interp = inch();
    let events = run(&mut interp, "G90 F10\nG68 X0 Y0 R90\nG51 X2 Y2\nG0 X1 Y0\nG3 X0 Y1 I-1 J0");
    let Some(Event::Arc(arc)) = events.last() else { panic!("an exact arc: {events:?}") };
    assert!(close(arc.start, Xyz::new(0.0, 2.0, 0.0)));
    assert!(close(arc.end, Xyz::new(-2.0, 0.0, 0.0)));
    assert!(close(arc.center, Xyz::ZERO));
    assert_eq!(arc.direction, ArcDirection::CounterClockwise);
    assert!((arc.angle - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    // A mirror reverses the direction.
    let mut interp = inch();
    let events = run(&mut interp, "G90 F10\nG51 X-1 Y1\nG0 X1 Y0\nG3 X0 Y1 I-1 J0");
    let Some(Event::Arc(arc)) = events.last() else { panic!("an exact arc") };
    assert_eq!(arc.direction, ArcDirection::Clockwise);
    assert!(close(arc.point_at(0.5), Xyz::new(-(0.5_f64.sqrt()), 0.5_f64.sqrt(), 0.0)));
    // G18 arcs under a rotation become polylines.
    let mut interp = inch();
    let events = run(&mut interp, "G90 G18 F10\nG68 X0 Y0 R30\nG0 X1 Z0\nG3 X-1 Z0 I-1 K0");
    assert!(events.iter().all(|e| !matches!(e, Event::Arc(_))));
}

#[test]
fn full_circles_turns_helices_and_r_arcs() {
    let mut interp = inch();
    let events = run(&mut interp, "G90 F10 G0 X1 Y0\nG2 X1 Y0 Z-0.5 I-1 J0 P3");
    let Some(Event::Arc(arc)) = events.last() else { panic!("arc") };
    assert!((arc.angle - 3.0 * std::f64::consts::TAU).abs() < 1e-12);
    assert_eq!(arc.extra_turns(), 2);
    assert_eq!(arc.end, Xyz::new(1.0, 0.0, -0.5));
    assert!((arc.point_at(0.5).z + 0.25).abs() < 1e-12);
    let events = run(&mut interp, "G0 X0 Y0 Z0\nG2 X2 Y0 R-1.5");
    let Some(Event::Arc(arc)) = events.last() else { panic!("arc") };
    assert!(arc.angle > std::f64::consts::PI, "negative R: the long way");
    assert_eq!(run_err(&mut interp, "G2 X2 Y0 R1"), (1, RunProblem::ArcRFullCircle));
}

#[test]
fn path_modes_and_modal_readers() {
    let mut interp = inch();
    assert_eq!(interp.path_mode(), PathMode::Blend { tolerance: None });
    run(&mut interp, "G21 G64 P0.254 G19 G91.1 G0");
    assert_eq!(interp.path_mode(), PathMode::Blend { tolerance: Some(0.01) });
    assert_eq!(interp.plane(), vision_gcode::Plane::Yz);
    assert_eq!(interp.motion_mode(), Some(vision_gcode::MotionMode::Rapid));
    run(&mut interp, "G61 G90.1 T5");
    assert_eq!(interp.path_mode(), PathMode::ExactStop);
    assert!(interp.is_arc_absolute());
    assert_eq!(interp.selected_tool(), 5);
    assert_eq!(interp.active_tool(), 0);
}

#[test]
fn user_mcodes_without_a_handler_are_reported_not_executed() {
    let mut interp = inch();
    let events = run(&mut interp, "G0 X1\nM283 C1 (walk sheet 1) (second)\nM282");
    assert_eq!(
        events[1],
        Event::UserMCode(vision_gcode::UserCall {
            line: 2,
            code: 283,
            words: vec![('C', 1.0)],
            comments: vec!["walk sheet 1".into(), "second".into()],
        })
    );
    assert!(matches!(&events[2], Event::UserMCode(c) if c.code == 282 && c.words.is_empty()));
    assert_eq!(interp.machine_position().x, 1.0);
}

#[test]
fn g28_with_an_intermediate_point_homes_only_the_named_axes() {
    let mut interp = inch();
    run(&mut interp, "G0 X1 Y2 Z3\nG28.1\nG0 X5 Y5 Z5");
    let events = run(&mut interp, "G28 Z4");
    let moves = linears(&events);
    assert_eq!(moves.len(), 2);
    assert_eq!(moves[0].end, Xyz::new(5.0, 5.0, 4.0));
    assert_eq!(moves[1].end, Xyz::new(5.0, 5.0, 3.0));
}

/// A handler that moves, then reads a watch of the interpreter that is running it (as the
/// simulated camera does).
struct MoveAndLook {
    watch: vision_gcode::PositionWatch,
    seen: Vec<Xyz>,
}

impl vision_gcode::MCodeHandler for MoveAndLook {
    fn call(
        &mut self,
        _call: &vision_gcode::UserMCode<'_>,
        ctx: &mut vision_gcode::Context<'_>,
    ) -> Result<Vec<String>, vision_gcode::HandlerError> {
        self.seen.push(self.watch.get());
        ctx.execute("G0 X2 Y3")?;
        self.seen.push(self.watch.get());
        Ok(Vec::new())
    }
}

#[test]
fn a_position_watch_reads_what_the_interpreter_commits_and_nothing_else() {
    let mut interp = inch();
    interp.set_machine_position(Xyz::new(1.0, 1.0, 0.0)).expect("finite");
    let watch = interp.watch_position();
    assert_eq!(watch.get(), Xyz::new(1.0, 1.0, 0.0));
    // A G52 re-derives the program point; the machine stays.
    run(&mut interp, "G90 G52 X5\nG0 X1 Y-1");
    assert_eq!(watch.get(), Xyz::new(6.0, -1.0, 0.0));
    // A failing line changes nothing, so the watch does not move either.
    run_err(&mut interp, "G0 X7 Q1");
    assert_eq!(watch.get(), Xyz::new(6.0, -1.0, 0.0));
    // A host placing the machine (no event) is seen too.
    interp.set_machine_position(Xyz::new(0.5, 0.25, -1.0)).expect("finite");
    assert_eq!(watch.get(), Xyz::new(0.5, 0.25, -1.0));
    // A clone is a separate machine: its moves are not published.
    let mut copy = interp.clone();
    run(&mut copy, "G0 X9");
    assert_eq!(watch.get(), Xyz::new(0.5, 0.25, -1.0));
    // Inside a handler, G-code it runs is published before it returns.
    let mut look = MoveAndLook { watch: interp.watch_position(), seen: Vec::new() };
    interp.run("G52 X0\nM100", Some(&mut look), &mut Vec::new()).expect("runs");
    assert_eq!(look.seen, vec![Xyz::new(0.5, 0.25, -1.0), Xyz::new(2.0, 3.0, -1.0)]);
    assert_eq!(watch.get(), interp.machine_position());
}
