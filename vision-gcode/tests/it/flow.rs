//! LinuxCNC o-word subroutines, control flow and named parameters, checked against LinuxCNC:
//! the expected moves are what its `rs274` printed for the same program and subroutine file.

#![expect(clippy::float_cmp, reason = "tests compare exact values")]

use vision_gcode::{GcodeError, Interpreter, InterpreterConfig, RunProblem, SyntaxProblem, Xyz};
use vision_math::LengthUnit;

use crate::common;
use common::moves;

/// Written for these tests (every o-word form); `ext.ngc` is [`EXT`], on the subroutine path.
const PROGRAM: &str = include_str!("../programs/linuxcnc_flow.ngc");

const EXT: &str = "o<ext> sub\nG0 X#1 Y#1\no<ext> return\no<ext> endsub\n";

fn mm(path: Vec<std::path::PathBuf>) -> Interpreter {
    Interpreter::new(InterpreterConfig { subroutine_path: path, ..InterpreterConfig::new(LengthUnit::Millimetre) })
}

fn run_problem(interp: &mut Interpreter, text: &str) -> RunProblem {
    match interp.run(text, None, &mut Vec::new()) {
        Err(GcodeError::Run { problem, .. }) => problem,
        other => panic!("expected a run error for {text:?}, got {other:?}"),
    }
}

