//! Number literals: digits with at most one `.`, spaces allowed anywhere (they are ignored, as
//! in LinuxCNC), no sign and no exponent (the caller handles signs; `E` is a word letter).
//!
//! Fast path: up to 17 significant digits with at most 22 decimals are exact in `u64`, and one
//! division by an exact power of ten is correctly rounded (Clinger), so the result is the same
//! `f64` as `str::parse`. Anything longer goes through `str::parse`.

use super::{Cursor, PResult};
use crate::error::SyntaxProblem;

/// Exact powers of ten representable in an `f64`.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20,
    1e21, 1e22,
];

/// Largest mantissa that still takes another digit without leaving the exact range.
const MANTISSA_LIMIT: u64 = 100_000_000_000_000_000;

/// Whether `b` is a blank the parser ignores.
#[inline]
pub(crate) fn is_blank(b: u8) -> bool {
    b == b' ' || b == b'\t' || b == b'\r'
}

/// Reads an unsigned number at the cursor (which must be at a digit or `.`).
pub(super) fn number(cur: &mut Cursor<'_>) -> PResult<f64> {
    let bytes = cur.bytes;
    let start = cur.pos;
    let mut i = start;
    let mut mantissa: u64 = 0;
    let mut decimals: u32 = 0;
    let mut dot = false;
    let mut digits = false;
    let mut exact = true;
    while let Some(&c) = bytes.get(i) {
        if c.is_ascii_digit() {
            digits = true;
            if mantissa < MANTISSA_LIMIT {
                mantissa = mantissa * 10 + u64::from(c - b'0');
                decimals += u32::from(dot);
            } else {
                exact = false;
            }
        } else if c == b'.' {
            if dot {
                return Err((i, SyntaxProblem::BadNumber));
            }
            dot = true;
        } else if !is_blank(c) {
            break;
        }
        i += 1;
    }
    if !digits {
        return Err((start, SyntaxProblem::BadNumber));
    }
    cur.pos = i;
    if exact && mantissa <= (1 << 53) && (decimals as usize) < POW10.len() {
        #[allow(clippy::cast_precision_loss)] // mantissa ≤ 2^53: exact.
        return Ok(mantissa as f64 / POW10[decimals as usize]);
    }
    slow(&bytes[start..i]).ok_or((start, SyntaxProblem::BadNumber))
}

/// The general case: strip blanks and let the standard library round.
#[cold]
fn slow(raw: &[u8]) -> Option<f64> {
    let text: String = raw.iter().filter(|b| !is_blank(**b)).map(|&b| char::from(b)).collect();
    text.parse::<f64>().ok()
}

#[cfg(test)]
#[allow(clippy::float_cmp)]
mod tests {
    use super::*;

    fn num(s: &str) -> Result<(f64, usize), SyntaxProblem> {
        let mut cur = Cursor::new(s);
        number(&mut cur).map(|v| (v, cur.pos)).map_err(|e| e.1)
    }

    #[test]
    fn literals_match_the_standard_library() {
        for s in [
            "0",
            "1",
            "1.",
            ".5",
            "12.345",
            "0.1",
            "3.14159265358979",
            "123456789012345678",
            "0.000000000000000000000001",
        ] {
            assert_eq!(num(s).expect("parses").0, s.parse::<f64>().expect("std"), "{s}");
        }
        assert_eq!(num("99999999999999999999.9999").expect("long").0, 99_999_999_999_999_999_999.999_9);
    }

    #[test]
    fn blanks_inside_are_ignored_and_stop_at_letters() {
        assert_eq!(num("1 2 . 5 Y").expect("spaces"), (12.5, 8));
        assert_eq!(num("7X").expect("letter").1, 1);
    }

    #[test]
    fn malformed_numbers_are_errors() {
        assert_eq!(num("."), Err(SyntaxProblem::BadNumber));
        assert_eq!(num("1.2.3"), Err(SyntaxProblem::BadNumber));
    }
}
