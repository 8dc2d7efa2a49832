//! Expressions: the node list the parser builds and its evaluation.
//!
//! The parser writes an expression in postfix order (operands before their operator), so
//! evaluation is one pass over a slice with a value stack: no recursion, no allocation once the
//! stack has grown, and no stack overflow whatever the input.
//!
//! Semantics follow LinuxCNC (`interp_execute.cc`): angles in degrees; `EQ`/`NE`/`LE`/`GE` compare
//! with a tolerance of 1e-6; `MOD` is never negative; `ROUND` rounds half away from zero; the
//! logical operators treat any non-zero value as true and return 1 or 0. Unlike LinuxCNC, every
//! intermediate NaN or infinity is an error rather than a value.

use crate::error::RunProblem;
use crate::params::ParameterTable;

/// Two numbers compare equal (`EQ`, `NE`, `LE`, `GE`) when they differ by less than this.
pub(crate) const EQUAL_TOLERANCE: f64 = 1e-6;

/// A one-argument function, `NAME[x]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Func {
    /// Absolute value.
    Abs,
    /// Arc cosine, degrees.
    Acos,
    /// Arc sine, degrees.
    Asin,
    /// Cosine of degrees.
    Cos,
    /// e to the power x.
    Exp,
    /// Round down (floor).
    Fix,
    /// Round up (ceiling).
    Fup,
    /// Natural logarithm.
    Ln,
    /// Round half away from zero.
    Round,
    /// Sine of degrees.
    Sin,
    /// Square root.
    Sqrt,
    /// Tangent of degrees.
    Tan,
}

impl Func {
    /// Every function with its name (ATAN is separate: it takes two arguments).
    pub(crate) const ALL: [(Func, &'static str); 12] = [
        (Func::Abs, "ABS"),
        (Func::Acos, "ACOS"),
        (Func::Asin, "ASIN"),
        (Func::Cos, "COS"),
        (Func::Exp, "EXP"),
        (Func::Fix, "FIX"),
        (Func::Fup, "FUP"),
        (Func::Ln, "LN"),
        (Func::Round, "ROUND"),
        (Func::Sin, "SIN"),
        (Func::Sqrt, "SQRT"),
        (Func::Tan, "TAN"),
    ];

    /// The function's name as written.
    #[must_use]
    pub(crate) fn name(self) -> &'static str {
        Func::ALL.iter().find(|(f, _)| *f == self).map_or("?", |(_, n)| n)
    }

    /// Applies the function (degrees for the trigonometry).
    ///
    /// # Errors
    /// Arguments outside the domain (ACOS/ASIN outside [-1, 1], LN of x ≤ 0, SQRT of x < 0).
    pub(crate) fn apply(self, x: f64) -> Result<f64, RunProblem> {
        let domain = |hint| Err(RunProblem::Domain { function: self.name(), argument: x, hint });
        Ok(match self {
            Func::Abs => x.abs(),
            Func::Acos if !(-1.0..=1.0).contains(&x) => return domain("the argument must lie in [-1, 1]"),
            Func::Acos => x.acos().to_degrees(),
            Func::Asin if !(-1.0..=1.0).contains(&x) => return domain("the argument must lie in [-1, 1]"),
            Func::Asin => x.asin().to_degrees(),
            Func::Cos => x.to_radians().cos(),
            Func::Exp => x.exp(),
            Func::Fix => x.floor(),
            Func::Fup => x.ceil(),
            Func::Ln if x <= 0.0 => return domain("the argument must be positive"),
            Func::Ln => x.ln(),
            Func::Round => x.round(),
            Func::Sin => x.to_radians().sin(),
            Func::Sqrt if x < 0.0 => return domain("the argument must not be negative"),
            Func::Sqrt => x.sqrt(),
            Func::Tan => x.to_radians().tan(),
        })
    }
}

/// A binary operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum BinOp {
    /// `**`
    Pow,
    /// `*`
    Mul,
    /// `/`
    Div,
    /// `MOD`
    Mod,
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `EQ`
    Eq,
    /// `NE`
    Ne,
    /// `GT`
    Gt,
    /// `GE`
    Ge,
    /// `LT`
    Lt,
    /// `LE`
    Le,
    /// `AND`
    And,
    /// `OR`
    Or,
    /// `XOR`
    Xor,
}

