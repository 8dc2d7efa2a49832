//! The user M-code extension point: what a handler sees and may do.

#![expect(clippy::float_cmp, reason = "tests compare exact values")]

use vision_gcode::{
    Context, Event, GcodeError, HandlerError, Interpreter, InterpreterConfig, MCodeHandler, RunProblem, Tool,
    UserMCode, Xyz,
};
use vision_math::LengthUnit;

/// A handler made of a closure.
struct Handler<F>(F);

impl<F> MCodeHandler for Handler<F>
where
    F: FnMut(&UserMCode<'_>, &mut Context<'_>) -> Result<Vec<String>, HandlerError>,
{
    fn call(&mut self, call: &UserMCode<'_>, ctx: &mut Context<'_>) -> Result<Vec<String>, HandlerError> {
        (self.0)(call, ctx)
    }
}

fn interp() -> Interpreter {
    Interpreter::new(InterpreterConfig::default())
}

#[test]
fn the_call_carries_its_words_comments_and_line() {
    let mut seen = Vec::new();
    let mut h = Handler(|call: &UserMCode<'_>, _: &mut Context<'_>| {
        seen.push((call.code(), call.line(), call.word('c'), call.word('$'), call.comment().map(str::to_string)));
        Ok(Vec::new())
    });
    interp().run("G0 X1\nm283 c1 $2 (Data:\"VisionLastOffsetX\") ; tail", Some(&mut h), &mut Vec::new()).expect("runs");
    assert_eq!(seen, vec![(283, 2, Some(1.0), Some(2.0), Some("Data:\"VisionLastOffsetX\"".to_string()))]);
}

#[test]
fn execute_is_synchronous_and_its_events_carry_the_mcode_line() {
    let mut interp = interp();
    let mut positions = Vec::new();
    let mut h = Handler(|_: &UserMCode<'_>, ctx: &mut Context<'_>| {
        for _ in 0..3 {
            ctx.execute("G91 G0 X0.1 Y0\nG90")?;
            positions.push(ctx.program_position().x);
        }
        ctx.dwell(0.5)?;
        Ok(vec!["G0 Y2".to_string()])
    });
    let mut events = Vec::new();
    interp.run("G0 X1\nM200\nG0 Z1", Some(&mut h), &mut events).expect("runs");
    assert_eq!(positions.len(), 3);
    for (p, want) in positions.iter().zip([1.1, 1.2, 1.3]) {
        assert!((p - want).abs() < 1e-12);
    }
    let lines: Vec<u32> = events.iter().map(Event::line).collect();
    assert_eq!(lines, vec![1, 2, 2, 2, 2, 2, 3], "moves, the dwell, the returned line, then line 3");
    assert_eq!(events[4], Event::Dwell { line: 2, seconds: 0.5 });
    assert!((interp.machine_position() - Xyz::new(1.3, 2.0, 1.0)).norm() < 1e-12);
}

#[test]
fn parameters_assignments_and_read_only_values() {
    let mut interp = interp();
    let mut h = Handler(|_: &UserMCode<'_>, ctx: &mut Context<'_>| {
        // The line's own assignment is written before the call.
        assert_eq!(ctx.pound(1)?, 5.0);
        ctx.set_pound(500, 1.25)?;
        assert!(matches!(
            ctx.set_pound(5420, 1.0),
            Err(GcodeError::Run { line: 1, problem: RunProblem::ReadOnlyParameter { index: 5420, .. } })
        ));
        assert!(ctx.pound(0).is_err() && ctx.pound(10_000).is_err());
        assert!(ctx.set_pound(7, f64::NAN).is_err());
        Ok(Vec::new())
    });
    interp.run("#1=5 M281", Some(&mut h), &mut Vec::new()).expect("runs");
    assert_eq!(interp.param(500), 1.25);
    assert_eq!(interp.param(1), 5.0);
}

#[test]
fn tool_offsets_units_positions_and_alignment_in_current_units() {
    let mut interp = interp();
    interp.set_tool(98, Tool { offset: Xyz::new(1.0, 0.0, 0.0), outputs: None });
    let mut h = Handler(|_: &UserMCode<'_>, ctx: &mut Context<'_>| {
        assert_eq!(ctx.units(), LengthUnit::Millimetre);
        assert_eq!(ctx.active_tool(), 98);
        assert_eq!(ctx.tool_offset(98)?, Xyz::new(25.4, 0.0, 0.0));
        assert!((ctx.program_position() - Xyz::new(25.4, 0.0, 0.0)).norm() < 1e-12);
        // Machine units: program 1 in + G52 0.1 in − tool 1 in.
        assert!((ctx.machine_position() - Xyz::new(0.1, 0.0, 0.0)).norm() < 1e-12);
        let chain = ctx.active_alignment().expect("G52 active");
        assert!((chain.shift.x - 2.54).abs() < 1e-12);
        ctx.set_tool_offset(98, 50.8, 0.0)?;
        assert!(ctx.tool_offset(0).is_ok() && ctx.tool_offset(999).is_err());
        assert!(ctx.set_tool_offset(999, 0.0, 0.0).is_err());
        Ok(Vec::new())
    });
    interp.run("G21 G52 X2.54\nT98 M6\nG0 X25.4 Y0\nM283 C1", Some(&mut h), &mut Vec::new()).expect("runs");
    assert_eq!(interp.tools().get(98).map(|t| t.offset), Some(Xyz::new(2.0, 0.0, 0.0)));
    assert_eq!(interp.config().tools.get(98), interp.tools().get(98), "one live tool table");
    // The machine stayed; the program point moved with the offset: 0.1 + 2 − 0.1 in = 50.8 mm.
    assert!((interp.machine_position() - Xyz::new(0.1, 0.0, 0.0)).norm() < 1e-12);
    assert!((interp.program_position().x - 50.8).abs() < 1e-9);
}

