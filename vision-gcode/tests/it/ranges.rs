//! One range rule for every coordinate, offset and parameter that reaches the machine
//! (issue 17 items 3 and 4): beyond ±`MAX_COORDINATE` machine units is an error naming what,
//! as the path planner refuses it, and absurd G68 rotations and G51 scales are refused.
#![expect(clippy::float_cmp, reason = "tests compare exact values")]

use vision_gcode::{Event, GcodeError, Interpreter, InterpreterConfig, RunProblem, MAX_COORDINATE};

/// The problem `text` stops with (as the last line), or `None` when it runs.
fn problem(text: &str) -> Option<RunProblem> {
    let mut interp = Interpreter::new(InterpreterConfig::default());
    let mut events: Vec<Event> = Vec::new();
    match interp.run(text, None, &mut events) {
        Ok(_) => None,
        Err(GcodeError::Run { problem, .. }) => Some(problem),
        Err(e) => panic!("unexpected error {e}"),
    }
}

fn beyond(text: &str) -> (String, f64) {
    match problem(text) {
        Some(RunProblem::BeyondRange { what, value }) => (what, value),
        other => panic!("{text:?}: expected BeyondRange, got {other:?}"),
    }
}

#[test]
fn axis_words_beyond_the_range_are_refused_naming_the_word() {
    let (what, value) = beyond("G0 X[1*10**308]");
    assert!(what.contains("X word"), "{what}");
    assert_eq!(value, 1e308);
    let (what, _) = beyond("G10 L2 P1 Y[0-10**308]");
    assert!(what.contains("G10") && what.contains("Y word"), "{what}");
    beyond("G52 Z2000000000");
    beyond("G92 X[1*10**12]");
    beyond("G68 X10000000000 Y0 R1");
    // The bound is in machine units (inch here): 2e10 mm is 7.9e8 inch, 3e10 mm 1.2e9 inch.
    assert_eq!(problem("G21 G0 X20000000000"), None);
    beyond("G21 G0 X30000000000");
    // The bound itself is accepted.
    assert_eq!(problem(&format!("G0 X{MAX_COORDINATE} Y-{MAX_COORDINATE}")), None);
}

#[test]
fn moves_and_offsets_that_add_up_beyond_the_range_are_refused() {
    // Each word is in range; the machine position is not.
    let (what, value) = beyond("G91 G0 X600000000\nG0 X600000000");
    assert!(what.contains("machine position"), "{what}");
    assert_eq!(value, 1.2e9);
    beyond("G10 L2 P1 X900000000\nG0 X900000000");
    // G92 / G10 L20 offsets computed from in-range words.
    let (what, _) = beyond("G0 X900000000\nG92 X-900000000");
    assert!(what.contains("G92"), "{what}");
    let (what, _) = beyond("G0 X900000000\nG10 L20 P1 X-900000000");
    assert!(what.contains("G10 L20"), "{what}");
}

#[test]
fn offset_parameters_are_bounded_and_other_parameters_are_not() {
    let (what, _) = beyond("#5221 = [1*10**308]");
    assert!(what.contains("#5221"), "{what}");
    beyond("#5242 = -2000000000"); // G55 Y
    beyond("#5213 = 2000000000"); // G92 Z
    beyond("#5161 = 2000000000"); // G28 X
                                  // Not offsets: scratch values may be anything finite.
    assert_eq!(problem("#1 = [1*10**308]\n#5224 = [1*10**308]\n#<_big> = [1*10**300]"), None);
}

#[test]
fn a_handler_cannot_set_a_tool_offset_beyond_the_range() {
    let mut interp = Interpreter::new(InterpreterConfig::default());
    assert!(matches!(
        interp.set_tool_offset(1, 1e308, 0.0),
        Err(GcodeError::Run { problem: RunProblem::BeyondRange { .. }, .. })
    ));
    interp.set_tool_offset(1, 1.0, -2.0).expect("in range");
    assert_eq!(interp.tool_offset(1).map(|o| [o.x, o.y]), Some([1.0, -2.0]));
}

#[test]
fn absurd_rotations_and_scales_are_refused_naming_the_word() {
    for (text, letter) in
        [("G68 R[1*10**300]", 'R'), ("G68 X0 Y0 R-361", 'R'), ("G51 X[1*10**300]", 'X'), ("G51 Y[10**-9]", 'Y')]
    {
        match problem(text) {
            Some(RunProblem::OutOfRange { letter: l, .. }) => assert_eq!(l, letter, "{text}"),
            other => panic!("{text:?}: expected OutOfRange, got {other:?}"),
        }
    }
    for text in ["G68 R360", "G68 R-359.9", "G51 X1000 Y-0.001", "G51 X-1 Y1"] {
        assert_eq!(problem(text), None, "{text}");
    }
}
