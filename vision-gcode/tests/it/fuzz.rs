//! Bad input is part of the product: the parser and the interpreter never panic on arbitrary
//! text or bytes, or on mutated valid programs, and never emit a non-finite number.
#![expect(clippy::cast_possible_truncation, clippy::cast_sign_loss, reason = "test values are small and whole")]

use proptest::prelude::*;
use vision_gcode::{Context, Event, HandlerError, Interpreter, InterpreterConfig, MCodeHandler, UserMCode};

/// Panics if an event carries NaN or infinity.
fn check_finite(event: &Event) {
    let ok = match event {
        Event::Linear(m) => m.start.is_finite() && m.end.is_finite() && rate_ok(m.rate),
        Event::Arc(a) => {
            a.start.is_finite()
                && a.end.is_finite()
                && a.center.is_finite()
                && a.angle.is_finite()
                && a.feed.is_finite()
        }
        Event::Dwell { seconds, .. } => seconds.is_finite(),
        Event::ToolChange { offset, .. } => offset.is_finite(),
        Event::UserMCode(c) => c.words.iter().all(|(_, v)| v.is_finite()),
        Event::Spindle { speed, .. } => speed.is_none_or(f64::is_finite),
        Event::Output(_) | Event::Coolant { .. } | Event::Stop { .. } | Event::ProgramEnd { .. } => true,
    };
    assert!(ok, "non-finite event {event:?}");
}

fn rate_ok(rate: vision_gcode::Rate) -> bool {
    match rate {
        vision_gcode::Rate::Rapid => true,
        vision_gcode::Rate::Feed(f) => f.is_finite(),
    }
}

/// Runs its comments as G-code and pokes the context with its words: the nested paths get
/// fuzzed too.
struct Echo;

impl MCodeHandler for Echo {
    fn call(&mut self, call: &UserMCode<'_>, ctx: &mut Context<'_>) -> Result<Vec<String>, HandlerError> {
        for &(letter, v) in call.words() {
            match letter {
                'P' => {
                    let _ = ctx.set_pound(v.abs().min(1e6) as u32, v);
                }
                'Q' => {
                    let _ = ctx.dwell(v);
                }
                'T' => {
                    let _ = ctx.set_tool_offset(v.abs().min(1e6) as u32, v, -v);
                }
                _ => {}
            }
        }
        if let Some(first) = call.comments().first() {
            ctx.execute(first)?;
        }
        Ok(call.comments().iter().skip(1).map(|c| (*c).to_string()).collect())
    }
}

fn exercise(text: &str) {
    let config =
        InterpreterConfig { max_arc_segments: 100_000, max_loop_iterations: 10_000, ..InterpreterConfig::default() };
    // A run stops at its first bad line; one run per line parses every line.
    let mut per_line = Interpreter::new(config.clone());
    for line in text.split('\n') {
        let _ = per_line.run(line, None, &mut |e: &Event| check_finite(e));
    }
    let mut interp = Interpreter::new(config);
    let _ = interp.run(text, Some(&mut Echo), &mut |e: &Event| check_finite(e));
    assert!(interp.machine_position().is_finite());
    assert!(interp.program_position().is_finite());
    let _ = interp.run(text, None, &mut |e: &Event| check_finite(e));
    let mut linuxcnc = Interpreter::new(InterpreterConfig {
        dialect: vision_gcode::Dialect::LinuxCnc,
        max_loop_iterations: 10_000,
        ..InterpreterConfig::default()
    });
    let _ = linuxcnc.run(text, None, &mut |e: &Event| check_finite(e));
}

