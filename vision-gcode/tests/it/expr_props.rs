//! Random expressions, written with the fewest brackets LinuxCNC's precedence allows, evaluate
//! like a reference evaluator working on the expression tree — or both refuse them.
#![expect(clippy::cast_possible_wrap, reason = "test values are small and whole")]
#![expect(clippy::float_cmp, reason = "tests compare exact values")]

use proptest::prelude::*;
use vision_gcode::{Interpreter, InterpreterConfig};

#[derive(Debug, Clone)]
enum E {
    Num(f64),
    Param(u32),
    Neg(Box<E>),
    Func(&'static str, Box<E>),
    Atan(Box<E>, Box<E>),
    Bin((&'static str, u8), Box<E>, Box<E>),
}

/// LinuxCNC's one-argument functions, as written `NAME[x]` (the test's own list, so that a
/// wrong name in the interpreter fails here).
const FUNCS: [&str; 12] = ["ABS", "ACOS", "ASIN", "COS", "EXP", "FIX", "FUP", "LN", "ROUND", "SIN", "SQRT", "TAN"];

/// LinuxCNC's binary operators as written, with their binding strength (five levels: `**` 4;
/// `* / MOD` 3; `+ -` 2; comparisons 1; `AND OR XOR` 0), left-associative within a level.
const OPS: [(&str, u8); 15] = [
    ("**", 4),
    ("*", 3),
    ("/", 3),
    ("MOD", 3),
    ("+", 2),
    ("-", 2),
    ("EQ", 1),
    ("NE", 1),
    ("GT", 1),
    ("GE", 1),
    ("LT", 1),
    ("LE", 1),
    ("AND", 0),
    ("OR", 0),
    ("XOR", 0),
];

const PARAMS: u32 = 6;

fn expr() -> impl Strategy<Value = E> {
    let leaf = prop_oneof![
        (0u32..2000, 0u32..4).prop_map(|(m, d)| E::Num(f64::from(m) / 10f64.powi(d as i32))),
        (1..=PARAMS).prop_map(E::Param),
    ];
    leaf.prop_recursive(6, 48, 2, |inner| {
        prop_oneof![
            inner.clone().prop_map(|e| E::Neg(Box::new(e))),
            (prop::sample::select(FUNCS.to_vec()), inner.clone()).prop_map(|(f, e)| E::Func(f, Box::new(e))),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| E::Atan(Box::new(a), Box::new(b))),
            (prop::sample::select(OPS.to_vec()), inner.clone(), inner).prop_map(|(op, a, b)| E::Bin(
                op,
                Box::new(a),
                Box::new(b)
            )),
        ]
    })
}

/// Binding strength of a node: binary operators by precedence, everything else is an operand.
fn strength(e: &E) -> u8 {
    match e {
        E::Bin((_, strength), ..) => *strength,
        _ => u8::MAX,
    }
}

/// The text, with brackets only where precedence and left associativity require them.
fn render(e: &E) -> String {
    match e {
        E::Num(v) => format!("{v}"),
        E::Param(n) => format!("#{n}"),
        E::Neg(a) => format!("-{}", operand(a)),
        E::Func(name, a) => format!("{name}[{}]", render(a)),
        E::Atan(a, b) => format!("ATAN[{}]/[{}]", render(a), render(b)),
        E::Bin((symbol, p), a, b) => {
            let p = *p;
            let left = if strength(a) < p { format!("[{}]", render(a)) } else { render(a) };
            let right = if strength(b) <= p { format!("[{}]", render(b)) } else { render(b) };
            format!("{left} {symbol} {right}")
        }
    }
}

fn operand(e: &E) -> String {
    if strength(e) == u8::MAX {
        render(e)
    } else {
        format!("[{}]", render(e))
    }
}

/// LinuxCNC's semantics on the tree; `None` where the interpreter must refuse.
fn reference(e: &E, params: &[f64]) -> Option<f64> {
    let v = match e {
        E::Num(v) => *v,
        E::Param(n) => params[*n as usize],
        E::Neg(a) => -reference(a, params)?,
        E::Func(f, a) => {
            let x = reference(a, params)?;
            match *f {
                "ABS" => x.abs(),
                "ACOS" => (-1.0..=1.0).contains(&x).then(|| x.acos().to_degrees())?,
                "ASIN" => (-1.0..=1.0).contains(&x).then(|| x.asin().to_degrees())?,
                "COS" => x.to_radians().cos(),
                "EXP" => x.exp(),
                "FIX" => x.floor(),
                "FUP" => x.ceil(),
                "LN" => (x > 0.0).then(|| x.ln())?,
                "ROUND" => x.round(),
                "SIN" => x.to_radians().sin(),
                "SQRT" => (x >= 0.0).then(|| x.sqrt())?,
                "TAN" => x.to_radians().tan(),
                other => unreachable!("no function {other}"),
            }
        }
        E::Atan(a, b) => reference(a, params)?.atan2(reference(b, params)?).to_degrees(),
        E::Bin(op, a, b) => {
            let (x, y) = (reference(a, params)?, reference(b, params)?);
            let t = |c: bool| if c { 1.0 } else { 0.0 };
            let near = (x - y).abs() < 1e-6;
            match op.0 {
                "**" => (x >= 0.0 || y.floor() == y).then(|| x.powf(y))?,
                "*" => x * y,
                "/" => (y != 0.0).then(|| x / y)?,
                "MOD" => (y != 0.0).then(|| {
                    let r = x % y;
                    if r < 0.0 {
                        r + y.abs()
                    } else {
                        r
                    }
                })?,
                "+" => x + y,
                "-" => x - y,
                "EQ" => t(near),
                "NE" => t(!near),
                "GT" => t(x > y),
                "GE" => t(near || x >= y),
                "LT" => t(x < y),
                "LE" => t(near || x <= y),
                "AND" => t(x != 0.0 && y != 0.0),
                "OR" => t(x != 0.0 || y != 0.0),
                "XOR" => t((x != 0.0) != (y != 0.0)),
                other => unreachable!("no operator {other}"),
            }
        }
    };
    v.is_finite().then_some(v)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn expressions_evaluate_like_the_reference(
        e in expr(),
        values in prop::collection::vec(-50.0..50.0f64, PARAMS as usize),
    ) {
        let mut params = vec![0.0];
        params.extend(&values);
        let mut program = String::new();
        for (i, v) in values.iter().enumerate() {
            program.push_str(&format!("#{} = {v}\n", i + 1));
        }
        let text = render(&e);
        program.push_str(&format!("#100 = [{text}]\n"));
        let mut interp = Interpreter::new(InterpreterConfig::default());
        let got = interp.run(&program, None, &mut Vec::new());
        match reference(&e, &params) {
            Some(want) => {
                prop_assert!(got.is_ok(), "{text}: {got:?}");
                let v = interp.param(100);
                prop_assert!(v == want || (v.is_nan() && want.is_nan()), "{text}: {v} != {want}");
            }
            None => prop_assert!(got.is_err(), "{text} should be refused, got {}", interp.param(100)),
        }
    }

    #[test]
    fn word_values_and_assignments_agree(e in expr(), values in prop::collection::vec(-50.0..50.0f64, PARAMS as usize)) {
        // The same expression as a word value: F is stored as given (G20 on an inch machine).
        let mut params = vec![0.0];
        params.extend(&values);
        let mut program = String::new();
        for (i, v) in values.iter().enumerate() {
            program.push_str(&format!("#{} = {v}\n", i + 1));
        }
        program.push_str(&format!("F[ABS[{}]]\n", render(&e)));
        let mut interp = Interpreter::new(InterpreterConfig::default());
        let got = interp.run(&program, None, &mut Vec::new());
        match reference(&e, &params) {
            Some(want) => {
                prop_assert!(got.is_ok(), "{:?}", got);
                prop_assert_eq!(interp.feed(), Some(want.abs()));
            }
            None => prop_assert!(got.is_err()),
        }
    }
}

#[test]
fn rendering_relies_on_precedence() {
    let e = E::Bin(
        ("-", 2),
        Box::new(E::Num(10.0)),
        Box::new(E::Bin(("-", 2), Box::new(E::Num(4.0)), Box::new(E::Num(3.0)))),
    );
    assert_eq!(render(&e), "10 - [4 - 3]");
    assert_eq!(reference(&e, &[]), Some(9.0));
    let e = E::Bin(
        ("+", 2),
        Box::new(E::Num(1.0)),
        Box::new(E::Bin(("*", 3), Box::new(E::Num(2.0)), Box::new(E::Num(3.0)))),
    );
    assert_eq!(render(&e), "1 + 2 * 3");
}
