//! Numbers in messages: one formatter, so a huge or tiny value reads as `1e300` or `1e-9`,
//! never as hundreds of digits or a float's rounding noise (`0.0000000009999999999999999`).
//!
//! G-code output does not use it: lines are written with fixed decimals
//! ([`crate::chain::fixed`]) after their values are checked against [`crate::bounds`].

/// Significant digits a message shows (more than any machine resolves).
const DIGITS: i32 = 10;

/// `x` for a message: up to 10 significant digits, trailing zeros dropped; scientific
/// notation from 1e9 up and below 1e-6 (`1e300`, `-2.5e-300`); `NaN`, `inf`, `-inf` as such.
///
/// ```
/// use vision_math::show::number;
/// assert_eq!(number(1e300), "1e300");
/// assert_eq!(number(0.000_000_000_999_999_999_999_999_9), "1e-9");
/// assert_eq!(number(0.1 + 0.2), "0.3");
/// assert_eq!(number(-12.5), "-12.5");
/// ```
#[must_use]
pub fn number(x: f64) -> String {
    if !x.is_finite() {
        return x.to_string();
    }
    if x == 0.0 {
        return "0".to_string();
    }
    // Rounded to DIGITS significant digits first, so the exponent is that of the rounded value.
    let sci = format!("{:.*e}", (DIGITS - 1) as usize, x);
    let Some((mantissa, exp)) = sci.split_once('e') else { return sci };
    let exp: i32 = exp.parse().unwrap_or(0);
    if (-6..9).contains(&exp) {
        let decimals = usize::try_from(DIGITS - 1 - exp).unwrap_or(0);
        trim(&format!("{x:.decimals$}")).to_string()
    } else {
        format!("{}e{exp}", trim(mantissa))
    }
}

/// `s` without trailing decimal zeros (and without a trailing point).
fn trim(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::number;
    use proptest::prelude::*;

    #[test]
    fn the_issues_values_read_short() {
        for (x, shown) in [
            (1e300, "1e300"),
            (1e-300, "1e-300"),
            (-1e308, "-1e308"),
            (f64::MAX, "1.797693135e308"),
            (f64::MIN_POSITIVE, "2.225073859e-308"),
            (0.000_000_000_999_999_999_999_999_9, "1e-9"),
            (1e9, "1e9"),
            (999_999_999.9, "999999999.9"),
            (1e15, "1e15"),
            (0.000_001, "0.000001"),
            (0.000_000_9, "9e-7"),
            (123.456, "123.456"),
            (-0.5, "-0.5"),
            (3.0, "3"),
            (0.0, "0"),
            (-0.0, "0"),
            (f64::NAN, "NaN"),
            (f64::NEG_INFINITY, "-inf"),
        ] {
            assert_eq!(number(x), shown, "{x:e}");
        }
    }

    proptest! {
        /// Short, and the value read back is the value to 10 significant digits.
        #[test]
        fn every_finite_value_reads_back_close_and_short(x in proptest::num::f64::NORMAL | proptest::num::f64::SUBNORMAL | proptest::num::f64::ZERO) {
            let shown = number(x);
            prop_assert!(shown.len() <= 24, "{shown}");
            let back: f64 = shown.parse().expect("a number Rust reads");
            let tolerance = x.abs() * 1e-9;
            prop_assert!((back - x).abs() <= tolerance, "{x:e} shown as {shown}");
        }
    }
}
