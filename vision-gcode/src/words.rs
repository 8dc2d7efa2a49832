//! A parsed line with every value evaluated: the "reads" of a line, done before any write.

use crate::error::{GCode, RunProblem};
use crate::expr::{eval, Node};
use crate::letters::{letter_of, slot, SLOTS};
use crate::params::ParameterTable;
use crate::parse::{Block, Value};
use crate::whole::whole_in;

/// A short list with a fixed capacity (no allocation per line).
#[derive(Debug, Clone, Copy)]
pub(crate) struct List<T: Copy + Default, const N: usize> {
    items: [T; N],
    len: usize,
}

impl<T: Copy + Default, const N: usize> Default for List<T, N> {
    fn default() -> Self {
        List { items: [T::default(); N], len: 0 }
    }
}

impl<T: Copy + Default, const N: usize> List<T, N> {
    /// Appends; `false` when full.
    fn push(&mut self, item: T) -> bool {
        match self.items.get_mut(self.len) {
            Some(slot) => {
                *slot = item;
                self.len += 1;
                true
            }
            None => false,
        }
    }

    /// The items.
    pub(crate) fn as_slice(&self) -> &[T] {
        &self.items[..self.len]
    }
}

/// A line's evaluated words. G and M may repeat; every other letter appears at most once.
#[derive(Debug, Clone)]
pub(crate) struct Words {
    present: u32,
    used: u32,
    values: [f64; SLOTS],
    owners: [&'static str; SLOTS],
    /// G codes in tenths, in order.
    pub(crate) g: List<u16, 24>,
    /// M codes, in order.
    pub(crate) m: List<u32, 12>,
}

impl Default for Words {
    fn default() -> Self {
        Words { present: 0, used: 0, values: [0.0; SLOTS], owners: [""; SLOTS], g: List::default(), m: List::default() }
    }
}

impl Words {
    /// Whether `letter` is on the line.
    #[inline]
    pub(crate) fn has(&self, letter: u8) -> bool {
        self.present & (1 << slot(letter)) != 0
    }

    /// Claims `letter` for `owner` and returns its value.
    ///
    /// # Errors
    /// [`RunProblem::WordConflict`] when another code already claimed it.
    #[inline]
    pub(crate) fn take(&mut self, letter: u8, owner: &'static str) -> Result<Option<f64>, RunProblem> {
        let s = slot(letter);
        let bit = 1 << s;
        if self.present & bit == 0 {
            return Ok(None);
        }
        if self.used & bit != 0 && self.owners[s] != owner {
            return Err(RunProblem::WordConflict { letter: letter_of(s), first: self.owners[s], second: owner });
        }
        self.used |= bit;
        self.owners[s] = owner;
        Ok(Some(self.values[s]))
    }

    /// The first letter present but never claimed.
    pub(crate) fn unused(&self) -> Option<char> {
        let rest = self.present & !self.used;
        (rest != 0).then(|| letter_of(rest.trailing_zeros() as usize))
    }

    /// Every non-G/M word, letter and value, alphabetical (`$`, `@`, `^` last).
    pub(crate) fn all(&self) -> impl Iterator<Item = (char, f64)> + '_ {
        (0..SLOTS).filter(|s| self.present & (1 << s) != 0).map(|s| (letter_of(s), self.values[s]))
    }
}

/// What an assignment writes: `#n` or `#<name>`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Target {
    /// `#n`.
    Number(u32),
    /// `#<name>` (lower case).
    Named(Box<str>),
}

