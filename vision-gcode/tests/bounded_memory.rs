//! Memory is bounded by design (issue 26): a canned cycle's repeats and a loop's iterations
//! stream to the sink, none is held; every repeat count has a bound with its own message. A
//! global allocator in this test binary tracks the peak of live bytes (`vision-testalloc`); the
//! tests run one at a time so that one test's allocations do not show in another's peak.

use vision_gcode::{
    Dialect, Event, GcodeError, Interpreter, InterpreterConfig, RunProblem, MAX_CYCLE_MOVES, MAX_REPEATS,
};

#[global_allocator]
static GLOBAL: vision_testalloc::PeakAlloc = vision_testalloc::PeakAlloc;

fn linuxcnc() -> Interpreter {
    Interpreter::new(InterpreterConfig { dialect: Dialect::LinuxCnc, ..InterpreterConfig::default() })
}

/// Runs `text`, counting its moves; the result, the moves and the bytes allocated beyond what
/// was live before (the peak).
fn run_counting(text: &str) -> (Result<(), GcodeError>, u64, usize) {
    let mut interp = linuxcnc();
    let mut moves = 0u64;
    let (result, peak) = vision_testalloc::peak_during(|| {
        interp
            .run(text, None, &mut |e: &Event| {
                if matches!(e, Event::Linear(_) | Event::Arc(_)) {
                    moves += 1;
                }
            })
            .map(drop)
    });
    (result, moves, peak)
}

fn problem(result: Result<(), GcodeError>) -> RunProblem {
    match result {
        Err(GcodeError::Run { problem, .. }) => problem,
        other => panic!("expected a run error, got {other:?}"),
    }
}

#[test]
fn a_cycle_at_the_repeat_bound_streams_its_moves_in_little_memory() {
    let text = format!("G20 G90 F10\nG0 Z1\nG91 G81 X0.001 Y0 Z-0.1 R0.1 L{MAX_REPEATS}\nG80\nM2");
    let (result, moves, extra) = run_counting(&text);
    result.expect("runs");
    // The G0, the rise to R (Z1.1), then per hole: over at R, down, back up.
    assert_eq!(moves, 2 + 3 * u64::from(MAX_REPEATS));
    // Held whole, 300 000 moves took tens of megabytes before the cycle was streamed.
    assert!(extra < 1_000_000, "a cycle of {moves} moves took {extra} bytes");
}

#[test]
fn a_long_loop_streams_in_little_memory() {
    let text = format!("G20 G90 F100\no100 repeat [{MAX_REPEATS}]\nG1 X1\nG1 X0\no100 endrepeat\nM2");
    let (result, moves, extra) = run_counting(&text);
    result.expect("runs");
    assert_eq!(moves, 2 * u64::from(MAX_REPEATS));
    assert!(extra < 1_000_000, "a loop of {moves} moves took {extra} bytes");
}