const PROGRAMS: &[&str] = &[
    include_str!("../programs/example1_calibration.nc"),
    include_str!("../programs/example2_verify.nc"),
    include_str!("../programs/example4_rectangle_fit.nc"),
    include_str!("../programs/example6_pound_vars.nc"),
    include_str!("../programs/example7_job_switch.nc"),
    "G90 G21 G61 G17 G90.1\nG0 X500 Y250 Z500\nG3 X0 Y250 I250 J250\nG3 X500 Y250 I250 J250",
    "G90 G21 G61 G18 G90.1\nG0 X500 Y500 Z250\nG3 X0 Z250 I250 K250\nG2 X500 Z250 R-250 P2",
    "G90 G20 F10\nG52 X0.1 Y0.2\nG68 X3 Y2 R0.5\nG51 X1.001 Y0.999\nG0 X6 Y4\nG2 X0 Y4 I-3 J0\nG69 G50 G52 X0 Y0",
    "#1 = [2 * ATAN[1]/[2]] #2 = [#1 MOD 7 ** 2]\nG1 X[#1 / 3] Y-#2 Z[SQRT[ABS[#2]]] F[100 + #1]\nG10 L20 P0 X0\nG92 Y1\nG28.1\nG28 X2",
    "T1 M6 M3\nG4 P0.5\nM4 $1\nM5 A1 P2\nM0\nM1\nM2",
    include_str!("../programs/linuxcnc_flow.ngc"),
    "%\nO0001\nG0 X0\nM98 P1000 L3\nM98 P2000\nM30\nO1000\nG91 G1 X1 F100\nG90\nM99\nO2000\nM98 P1000\nM99\n%",
    "o<s> sub\n#<l> = #1\no1 if [#<l> GT 1]\nG0 X#<l>\no1 else\nG1 Y1 F9\no1 endif\no<s> endsub\no2 repeat [3]\no<s> call [2]\no2 endrepeat\no3 do\n#<_k> = [#<_k> + 1]\no3 while [#<_k> LT 3]",
    "G21 G0 @10 ^90\nG91 G0 ^45\nG0 @-2\nG90 G81 R1 Z-1 F10 @5 ^30\nG91 G81 R.1 Z-.5 ^60 L6\nG90 G80 G2 @5 ^-30 I0 J5\nG10 L2 P0 R30\nG52 X1\nG91 G1 X1\nM2",
    "%\nG17 G40 G49 G80 G90 G20\nT2 M6\nS12000 M3\nG43 H2 M8\nG53 G0 Z0\n/G0 X1\nG0 X0.5 Y0.5 Z0.2\nG98 G81 X1 Y1 Z-0.3 R0.1 F20\nX2\nG99 G83 X3 Q0.1 Z-0.5 R0.1 L2\nG91 G73 X0.5 Z-0.2 R-0.1 Q0.05 L3\nG90 G82 P0.2 Z-0.1 R0.1 X1\nG85 X2\nG89 X3 P0.1\nG80 G0 Z1\nG2 I0.5 F30\nG3 X1 Y1 R0.5 P2\nG64 P0.01 Q0.01\nG43.1 Z0.1\nG49 M9\nG30 G92.1\nM5\n%\nG1 X9",
];

/// 384 cases per property in CI; `FUZZ_CASES=100000 cargo test --release --test it fuzz::` for a
/// deeper local run.
fn cases() -> u32 {
    std::env::var("FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(384)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases()))]

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,300}") {
        exercise(&text);
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..300)) {
        exercise(&String::from_utf8_lossy(&bytes));
    }

    #[test]
    fn gcode_shaped_text_never_panics(text in "[GMXYZIJKRPFTLNQSHO#$@^%<>\\[\\]0-9.+*/ ()=;EQANDORSINMCOS\n-]{0,300}") {
        exercise(&text);
    }

    #[test]
    fn mutated_valid_programs_never_panic(
        which in 0..PROGRAMS.len(),
        edits in prop::collection::vec((any::<prop::sample::Index>(), 0u8..4, "[ -~\n]{1,6}"), 1..8),
    ) {
        let mut text: Vec<char> = PROGRAMS[which].chars().collect();
        for (at, op, piece) in edits {
            let i = if text.is_empty() { 0 } else { at.index(text.len()) };
            match op {
                0 => text.splice(i..i, piece.chars()).for_each(drop),
                1 if !text.is_empty() => {
                    let end = (i + piece.len()).min(text.len());
                    text.drain(i..end).for_each(drop);
                }
                2 if !text.is_empty() => {
                    let end = (i + piece.len()).min(text.len());
                    text.splice(i..end, piece.chars()).for_each(drop);
                }
                _ => {
                    // Duplicate a slice (repeats words, lines, brackets).
                    let end = (i + 12).min(text.len());
                    let copy: Vec<char> = text[i..end].to_vec();
                    text.splice(i..i, copy).for_each(drop);
                }
            }
        }
        exercise(&text.into_iter().collect::<String>());
    }
}

