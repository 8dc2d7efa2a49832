//! A runaway generated line (issue 17 item 16, `1+1+…` over megabytes) is refused with a clear
//! message, and refusing it takes little memory beyond the text itself: a global allocator in
//! this test binary tracks the peak of live bytes.
#![expect(clippy::float_cmp, reason = "tests compare exact values")]

use vision_gcode::{Event, GcodeError, Interpreter, InterpreterConfig, SyntaxProblem};

#[global_allocator]
static GLOBAL: vision_testalloc::PeakAlloc = vision_testalloc::PeakAlloc;

/// The documented limit: operands in one line's expressions.
const LIMIT: usize = 10_000;

/// `#1 = [1+1+…]` with `operands` ones.
fn sum_line(operands: usize) -> String {
    let mut text = String::with_capacity(8 + 2 * operands);
    text.push_str("#1 = [1");
    for _ in 1..operands {
        text.push_str("+1");
    }
    text.push(']');
    text
}

fn run(text: &str) -> (Result<(), GcodeError>, f64) {
    let mut interp = Interpreter::new(InterpreterConfig::default());
    let mut events: Vec<Event> = Vec::new();
    let result = interp.run(text, None, &mut events).map(drop);
    (result, interp.param(1))
}

#[test]
fn a_megabyte_expression_is_refused_in_little_memory() {
    let text = sum_line(5_000_000); // 10 MB
    let ((result, _), extra) = vision_testalloc::peak_during(|| run(&text));
    match result {
        Err(GcodeError::Syntax { line: 1, problem: SyntaxProblem::TooLong { limit }, .. }) => {
            assert_eq!(limit, LIMIT);
        }
        other => panic!("expected TooLong, got {other:?}"),
    }
    assert!(extra < 2_000_000, "refusing a 10 MB line took {extra} bytes beyond the text");
}

#[test]
fn expressions_up_to_the_limit_run() {
    let (result, value) = run(&sum_line(LIMIT));
    result.expect("within the limit");
    assert_eq!(value, LIMIT as f64);
    let (result, _) = run(&sum_line(LIMIT + 1));
    assert!(matches!(result, Err(GcodeError::Syntax { problem: SyntaxProblem::TooLong { .. }, .. })), "{result:?}");
}
