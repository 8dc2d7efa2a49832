//! Expressions: precedence climbing that writes postfix nodes.
//!
//! Recursion is bounded: each bracket, `#`, sign or function call costs one level of
//! [`MAX_DEPTH`], and a chain of operators on one level is a loop, not a recursion.

use super::{is_blank, number, Cursor, PResult, Parser, MAX_DEPTH, MAX_OPERANDS};
use crate::error::SyntaxProblem;
use crate::expr::{BinOp, Func, Node};

/// A function name at the cursor: the function (`None` for ATAN) and the position after it.
pub(super) fn function_at(cur: &Cursor<'_>) -> Option<(Option<Func>, usize)> {
    if let Some(end) = keyword(cur, b"ATAN") {
        return Some((None, end));
    }
    Func::ALL.iter().find_map(|(f, name)| keyword(cur, name.as_bytes()).map(|end| (Some(*f), end)))
}

/// Matches `word` (upper case) at the cursor, case-insensitively, ignoring blanks between its
/// letters; returns the position after it.
fn keyword(cur: &Cursor<'_>, word: &[u8]) -> Option<usize> {
    let mut probe = *cur;
    for &w in word {
        probe.skip_blanks();
        if probe.peek().map(|b| b.to_ascii_uppercase()) != Some(w) {
            return None;
        }
        probe.pos += 1;
    }
    Some(probe.pos)
}

/// The binary operator at the cursor and the position after it.
fn binop_at(cur: &Cursor<'_>) -> Option<(BinOp, usize)> {
    let next = cur.pos + 1;
    match cur.peek()? {
        b'*' => {
            let mut probe = Cursor { bytes: cur.bytes, pos: next };
            probe.skip_blanks();
            if probe.peek() == Some(b'*') {
                Some((BinOp::Pow, probe.pos + 1))
            } else {
                Some((BinOp::Mul, next))
            }
        }
        b'/' => Some((BinOp::Div, next)),
        b'+' => Some((BinOp::Add, next)),
        b'-' => Some((BinOp::Sub, next)),
        b if b.is_ascii_alphabetic() => {
            BinOp::WORDS.iter().find_map(|(op, word)| keyword(cur, word).map(|end| (*op, end)))
        }
        _ => None,
    }
}

impl Parser {
    /// `<name>` after a `#`: pushes [`Node::Named`] and returns true; false (nothing consumed)
    /// when no `<` follows. Names are case-insensitive and blanks inside are ignored, as in
    /// LinuxCNC.
    pub(super) fn named(&mut self, cur: &mut Cursor<'_>) -> PResult<bool> {
        let mut probe = *cur;
        probe.skip_blanks();
        if probe.peek() != Some(b'<') {
            return Ok(false);
        }
        let open = probe.pos;
        let close = cur.bytes[open..].iter().position(|&b| b == b'>').ok_or((open, SyntaxProblem::UnclosedName))?;
        let raw = &cur.bytes[open + 1..open + close];
        let name: String = raw.iter().filter(|b| !is_blank(**b)).map(|b| char::from(b.to_ascii_lowercase())).collect();
        if name.is_empty() {
            return Err((open, SyntaxProblem::UnclosedName));
        }
        let index = u32::try_from(self.names.len()).unwrap_or(u32::MAX);
        self.names.push(name.into_boxed_str());
        self.nodes.push(Node::Named(index));
        cur.pos = open + close + 1;
        Ok(true)
    }

    /// One operand: a number, `#operand`, `-operand`, `+operand`, `[expr]` or a function.
    pub(super) fn operand(&mut self, cur: &mut Cursor<'_>, depth: u32) -> PResult<()> {
        if depth > MAX_DEPTH {
            return Err((cur.pos, SyntaxProblem::TooDeep { limit: MAX_DEPTH }));
        }
        // Each operand adds at most two nodes (itself and the operator after it).
        if self.nodes.len() >= 2 * MAX_OPERANDS {
            return Err((cur.pos, SyntaxProblem::TooLong { limit: MAX_OPERANDS }));
        }
        cur.skip_blanks();
        let at = cur.pos;
        match cur.peek() {
            Some(b'0'..=b'9' | b'.') => {
                let v = number::number(cur)?;
                self.nodes.push(Node::Num(v));
            }
            Some(b'-') => {
                cur.pos += 1;
                self.operand(cur, depth + 1)?;
                self.nodes.push(Node::Neg);
            }
            Some(b'+') => {
                cur.pos += 1;
                self.operand(cur, depth + 1)?;
            }
            Some(b'#') => {
                cur.pos += 1;
                if !self.named(cur)? {
                    self.operand(cur, depth + 1)?;
                    self.nodes.push(Node::Param);
                }
            }
            Some(b'[') => {
                cur.pos += 1;
                self.bracketed(cur, depth + 1, at)?;
            }
            Some(b) if b.is_ascii_alphabetic() => {
                let (func, end) = function_at(cur).ok_or((at, SyntaxProblem::UnknownFunction))?;
                cur.pos = end;
                cur.skip_blanks();
                let open = cur.pos;
                if cur.peek() != Some(b'[') {
                    let name = func.map_or("ATAN", Func::name);
                    return Err((open, SyntaxProblem::FunctionNeedsBracket { name }));
                }
                cur.pos += 1;
                self.bracketed(cur, depth + 1, open)?;
                match func {
                    Some(f) => self.nodes.push(Node::Func(f)),
                    None => {
                        cur.skip_blanks();
                        if cur.peek() != Some(b'/') {
                            return Err((cur.pos, SyntaxProblem::AtanForm));
                        }
                        cur.pos += 1;
                        cur.skip_blanks();
                        let open = cur.pos;
                        if cur.peek() != Some(b'[') {
                            return Err((open, SyntaxProblem::AtanForm));
                        }
                        cur.pos += 1;
                        self.bracketed(cur, depth + 1, open)?;
                        self.nodes.push(Node::Atan);
                    }
                }
            }
            _ => return Err((at, SyntaxProblem::ExpectedValue)),
        }
        Ok(())
    }

    /// The inside of `[ ... ]` (the cursor is after `[`, which was at `open`), and the `]`.
    fn bracketed(&mut self, cur: &mut Cursor<'_>, depth: u32, open: usize) -> PResult<()> {
        self.binary(cur, depth, 0)?;
        cur.skip_blanks();
        match cur.peek() {
            Some(b']') => {
                cur.pos += 1;
                Ok(())
            }
            None => Err((open, SyntaxProblem::UnclosedBracket)),
            Some(_) => Err((cur.pos, SyntaxProblem::ExpectedOperator)),
        }
    }

    /// Operands joined by operators of precedence `min` or more, left-associative.
    fn binary(&mut self, cur: &mut Cursor<'_>, depth: u32, min: u8) -> PResult<()> {
        self.operand(cur, depth)?;
        loop {
            cur.skip_blanks();
            let Some((op, end)) = binop_at(cur) else { return Ok(()) };
            if op.precedence() < min {
                return Ok(());
            }
            cur.pos = end;
            // The right operand binds only tighter operators: left associativity. The depth of
            // this recursion is bounded by the five precedence levels.
            self.binary(cur, depth, op.precedence() + 1)?;
            self.nodes.push(Node::Bin(op));
        }
    }
}