impl BinOp {
    /// Operators written as words, with their names.
    pub(crate) const WORDS: [(BinOp, &'static [u8]); 10] = [
        (BinOp::Mod, b"MOD"),
        (BinOp::Eq, b"EQ"),
        (BinOp::Ne, b"NE"),
        (BinOp::Gt, b"GT"),
        (BinOp::Ge, b"GE"),
        (BinOp::Lt, b"LT"),
        (BinOp::Le, b"LE"),
        (BinOp::And, b"AND"),
        (BinOp::Or, b"OR"),
        (BinOp::Xor, b"XOR"),
    ];

    /// Binding strength, LinuxCNC's five levels: `**` 4; `* / MOD` 3; `+ -` 2; comparisons 1;
    /// `AND OR XOR` 0. Operators of one level associate to the left.
    #[must_use]
    pub(crate) fn precedence(self) -> u8 {
        match self {
            BinOp::Pow => 4,
            BinOp::Mul | BinOp::Div | BinOp::Mod => 3,
            BinOp::Add | BinOp::Sub => 2,
            BinOp::Eq | BinOp::Ne | BinOp::Gt | BinOp::Ge | BinOp::Lt | BinOp::Le => 1,
            BinOp::And | BinOp::Or | BinOp::Xor => 0,
        }
    }

    /// The operator as written.
    #[must_use]
    pub(crate) fn symbol(self) -> &'static str {
        match self {
            BinOp::Pow => "**",
            BinOp::Mul => "*",
            BinOp::Div => "/",
            BinOp::Add => "+",
            BinOp::Sub => "-",
            other => BinOp::WORDS
                .iter()
                .find(|(op, _)| *op == other)
                .and_then(|(_, w)| std::str::from_utf8(w).ok())
                .unwrap_or("?"),
        }
    }

    /// Applies the operator.
    ///
    /// # Errors
    /// Division by zero; a negative number to a non-integer power.
    #[expect(clippy::float_cmp, reason = "whole means exactly whole")]
    pub(crate) fn apply(self, a: f64, b: f64) -> Result<f64, RunProblem> {
        let truth = |t: bool| if t { 1.0 } else { 0.0 };
        Ok(match self {
            BinOp::Pow if a < 0.0 && b.floor() != b => {
                return Err(RunProblem::Domain {
                    function: "**",
                    argument: a,
                    hint: "a negative number has no real non-integer power",
                })
            }
            BinOp::Pow => a.powf(b),
            BinOp::Mul => a * b,
            BinOp::Div if b == 0.0 => return Err(RunProblem::DivisionByZero),
            BinOp::Div => a / b,
            BinOp::Mod if b == 0.0 => return Err(RunProblem::DivisionByZero),
            BinOp::Mod => {
                let r = a % b;
                if r < 0.0 {
                    r + b.abs()
                } else {
                    r
                }
            }
            BinOp::Add => a + b,
            BinOp::Sub => a - b,
            BinOp::Eq => truth((a - b).abs() < EQUAL_TOLERANCE),
            BinOp::Ne => truth((a - b).abs() >= EQUAL_TOLERANCE),
            BinOp::Gt => truth(a > b),
            BinOp::Ge => truth((a - b).abs() < EQUAL_TOLERANCE || a >= b),
            BinOp::Lt => truth(a < b),
            BinOp::Le => truth((a - b).abs() < EQUAL_TOLERANCE || a <= b),
            BinOp::And => truth(a != 0.0 && b != 0.0),
            BinOp::Or => truth(a != 0.0 || b != 0.0),
            BinOp::Xor => truth((a != 0.0) != (b != 0.0)),
        })
    }
}

/// One postfix instruction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Node {
    /// Push a literal.
    Num(f64),
    /// Pop an index, push that parameter's value.
    Param,
    /// Push named parameter number `n` of the line's names (`#<name>`).
    Named(u32),
    /// Negate the top.
    Neg,
    /// Apply a function to the top.
    Func(Func),
    /// Pop x, pop y, push ATAN[y]/[x] in degrees.
    Atan,
    /// Pop b, pop a, push `a op b`.
    Bin(BinOp),
}