/// Evaluates `block`'s words into `words` and its assignments into `assigns` (target, value),
/// all against the parameters as they were before the line.
///
/// # Errors
/// Expression errors, bad parameter numbers, non-finite values, malformed G/M numbers.
pub(crate) fn evaluate(
    block: &Block<'_, '_>,
    params: &ParameterTable,
    stack: &mut Vec<f64>,
    words: &mut Words,
    assigns: &mut Vec<(Target, f64)>,
) -> Result<(), RunProblem> {
    assigns.clear();
    let value = |v: Value, stack: &mut Vec<f64>| match v {
        Value::Number(n) => Ok(n),
        Value::Expr(e) => eval(block.nodes(e), block.names(), params, stack),
    };
    for word in block.words() {
        let v = value(word.value(), stack)?;
        let letter = word.letter_byte();
        if !v.is_finite() {
            return Err(RunProblem::NonFiniteWord { letter: char::from(letter) });
        }
        match letter {
            b'G' => {
                let code = g_code(v)?;
                if !words.g.push(code) {
                    return Err(too_many(&GCode(code).to_string()));
                }
            }
            b'M' => {
                let code = m_code(v)?;
                if !words.m.push(code) {
                    return Err(too_many(&format!("M{code}")));
                }
            }
            _ => {
                let s = slot(letter);
                words.present |= 1 << s;
                words.values[s] = v;
            }
        }
    }
    for a in block.assignments() {
        let target = match block.nodes(a.target()) {
            [Node::Named(i)] => Target::Named(block.names().get(*i as usize).cloned().unwrap_or_default()),
            nodes => Target::Number(params.index(eval(nodes, block.names(), params, stack)?)?),
        };
        let v = value(a.value(), stack)?;
        if !v.is_finite() {
            return Err(RunProblem::NonFinite { what: "the value assigned" });
        }
        assigns.push((target, v));
    }
    Ok(())
}

fn too_many(code: &str) -> RunProblem {
    RunProblem::ModalConflict { first: code.to_string(), second: "the many other codes on this line".to_string() }
}

/// A G value in tenths (`90.1` → 901).
fn g_code(v: f64) -> Result<u16, RunProblem> {
    // A `match`, not `ok_or`: no error value is built (and dropped) for every G word.
    match whole_in(v * 10.0, 1e-6, 9999).and_then(|t| u16::try_from(t).ok()) {
        Some(code) => Ok(code),
        None => Err(RunProblem::BadGCode { value: v }),
    }
}

/// An M value: a whole, non-negative number.
fn m_code(v: f64) -> Result<u32, RunProblem> {
    match whole_in(v, 1e-6, 999_999) {
        Some(code) => Ok(code),
        None => Err(RunProblem::BadMCode { value: v }),
    }
}

/// A word value that must be a whole, non-negative number (tool, port, coordinate system).
///
/// # Errors
/// [`RunProblem::NotWhole`].
pub(crate) fn whole(letter: u8, v: f64) -> Result<u32, RunProblem> {
    whole_in(v, 1e-4, u32::MAX).ok_or_else(|| RunProblem::NotWhole { letter: char::from(letter), value: v })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parse::Parser;

    #[test]
    fn reads_happen_before_writes_and_codes_are_tenths() {
        let mut params = ParameterTable::new();
        params.write(1, 3.0).expect("write");
        let mut parser = Parser::new();
        let block = parser.parse_line("#1=7 #2=#1 G90.1 M3 X#1 $2", 1).expect("parses");
        let mut words = Words::default();
        let mut assigns = Vec::new();
        evaluate(&block, &params, &mut Vec::new(), &mut words, &mut assigns).expect("evaluates");
        assert_eq!(assigns, vec![(Target::Number(1), 7.0), (Target::Number(2), 3.0)]);
        assert_eq!(words.g.as_slice(), &[901]);
        assert_eq!(words.m.as_slice(), &[3]);
        assert!(words.has(b'X'));
        assert_eq!(words.take(b'$', "M3"), Ok(Some(2.0)));
        assert_eq!(words.unused(), Some('X'));
        assert_eq!(words.take(b'X', "G0"), Ok(Some(3.0)));
        assert!(matches!(words.take(b'X', "G92"), Err(RunProblem::WordConflict { letter: 'X', .. })));
        assert_eq!(words.unused(), None);
        assert!(g_code(1.25).is_err());
        assert!(m_code(-1.0).is_err());
        assert_eq!(whole(b'T', 98.00001), Ok(98));
        assert!(whole(b'T', 1.5).is_err());
        assert_eq!(g_code(90.1), Ok(901));
    }
}
