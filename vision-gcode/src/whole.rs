//! Whole numbers from G-code values (codes, parameter numbers, tools): a leaf, used by the word
//! reader and the parameter store alike.

/// `value` as a whole number in `0..=max`, when it lies within `tolerance` of one (never for
/// NaN).
pub(crate) fn whole_in(value: f64, tolerance: f64, max: u32) -> Option<u32> {
    let r = value.round();
    if (value - r).abs() < tolerance && (0.0..=f64::from(max)).contains(&r) {
        #[expect(clippy::cast_possible_truncation, clippy::cast_sign_loss, reason = "Whole and in 0..=max: exact.")]
        Some(r as u32)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::whole_in;

    #[test]
    fn whole_within_the_tolerance_and_the_range_only() {
        assert_eq!(whole_in(f64::NAN, 0.5, 10), None);
        assert_eq!(whole_in(10.4, 0.5, 10), Some(10));
        assert_eq!(whole_in(10.6, 0.5, 10), None);
        assert_eq!(whole_in(-0.4, 0.5, 10), Some(0));
    }
}