/// Evaluates the postfix `nodes` against `params`, using `stack` as scratch.
///
/// # Errors
/// Domain errors, division by zero, a bad parameter index, or a non-finite intermediate value.
pub(crate) fn eval(
    nodes: &[Node],
    names: &[Box<str>],
    params: &ParameterTable,
    stack: &mut Vec<f64>,
) -> Result<f64, RunProblem> {
    stack.clear();
    for node in nodes {
        let value = match *node {
            Node::Num(v) => v,
            Node::Param => params.read(pop(stack)?)?,
            Node::Named(i) => params.read_named(names.get(i as usize).map_or("", |n| n))?,
            Node::Neg => -pop(stack)?,
            Node::Func(f) => f.apply(pop(stack)?)?,
            Node::Atan => {
                let x = pop(stack)?;
                let y = pop(stack)?;
                y.atan2(x).to_degrees()
            }
            Node::Bin(op) => {
                let b = pop(stack)?;
                let a = pop(stack)?;
                op.apply(a, b)?
            }
        };
        if !value.is_finite() {
            return Err(RunProblem::NonFinite { what: node_name(*node) });
        }
        stack.push(value);
    }
    match (stack.pop(), stack.is_empty()) {
        (Some(v), true) => Ok(v),
        // The parser only builds well-formed postfix; report rather than panic if it did not.
        _ => Err(RunProblem::NonFinite { what: "a malformed expression" }),
    }
}

fn pop(stack: &mut Vec<f64>) -> Result<f64, RunProblem> {
    match stack.pop() {
        Some(v) => Ok(v),
        None => Err(RunProblem::NonFinite { what: "a malformed expression" }),
    }
}

fn node_name(node: Node) -> &'static str {
    match node {
        Node::Num(_) => "a number",
        Node::Param | Node::Named(_) => "a parameter",
        Node::Neg => "a negation",
        Node::Func(f) => f.name(),
        Node::Atan => "ATAN",
        Node::Bin(op) => op.symbol(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linuxcnc_semantics() {
        assert_eq!(BinOp::Mod.apply(-7.0, 3.0), Ok(2.0));
        assert_eq!(BinOp::Mod.apply(7.0, -3.0), Ok(1.0));
        assert_eq!(BinOp::Eq.apply(1.0, 1.0 + 1e-7), Ok(1.0));
        assert_eq!(BinOp::Ne.apply(1.0, 1.0 + 1e-7), Ok(0.0));
        assert_eq!(BinOp::Ge.apply(1.0 - 1e-7, 1.0), Ok(1.0));
        assert_eq!(BinOp::Gt.apply(1.0, 1.0), Ok(0.0));
        assert_eq!(BinOp::Xor.apply(2.0, 0.0), Ok(1.0));
        assert_eq!(BinOp::Div.apply(1.0, 0.0), Err(RunProblem::DivisionByZero));
        assert!(BinOp::Pow.apply(-8.0, 1.0 / 3.0).is_err());
        assert_eq!(BinOp::Pow.apply(-2.0, 3.0), Ok(-8.0));
        assert_eq!(Func::Round.apply(-2.5), Ok(-3.0));
        assert_eq!(Func::Fix.apply(-2.5), Ok(-3.0));
        assert_eq!(Func::Fup.apply(-2.5), Ok(-2.0));
        assert!((Func::Sin.apply(30.0).expect("sin") - 0.5).abs() < 1e-15);
        assert!((Func::Acos.apply(0.5).expect("acos") - 60.0).abs() < 1e-12);
        assert!(Func::Acos.apply(1.5).is_err());
        assert!(Func::Ln.apply(0.0).is_err());
        assert!(Func::Sqrt.apply(-1.0).is_err());
        assert_eq!(Func::Abs.name(), "ABS");
        assert_eq!(BinOp::Xor.symbol(), "XOR");
    }

    #[test]
    fn postfix_evaluation_and_non_finite_intermediates() {
        let params = ParameterTable::new();
        let mut stack = Vec::new();
        // [2 + 3 * 4]
        let nodes = [Node::Num(2.0), Node::Num(3.0), Node::Num(4.0), Node::Bin(BinOp::Mul), Node::Bin(BinOp::Add)];
        assert_eq!(eval(&nodes, &[], &params, &mut stack), Ok(14.0));
        let nodes = [Node::Num(1e300), Node::Num(1e300), Node::Bin(BinOp::Mul)];
        assert_eq!(eval(&nodes, &[], &params, &mut stack), Err(RunProblem::NonFinite { what: "*" }));
        let nodes = [Node::Num(1.0), Node::Num(1.0), Node::Atan];
        assert!((eval(&nodes, &[], &params, &mut stack).expect("atan") - 45.0).abs() < 1e-12);
        assert!(eval(&[Node::Bin(BinOp::Add)], &[], &params, &mut stack).is_err());
    }
}
