//! The comment rules of the dialects on random lines of words, parentheses and text: nothing
//! panics, every refusal is a typed syntax error, and the rules never disagree on a line two of
//! them read. Mach4's rule (balanced where the line balances the comment, else the first `)`)
//! reads every line RS274/NGC's first-`)` rule reads and every line the nesting rule reads,
//! each with the same meaning; LinuxCNC's (rs274's) refuses any `(` inside a comment.

use proptest::prelude::*;
use vision_gcode::{Dialect, GcodeError, Interpreter, InterpreterConfig, SyntaxProblem, Xyz};

/// 384 cases per property in CI, as `fuzz.rs`; `FUZZ_CASES` raises it.
fn cases() -> u32 {
    std::env::var("FUZZ_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(384)
}

/// Where `line` leaves the machine under `dialect`, or its error.
fn end(dialect: Dialect, line: &str) -> Result<Xyz, GcodeError> {
    let mut interp = Interpreter::new(InterpreterConfig { dialect, ..InterpreterConfig::default() });
    interp.run(line, None, &mut Vec::new()).map(|_| interp.machine_position())
}

/// The line with its comments removed by RS274/NGC's rule (a comment ends at its first `)`),
/// or `None` when a comment is not closed.
fn flat_code(line: &str) -> Option<String> {
    let mut out = String::new();
    let mut rest = line;
    while let Some(open) = rest.find('(') {
        out.push_str(&rest[..open]);
        out.push(' ');
        let close = rest[open..].find(')')? + open;
        rest = &rest[close + 1..];
    }
    out.push_str(rest);
    Some(out)
}

/// The line with its comments removed by the nesting rule, or `None` when one is not balanced.
fn nested_code(line: &str) -> Option<String> {
    let mut out = String::new();
    let mut depth = 0usize;
    for c in line.chars() {
        match c {
            '(' => {
                if depth == 0 {
                    out.push(' ');
                }
                depth += 1;
            }
            ')' if depth > 0 => depth -= 1,
            _ if depth == 0 => out.push(c),
            _ => {}
        }
    }
    (depth == 0).then_some(out)
}

/// Lines of words, comments and text; no piece starts with a digit, sign or point, so the
/// models' blank in place of a comment never joins two pieces into one number (the parser ends
/// a word at a comment).
fn line() -> impl Strategy<Value = String> {
    let piece = prop::sample::select(vec![
        "G0",
        "G1",
        "X1",
        "Y-2",
        "Z0.5",
        "F10",
        "X",
        "(",
        ")",
        "(",
        ")",
        " a ",
        "inch",
        ",",
        "#1=2",
        ";",
        " ",
        "(+/- 2.5, +/- 4.0)",
        " 1 -> 2 ",
    ]);
    prop::collection::vec(piece, 0..14).prop_map(|v| format!("G0 {}", v.concat()))
}

fn same(a: Xyz, b: Xyz) -> bool {
    (a.x - b.x).abs() < 1e-12 && (a.y - b.y).abs() < 1e-12 && (a.z - b.z).abs() < 1e-12
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases()))]

    #[test]
    fn the_comment_rules_agree_where_they_overlap(line in line()) {
        let mach4 = end(Dialect::Mach4, &line);
        let seed = end(Dialect::MachineMotion, &line);
        let rs274 = end(Dialect::LinuxCnc, &line);
        // Whatever the first-`)` rule reads without parentheses left over, Mach4 reads the same.
        if let Some(code) = flat_code(&line).filter(|c| !c.contains(')')) {
            if let Ok(want) = end(Dialect::Mach4, &code) {
                let got = mach4.as_ref();
                prop_assert!(got.is_ok_and(|g| same(*g, want)), "{line:?}: {got:?}, first-`)` rule {want:?}");
            }
        }
        // Whatever the nesting rule reads, Mach4 reads the same.
        if let Some(code) = nested_code(&line).filter(|c| !c.contains(')')) {
            if let Ok(want) = end(Dialect::Mach4, &code) {
                let got = mach4.as_ref();
                prop_assert!(got.is_ok_and(|g| same(*g, want)), "{line:?}: {got:?}, nesting rule {want:?}");
            }
        }
        // A line LinuxCNC reads holds no `(` inside a comment: every rule reads it the same.
        if let Ok(want) = &rs274 {
            for got in [&mach4, &seed] {
                prop_assert!(got.as_ref().is_ok_and(|g| same(*g, *want)), "{line:?}: {got:?} vs {want:?}");
            }
        }
        // LinuxCNC refuses a `(` inside a comment wherever the first-`)` rule sees one.
        if let Err(GcodeError::Syntax { problem: SyntaxProblem::NestedComment { open, inner }, .. }) = &rs274 {
            prop_assert!(open < inner, "{line:?}");
        }
        // When Mach4 ended a comment early and the rest failed, the message says where it ended.
        if let Err(e @ GcodeError::Syntax { problem: SyntaxProblem::CommentEndedEarly { open, close, .. }, .. }) = &mach4 {
            prop_assert!(open < close, "{line:?}");
            let said = format!("the comment opened at column {open} ended at the `)` at column {close}");
            prop_assert!(e.to_string().contains(&said), "{e}");
        }
    }

    #[test]
    fn arbitrary_text_with_parentheses_never_panics(text in "[()a-zA-Z0-9 .;#=\\[\\]-]{0,40}") {
        for dialect in Dialect::ALL {
            let _ = end(dialect, &text);
        }
    }
}
