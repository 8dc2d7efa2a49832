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
///
/// The common shape — digits, an optional `.` and digits, not followed by more digits after a
/// blank — is read by two tight loops; anything else (blanks inside, a second `.`, more than 19
/// digits) goes through [`general`].
#[inline]
pub(super) fn number(cur: &mut Cursor<'_>) -> PResult<f64> {
    let bytes = cur.bytes;
    let start = cur.pos;
    let mut i = start;
    let mut mantissa: u64 = 0;
    while let Some(d) = bytes.get(i).map(|c| c.wrapping_sub(b'0')).filter(|d| *d <= 9) {
        mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(d));
        i += 1;
    }
    let mut digits = i - start;
    let mut decimals = 0;
    if bytes.get(i) == Some(&b'.') {
        i += 1;
        let frac = i;
        while let Some(d) = bytes.get(i).map(|c| c.wrapping_sub(b'0')).filter(|d| *d <= 9) {
            mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(d));
            i += 1;
        }
        decimals = i - frac;
        digits += decimals;
    }
    // 19 digits always fit in a u64; more, a second `.`, or digits continuing after a blank
    // need the general reader.
    let continues = match bytes.get(i) {
        Some(b'.') => true,
        Some(&b) if is_blank(b) => {
            let mut j = i + 1;
            while bytes.get(j).is_some_and(|&b| is_blank(b)) {
                j += 1;
            }
            bytes.get(j).is_some_and(|b| b.is_ascii_digit() || *b == b'.')
        }
        _ => false,
    };
    if digits == 0 || digits > 19 || continues {
        return general(cur);
    }
    cur.pos = i;
    if mantissa <= (1 << 53) && decimals < POW10.len() {
        return Ok(mantissa as f64 / POW10[decimals]);
    }
    // Digits and at most one `.`, no blanks: the standard library reads the slice as it is.
    parse(&bytes[start..i]).ok_or((start, SyntaxProblem::BadNumber))
}

/// Any number: blanks inside are ignored (`1 2 . 5` is 12.5).
#[cold]
fn general(cur: &mut Cursor<'_>) -> PResult<f64> {
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
        return Ok(mantissa as f64 / POW10[decimals as usize]);
    }
    without_blanks(&bytes[start..i]).ok_or((start, SyntaxProblem::BadNumber))
}

/// Digits and at most one `.` (no blanks), correctly rounded by the standard library.
fn parse(digits: &[u8]) -> Option<f64> {
    std::str::from_utf8(digits).ok()?.parse().ok()
}

/// Longest literal (blanks removed) read without allocating; a longer one with blanks inside is
/// copied to the heap.
const STACK_DIGITS: usize = 64;

/// Digits, at most one `.` and blanks: the blanks removed, then [`parse`]. Allocates only for
/// a literal with blanks inside and more than [`STACK_DIGITS`] other characters.
#[cold]
fn without_blanks(raw: &[u8]) -> Option<f64> {
    if !raw.iter().any(|&b| is_blank(b)) {
        return parse(raw);
    }
    let mut buf = [0u8; STACK_DIGITS];
    let mut len = 0;
    for &b in raw.iter().filter(|&&b| !is_blank(b)) {
        let Some(slot) = buf.get_mut(len) else {
            let text: Vec<u8> = raw.iter().copied().filter(|&b| !is_blank(b)).collect();
            return parse(&text);
        };
        *slot = b;
        len += 1;
    }
    parse(&buf[..len])
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
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
        assert_eq!(num("7 X").expect("blank then letter"), (7.0, 1));
        assert_eq!(num("1. 5").expect("blank inside the fraction"), (1.5, 4));
        assert_eq!(num("12345678901234567890.5").expect("long").0, 12_345_678_901_234_567_890.5);
        assert_eq!(num("0.3000 0000 0000 0000 4").expect("17 digits with blanks").0, 0.300_000_000_000_000_04);
        // Longer than the stack buffer once the blanks are gone.
        let long = format!("0.{}", "1234 5678 ".repeat(20));
        let compact: String = long.chars().filter(|c| *c != ' ').collect();
        assert_eq!(num(&long).expect("long with blanks").0, compact.parse::<f64>().expect("std"));
    }

    proptest::proptest! {
        #[test]
        fn every_formatted_f64_reads_back_exactly(v in 0.0..1e12f64, decimals in 0usize..12) {
            for text in [format!("{v}"), format!("{v:.decimals$}")] {
                let expected: f64 = text.parse().expect("std");
                proptest::prop_assert_eq!(num(&text).map(|r| r.0), Ok(expected), "{}", text);
            }
        }

        #[test]
        fn digits_dots_and_blanks_read_like_the_blank_free_text(text in "[0-9.][0-9. ]{0,30}") {
            let compact: String = text.chars().filter(|c| *c != ' ').collect();
            let well_formed = compact.chars().any(|c| c.is_ascii_digit()) && compact.matches('.').count() <= 1;
            let got = num(&text).map(|r| r.0);
            if well_formed {
                proptest::prop_assert_eq!(got, Ok(compact.parse::<f64>().expect("std")), "{}", text);
            } else {
                proptest::prop_assert!(got.is_err(), "{}", text);
            }
        }
    }

    #[test]
    fn malformed_numbers_are_errors() {
        assert_eq!(num("."), Err(SyntaxProblem::BadNumber));
        assert_eq!(num("1.2.3"), Err(SyntaxProblem::BadNumber));
    }
}