proptest! {
    /// LinuxCNC's polar words with any finite values, absolute or incremental, in moves and
    /// canned cycles: a finite position or a typed error; an absolute `@r ^a` move lands at
    /// distance |r| from the program origin.
    #[test]
    fn polar_words_run_or_are_refused_never_non_finite(
        r in prop_oneof![-1e7..1e7f64, -1.0..1.0f64, Just(0.0)],
        a in prop_oneof![-1e9..1e9f64, -360.0..360.0f64, Just(0.0)],
        start in (-100.0..100.0f64, -100.0..100.0f64),
        incremental in any::<bool>(),
        cycle in any::<bool>(),
    ) {
        let mut interp = Interpreter::new(InterpreterConfig {
            dialect: vision_gcode::Dialect::LinuxCnc,
            ..InterpreterConfig::default()
        });
        let mode = if incremental { "G91" } else { "G90" };
        let motion = if cycle { "G81 R1 Z-1" } else { "G1" };
        let text = format!("%\nG0 X{} Y{}\n{mode} {motion} @{r} ^{a} F10\n%", start.0, start.1);
        let result = interp.run(&text, None, &mut |e: &Event| check_finite(e));
        prop_assert!(interp.machine_position().is_finite());
        if result.is_ok() && !incremental && !cycle {
            let p = interp.program_position();
            prop_assert!((p.x.hypot(p.y) - r.abs()).abs() <= 1e-9 * r.abs().max(1.0), "{p:?} for @{r}");
        }
        if let Err(e) = result {
            prop_assert!(matches!(e, vision_gcode::GcodeError::Run { .. }), "{e}");
        }
    }
}

#[test]
fn huge_and_degenerate_values_are_errors_not_numbers() {
    for text in [
        "G0 X1e308",
        "G0 X99999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999.0",
        "G51 X1e300 Y1e300\nG0 X1e300",
        "G1 F1 X[EXP[1000]]",
        "G2 X1 Y0 I1e-300 J0 F1",
        "G0 X[0/0]",
        "#1=[-1] G0 X#1 Y#[#1]",
    ] {
        exercise(text);
    }
}

/// Long inputs (issue 17): megabyte lines and a million-line program are refused or run in
/// bounded time, never panic. (Deeply nested or megabyte expressions are the expression
/// bounds' own tests.)
#[test]
fn megabyte_lines_and_million_line_programs_run_or_are_refused() {
    const MB: usize = 1 << 20;
    let started = std::time::Instant::now();
    for line in [
        format!("({})", "x".repeat(MB)),
        format!("G0 X{}", "1".repeat(MB)),
        format!("G0 X0.{}", "0".repeat(MB)),
        "G0 X1 ".repeat(MB / 6),
        format!("G0 X1 ;{}", "\u{7}".repeat(MB)),
        "\u{0}\u{ff}".repeat(MB / 2),
    ] {
        let mut interp = Interpreter::new(InterpreterConfig::default());
        let _ = interp.run(&line, None, &mut |e: &Event| check_finite(e));
        assert!(interp.machine_position().is_finite());
    }
    // A million lines in a release build, a tenth in a debug build (same code paths).
    let lines = if cfg!(debug_assertions) { 100_000 } else { 1_000_000 };
    let program = "G1 X1 Y2 F10\nG0 X0 Y0\n".repeat(lines / 2);
    let mut interp = Interpreter::new(InterpreterConfig::default());
    let mut moves = 0usize;
    interp
        .run(&program, None, &mut |e: &Event| {
            check_finite(e);
            moves += usize::from(matches!(e, Event::Linear(_)));
        })
        .expect("a long valid program runs");
    assert_eq!(moves, lines, "every line's move");
    assert!(started.elapsed().as_secs() < 60, "long inputs took {:?}", started.elapsed());
}