#[test]
fn handler_failures_and_nested_errors_name_the_mcode_line() {
    let mut failing = Handler(|_: &UserMCode<'_>, _: &mut Context<'_>| {
        Err(HandlerError::Failed("K matrix is zero; run M283 to calibrate first".into()))
    });
    let err = interp().run("G0 X1\nM281", Some(&mut failing), &mut Vec::new()).expect_err("fails");
    assert_eq!(err.to_string(), "line 2: M281 failed: K matrix is zero; run M283 to calibrate first");

    let mut nested = Handler(|_: &UserMCode<'_>, ctx: &mut Context<'_>| {
        ctx.execute("G0 X1\nM281")?;
        Ok(Vec::new())
    });
    let mut interp = interp();
    let err = interp.run("\n\nM283 C1", Some(&mut nested), &mut Vec::new()).expect_err("nested user M-code");
    match &err {
        GcodeError::HandlerGcode { line: 3, code: 283, inner } => {
            assert_eq!(**inner, GcodeError::Run { line: 2, problem: RunProblem::NestedUserMCode { code: 281 } });
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(interp.machine_position().x, 1.0, "the handler's first line ran");

    let mut ends = Handler(|_: &UserMCode<'_>, _: &mut Context<'_>| Ok(vec!["G0 X2".into(), "M30".into()]));
    let err = interp.run("M282", Some(&mut ends), &mut Vec::new()).expect_err("M30 in returned G-code");
    assert!(matches!(err, GcodeError::HandlerGcode { line: 1, code: 282, ref inner }
        if matches!(**inner, GcodeError::Run { line: 2, problem: RunProblem::EndInHandler { code: 30 } })));
    let mut bad = Handler(|_: &UserMCode<'_>, _: &mut Context<'_>| Ok(vec!["G0 X[".into()]));
    let err = interp.run("M282", Some(&mut bad), &mut Vec::new()).expect_err("syntax error in returned G-code");
    assert!(matches!(err, GcodeError::HandlerGcode { line: 1, code: 282, ref inner } if inner.column() == Some(6)));
}

#[test]
fn the_user_range_is_configurable_and_builtins_win() {
    let mut interp = Interpreter::new(InterpreterConfig { user_mcodes: 3..=299, ..InterpreterConfig::default() });
    let mut calls = Vec::new();
    let mut h = Handler(|call: &UserMCode<'_>, _: &mut Context<'_>| {
        calls.push(call.code());
        Ok(Vec::new())
    });
    let mut events = Vec::new();
    interp.run("T1 M6\nM3\nM250", Some(&mut h), &mut events).expect("runs");
    assert!(events.iter().any(|e| matches!(e, Event::Output(_))), "M3 stays built in");
    let err = interp.run("M300", Some(&mut h), &mut Vec::new()).expect_err("outside the range");
    assert_eq!(calls, vec![250]);
    assert!(matches!(
        err,
        GcodeError::Run { problem: RunProblem::UnknownMCode { code: 300, user_low: 3, user_high: 299 }, .. }
    ));
}

#[test]
fn a_standalone_context_serves_a_host() {
    let mut interp = interp();
    let mut events = Vec::new();
    {
        let mut ctx = interp.context(&mut events);
        assert_eq!(ctx.line(), 0);
        ctx.execute("G0 X1\nG0 Y1").expect("runs");
        ctx.dwell(0.1).expect("dwell");
        assert!(ctx.execute("M281").is_err(), "no handler outside a program");
        assert_eq!(ctx.interpreter().coordinate_system(), 1);
    }
    let lines: Vec<u32> = events.iter().map(Event::line).collect();
    assert_eq!(lines, vec![1, 2, 0]);
    assert_eq!(interp.machine_position(), Xyz::new(1.0, 1.0, 0.0));
    interp.set_machine_position(Xyz::new(5.0, 5.0, 5.0)).expect("finite");
    assert_eq!(interp.program_position(), Xyz::new(5.0, 5.0, 5.0));
    assert!(interp.set_machine_position(Xyz::new(f64::NAN, 0.0, 0.0)).is_err());
    interp.set_param(5221, 1.0).expect("G54 X origin");
    assert_eq!(interp.program_position().x, 4.0);
    interp.reset();
    assert_eq!(interp.motion_mode(), None);
}
