#![expect(clippy::float_cmp, reason = "tests compare exact values")]

use super::*;
use crate::expr::eval;
use crate::params::ParameterTable;

/// Parses `text` and evaluates every word and assignment value with all parameters zero
/// except those given.
fn words(text: &str, params: &ParameterTable) -> Vec<(char, f64)> {
    let mut parser = Parser::new();
    let block = parser.parse_line(text, 1).expect("parses");
    let mut stack = Vec::new();
    block
        .words()
        .iter()
        .map(|w| {
            let v = match w.value() {
                Value::Number(v) => v,
                Value::Expr(e) => eval(block.nodes(e), block.names(), params, &mut stack).expect("evaluates"),
            };
            (w.letter(), v)
        })
        .collect()
}

fn syntax(text: &str) -> (u32, SyntaxProblem) {
    let mut parser = Parser::new();
    match parser.parse_line(text, 3) {
        Err(GcodeError::Syntax { line: 3, column, problem }) => (column, problem),
        other => panic!("expected a syntax error for {text:?}, got {other:?}"),
    }
}

fn value(text: &str) -> f64 {
    words(&format!("X{text}"), &ParameterTable::new())[0].1
}

#[test]
fn words_numbers_case_and_blanks() {
    let p = ParameterTable::new();
    assert_eq!(
        words("g1 x1.5 Y-2 z+.25 f100", &p),
        vec![('G', 1.0), ('X', 1.5), ('Y', -2.0), ('Z', 0.25), ('F', 100.0)]
    );
    assert_eq!(words("G 0 1 X 1 . 5", &p), vec![('G', 1.0), ('X', 1.5)]);
    assert_eq!(words("G90.1G17", &p), vec![('G', 90.1), ('G', 17.0)]);
    assert_eq!(words("M3 $1", &p), vec![('M', 3.0), ('$', 1.0)]);
    assert_eq!(words("\tG0\r", &p), vec![('G', 0.0)]);
}

#[test]
fn line_numbers_comments_and_delimiters() {
    let mut parser = Parser::new();
    let block = parser.parse_line("N120 G0 X1 (move (to) it) ; the corner", 7).expect("parses");
    assert_eq!(block.line(), 7);
    assert_eq!(block.line_number(), Some(120));
    assert_eq!(block.words().len(), 2);
    assert_eq!(block.comments().collect::<Vec<_>>(), vec!["move (to) it", " the corner"]);
    let block = parser.parse_line("G0 ; rest ( is ) comment", 1).expect("parses");
    assert_eq!(block.comments().collect::<Vec<_>>(), vec![" rest ( is ) comment"]);
    let block = parser.parse_line("(a)(b) M281 (c)", 1).expect("parses");
    assert_eq!(block.comments().collect::<Vec<_>>(), vec!["a", "b", "c"]);
    assert!(parser.parse_line("%", 1).expect("delimiter").is_empty());
    assert!(parser.parse_line("   ", 1).expect("blank").is_empty());
    assert!(parser.parse_line("(only a comment)", 1).expect("comment").is_empty());
    // Non-ASCII text inside comments is kept.
    let block = parser.parse_line("G0 (Überfahrt ±0.1″)", 1).expect("parses");
    assert_eq!(block.comments().next(), Some("Überfahrt ±0.1″"));
}

#[test]
fn expressions_follow_linuxcnc_precedence() {
    assert_eq!(value("[1 + 2 * 3]"), 7.0);
    assert_eq!(value("[2 ** 3 ** 2]"), 64.0, "left associative");
    assert_eq!(value("[-2 ** 2]"), 4.0, "sign binds to the operand");
    assert_eq!(value("[10 - 4 - 3]"), 3.0);
    assert_eq!(value("[7 MOD 4 * 2]"), 6.0);
    assert_eq!(value("[1 + 1 EQ 2]"), 1.0);
    assert_eq!(value("[1 LT 2 AND 3 GT 4]"), 0.0);
    assert_eq!(value("[0 OR 2 XOR 1]"), 0.0);
    assert_eq!(value("[1 eq 1 and 2 ge 2]"), 1.0);
    assert!((value("SIN[30]") - 0.5).abs() < 1e-15);
    assert!((value("ATAN[1]/[1]") - 45.0).abs() < 1e-12);
    assert!((value("-ATAN[-1]/[0]") - 90.0).abs() < 1e-12);
    assert_eq!(value("ABS[-3]"), 3.0);
    assert_eq!(value("[SQRT[16] + FIX[2.7] + FUP[2.1] + ROUND[2.5]]"), 4.0 + 2.0 + 3.0 + 3.0);
    assert_eq!(value("[EXP[0] + LN[1]]"), 1.0);
    assert_eq!(value("[ A B S [ - 2 ] ]"), 2.0);
    assert_eq!(value("[1 ANDSIN[90]]"), 1.0, "operators match by prefix like LinuxCNC");
}

#[test]
fn parameters_and_indirection() {
    let mut p = ParameterTable::new();
    p.write(1, 5.0).expect("write");
    p.write(5, 42.0).expect("write");
    p.write(2, 0.5).expect("write");
    assert_eq!(words("X#1 Y-#2 Z##1 A#[2*2+1]", &p), vec![('X', 5.0), ('Y', -0.5), ('Z', 42.0), ('A', 42.0)]);
}