#[test]
fn repeat_counts_over_the_bound_are_refused_with_their_own_message() {
    // Issue 26's program: a 3 GB allocation before.
    let (result, moves, _) = run_counting("G20 G90 F10\nG0 Z1\nG91 G81 X0.001 Y0 Z-0.1 R0.1 L10000000\nG80\nM2");
    let error = result.expect_err("refused");
    assert_eq!(moves, 1, "the G0 ran, the cycle line emitted nothing");
    assert_eq!(error.line(), 3);
    assert_eq!(
        error.to_string(),
        "line 3: G81: `L10000000` exceeds the 100000 repeat bound: split the holes over several lines"
    );
    let over = MAX_REPEATS + 1;
    for (text, message) in [
        (format!("G20 G90 F10\nG81 X1 Z-1 R1 L{over}"), "G81: `L100001` exceeds the 100000 repeat bound: split"),
        (
            format!("G20 G90 F10\nM98 P100 L{over}\nM2\nO100\nM99"),
            "M98: `L100001` exceeds the 100000 repeat bound: call",
        ),
        (format!("G20 G90 F10\nG2 X0 Y0 I1 J0 P{over}\nM2"), "G2: `P100001` exceeds the 100000 repeat bound: program"),
        (format!("G20 G90 F10\no1 repeat [{over}]\no1 endrepeat\nM2"), "repeat: `[100001]` exceeds the 100000 repeat"),
        // Issue 33: a huge count is shown as every message shows numbers.
        ("G20 G90 F10\nM98 P100 L[10**15]\nM2\nO100\nM99".to_string(), "M98: `L1e15` exceeds the 100000 repeat bound"),
        ("G20 G90 F10\no1 repeat [10**15]\no1 endrepeat\nM2".to_string(), "repeat: `[1e15]` exceeds the 100000 repeat"),
    ] {
        let (result, _, _) = run_counting(&text);
        let problem = problem(result);
        assert!(matches!(problem, RunProblem::RepeatBound { limit: MAX_REPEATS, .. }), "{text}: {problem:?}");
        assert!(problem.to_string().starts_with(message), "{text}: {problem}");
    }
    // The bound itself is allowed.
    let (result, _, _) = run_counting(&format!("G20 G90 F10\nM98 P100 L{MAX_REPEATS}\nM2\nO100\nM99"));
    result.expect("at the bound");
}

#[test]
fn a_cycle_of_too_many_pecks_is_refused_before_it_emits() {
    // 99 999 pecks of 3 moves per hole, 100 holes: 30 million moves.
    let (result, moves, _) = run_counting("G20 G90 F10\nG0 Z1\nG91 G83 X0.001 Z-1 R0.1 Q0.00001 L100\nM2");
    assert_eq!(moves, 1);
    match problem(result) {
        RunProblem::CycleTooManyMoves { code: "G83", limit } => assert_eq!(limit, MAX_CYCLE_MOVES),
        other => panic!("expected the cycle's move bound, got {other:?}"),
    }
}

#[test]
fn a_cycle_that_fails_at_a_late_hole_emits_nothing() {
    // The 4th hole lies beyond ±1e9 units: the line fails whole, as every line does.
    let (result, moves, _) = run_counting("G20 G90 F10\nG0 Z1\nG91 G81 X300000000 Z-1 R0.1 L5\nM2");
    assert!(matches!(problem(result), RunProblem::BeyondRange { .. }));
    assert_eq!(moves, 1, "only the G0");
}

#[test]
fn chunked_events_are_the_same_events_in_bounded_chunks() {
    // Unmeasured, but large: alone, so its allocations do not show in another test's peak.
    vision_testalloc::alone(chunked_events_in_bounded_chunks);
}

fn chunked_events_in_bounded_chunks() {
    // A polyline (G51 scales X and Y apart) of about 10 000 segments, pecks, holes with a dwell.
    let text = "G20 G90 F10\nG51 X2 Y1\nG2 X0 Y0 I1 J0\nG50\nG0 Z1\nG91 G83 X0.5 Z-0.3 R0.1 Q0.05 L3\nG80\n\
                G90 G82 X1 Y1 Z-0.2 R0.1 P0.5\nG80\nM2";
    let config = InterpreterConfig { max_arc_segments: 20_000, chord_tolerance: 1e-7, ..InterpreterConfig::default() };
    let mut whole = Vec::new();
    Interpreter::new(config.clone()).run(text, None, &mut whole).expect("runs");
    let mut interp = Interpreter::new(config);
    interp.set_chunked_events(true);
    let mut chunked: Vec<Event> = Vec::new();
    interp.run(text, None, &mut chunked).expect("runs");
    let mut largest = 0;
    loop {
        let before = chunked.len();
        let more = interp.emit_held(&mut chunked);
        largest = largest.max(chunked.len() - before);
        if !more {
            break;
        }
    }
    assert!(whole.len() > 9000, "{} events", whole.len());
    assert_eq!(chunked, whole);
    assert!(largest <= 1024, "a chunk of {largest} events");
}