#[test]
fn subroutines_loops_and_named_parameters_match_rs274() {
    let dir = std::env::temp_dir().join(format!("vision-gcode-flow-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    std::fs::write(dir.join("ext.ngc"), EXT).expect("sub file");
    let mut interp = mm(vec![dir.clone()]);
    let mut events = Vec::new();
    let outcome = interp.run(PROGRAM, None, &mut events);
    std::fs::remove_dir_all(&dir).ok();
    outcome.expect("runs");
    let (f, r) = (false, true);
    #[rustfmt::skip]
    let want = [
        (f, [5.0, 0.0, 0.0]), (f, [10.0, 1.0, 0.0]), (f, [20.0, 2.0, 0.0]),
        (f, [21.0, 2.0, 0.0]), (f, [22.0, 2.0, 0.0]), (f, [22.0, 3.0, 0.0]), (f, [22.0, 4.0, 0.0]),
        (f, [22.0, 4.0, -1.0]), (f, [22.0, 4.0, -2.0]), (f, [22.0, 4.0, -3.0]),
        (f, [22.0, 4.0, -4.0]), (f, [22.0, 4.0, -6.0]),
        (r, [7.0, 7.0, -6.0]), (r, [7.0, 7.0, 6.0]),
    ];
    assert_eq!(moves(&events), want);
    // #1 came back from the call (7 inside it, 6 after).
    assert_eq!(interp.param(1), 6.0);
}

#[test]
fn named_parameters_are_scoped_and_checked() {
    let mut interp = mm(Vec::new());
    // Globals (`_`) are shared; locals belong to their call; names ignore case and blanks.
    let text = "o<s> sub\n#<local> = 5\n#<_G> = [#<_g> + #1]\no<s> endsub\n#<_g> = 1\n#<local> = 2\no<s> call [3]\nG0 X#<_ g> Y#<LOCAL>";
    interp.run(text, None, &mut Vec::new()).expect("runs");
    assert_eq!(interp.machine_position(), Xyz::new(4.0, 2.0, 0.0));
    assert_eq!(run_problem(&mut interp, "G0 X#<nothing>"), RunProblem::UndefinedName { name: "nothing".into() });
    // A failing line takes its named writes back.
    let mut interp = mm(Vec::new());
    let err = interp.run("#<a> = 1\n#<a> = 2 G0 X[1/0]\nG0 X#<a>", None, &mut Vec::new());
    assert!(err.is_err());
    interp.run("G0 X#<a>", None, &mut Vec::new()).expect("a is 1");
    assert_eq!(interp.machine_position().x, 1.0);
}

#[test]
fn control_flow_errors_are_named() {
    let mut interp = mm(Vec::new());
    assert_eq!(run_problem(&mut interp, "o<nowhere> call"), RunProblem::UnknownSubroutine { label: "nowhere".into() });
    assert_eq!(run_problem(&mut interp, "o1 sub\no1 call\no1 endsub\no1 call"), RunProblem::CallsTooDeep { limit: 10 });
    assert_eq!(run_problem(&mut interp, "o1 return"), RunProblem::FlowOutsideCall);
    let mut looping = Interpreter::new(InterpreterConfig { max_loop_iterations: 1000, ..InterpreterConfig::default() });
    assert_eq!(run_problem(&mut looping, "o1 while [1]\no1 endwhile"), RunProblem::TooManyIterations { limit: 1000 });
    for (text, line) in [("o1 if [1]\nG0 X1", 1), ("o1 while [1]\no2 endwhile", 2), ("o1 foo", 1), ("o1 break", 1)] {
        match interp.run(text, None, &mut Vec::new()) {
            Err(GcodeError::Syntax { line: l, problem: SyntaxProblem::BadOWord { .. }, .. }) => {
                assert_eq!(l, line, "{text}");
            }
            other => panic!("{text}: {other:?}"),
        }
    }
    match interp.run("G0 X1 o1 if [1]", None, &mut Vec::new()) {
        Err(GcodeError::Syntax { problem: SyntaxProblem::OWordNotFirst, .. }) => {}
        other => panic!("{other:?}"),
    }
    // Lines before the first o-word stream as usual; the flow runs from there.
    let mut interp = mm(Vec::new());
    let mut events = Vec::new();
    interp.run("G0 X1\no1 repeat [3]\nG91 G0 X1\no1 endrepeat\nG90 G0 Y1", None, &mut events).expect("runs");
    assert_eq!(moves(&events).iter().map(|m| m.1[0]).collect::<Vec<_>>(), [1.0, 2.0, 3.0, 4.0, 4.0]);
}

#[test]
fn fanuc_subprograms_m98_m99() {
    let program = "%\nO0001 (main)\nG90 G0 X0 Y0\nM98 P1000 L3\nG0 Y5\nM98 P2000\nM30\nO1000 (step)\nG91 G1 X1 F100\nG90\nM99\nO2000\nM98 P1000\nM99\n%";
    let mut interp = mm(Vec::new());
    let mut events = Vec::new();
    let outcome = interp.run(program, None, &mut events).expect("runs");
    assert_eq!(outcome, vision_gcode::RunOutcome::Ended { line: 7, code: 30 });
    #[rustfmt::skip]
    let want = [
        (true, [0.0, 0.0, 0.0]),
        (false, [1.0, 0.0, 0.0]), (false, [2.0, 0.0, 0.0]), (false, [3.0, 0.0, 0.0]),
        (true, [3.0, 5.0, 0.0]),
        (false, [4.0, 5.0, 0.0]),
    ];
    assert_eq!(moves(&events), want);
    let mut interp = mm(Vec::new());
    assert_eq!(run_problem(&mut interp, "G0 X1\nM99"), RunProblem::FlowOutsideCall);
    assert_eq!(run_problem(&mut interp, "M98 P12"), RunProblem::UnknownSubroutine { label: "12".into() });
    assert_eq!(
        run_problem(&mut interp, "o12 sub\no12 endsub\nM98 P12"),
        RunProblem::UnknownSubroutine { label: "O12".into() }
    );
    assert!(matches!(run_problem(&mut interp, "M98 P1 L0\nO1\nM99"), RunProblem::OutOfRange { letter: 'L', .. }));
}

#[test]
fn lines_that_need_the_whole_program_are_recognised() {
    for line in ["o100 sub", "  /N20 O<pocket> call [1]", "G0 X1 M98 P100 L2", "M 9 9", "m99 (back)"] {
        assert!(vision_gcode::needs_program(line), "{line}");
    }
    for line in ["G0 X1", "M9", "M980", "M9.8", "G1 X98", "N10 G0 (o-ring)", ""] {
        assert!(!vision_gcode::needs_program(line), "{line}");
    }
}