#[test]
fn assignments_are_collected_in_order() {
    let mut parser = Parser::new();
    let block = parser.parse_line("#1=2 #[1+1] = [3*4] #3=-#1 G0 X#1", 1).expect("parses");
    assert_eq!(block.assignments().len(), 3);
    assert_eq!(block.words().len(), 2);
    let p = ParameterTable::new();
    let mut stack = Vec::new();
    let targets: Vec<f64> = block
        .assignments()
        .iter()
        .map(|a| eval(block.nodes(a.target()), block.names(), &p, &mut stack).expect("target"))
        .collect();
    assert_eq!(targets, vec![1.0, 2.0, 3.0]);
    let values: Vec<f64> = block
        .assignments()
        .iter()
        .map(|a| match a.value() {
            Value::Number(v) => v,
            Value::Expr(e) => eval(block.nodes(e), block.names(), &p, &mut stack).expect("value"),
        })
        .collect();
    assert_eq!(values, vec![2.0, 12.0, -0.0]);
}

#[test]
fn syntax_errors_say_where_and_what() {
    assert_eq!(syntax("G0 X"), (4, SyntaxProblem::MissingValue { letter: 'X' }));
    assert_eq!(syntax("G0 XY1"), (4, SyntaxProblem::MissingValue { letter: 'X' }));
    assert_eq!(syntax("G0 X1 X2"), (7, SyntaxProblem::DuplicateWord { letter: 'X' }));
    assert_eq!(syntax("G0 (open"), (4, SyntaxProblem::UnclosedComment));
    assert_eq!(syntax("G0 (a (b)"), (4, SyntaxProblem::UnclosedComment));
    assert_eq!(syntax("G0 (a) b)"), (8, SyntaxProblem::MissingValue { letter: 'B' }));
    assert_eq!(syntax("X[1+2"), (2, SyntaxProblem::UnclosedBracket));
    assert_eq!(syntax("X[1 2 +]"), (8, SyntaxProblem::ExpectedValue));
    assert_eq!(syntax("X[1 FOO 2]"), (5, SyntaxProblem::ExpectedOperator));
    assert_eq!(syntax("X[FOO[2]]"), (3, SyntaxProblem::UnknownFunction));
    assert_eq!(syntax("XSIN 30"), (6, SyntaxProblem::FunctionNeedsBracket { name: "SIN" }));
    assert_eq!(syntax("XATAN[1]"), (9, SyntaxProblem::AtanForm));
    assert_eq!(syntax("#1 G0"), (4, SyntaxProblem::ExpectedEquals));
    assert_eq!(syntax("G0 N10"), (4, SyntaxProblem::LineNumberNotFirst));
    assert_eq!(syntax("N1.5"), (2, SyntaxProblem::BadLineNumber));
    assert_eq!(syntax("G0 @"), (4, SyntaxProblem::MissingValue { letter: '@' }));
    assert_eq!(syntax("G0 @1 @2"), (7, SyntaxProblem::DuplicateWord { letter: '@' }));
    assert_eq!(words("G1 @[1+1] ^-30", &ParameterTable::new()), vec![('G', 1.0), ('@', 2.0), ('^', -30.0)]);
    assert_eq!(syntax("G0 &"), (4, SyntaxProblem::Unexpected { found: '&' }));
    assert_eq!(syntax("Gé"), (1, SyntaxProblem::MissingValue { letter: 'G' }));
    assert_eq!(syntax("é"), (1, SyntaxProblem::Unexpected { found: 'é' }));
    assert_eq!(syntax("(é) ü"), (5, SyntaxProblem::Unexpected { found: 'ü' }));
    assert_eq!(syntax("X1.2.3"), (5, SyntaxProblem::BadNumber));
    assert_eq!(syntax("#1="), (4, SyntaxProblem::ExpectedValue));
    let deep = format!("X{}1{}", "[".repeat(100), "]".repeat(100));
    assert_eq!(syntax(&deep).1, SyntaxProblem::TooDeep { limit: MAX_DEPTH });
    let negs = format!("X{}1", "-".repeat(100));
    assert_eq!(syntax(&negs).1, SyntaxProblem::TooDeep { limit: MAX_DEPTH });
}

#[test]
fn long_operator_chains_do_not_recurse() {
    // As long as a line may hold (a recursion per operator would need that many frames).
    let chain = format!("[{}1]", "1+".repeat(MAX_OPERANDS - 1));
    assert_eq!(value(&chain), MAX_OPERANDS as f64);
}

#[test]
fn messages_name_the_problem_and_the_fix() {
    let mut parser = Parser::new();
    let err = parser.parse_line("G0 X", 12).expect_err("missing value");
    assert_eq!(err.line(), 12);
    assert_eq!(err.column(), Some(4));
    assert_eq!(
        err.to_string(),
        "line 12, column 4: `X` has no value: write a number, `#n`, `[expression]` or a function after it"
    );
}
