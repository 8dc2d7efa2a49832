//! The bounds every crate holds numbers from outside to, defined once: a controller's position
//! or offset, a G-code word, a fit's coordinate, a rotation. Past them a number is an error of
//! units or input, not a place a machine can be, and printing it with fixed decimals would
//! write hundreds of digits (or round a huge value's fraction away).

/// The largest magnitude of a coordinate, offset or length, machine units (in or mm): 10⁹ in
/// is 25 000 km, far beyond any machine, and squares and sums of such values stay finite.
pub const MAX_COORDINATE: f64 = 1e9;

/// The largest magnitude of a rotation, degrees (a million degrees is 2 778 turns: any real
/// G5x or G68 rotation is far below it, and 7 decimals of it stay exact in an `f64`).
pub const MAX_ROTATION_DEG: f64 = 1e6;

use crate::MathError;

/// `value` when it is finite and within ±[`MAX_COORDINATE`].
///
/// # Errors
/// [`MathError::NonFinite`] or [`MathError::BeyondBound`], naming `what`.
pub fn coordinate(what: &'static str, value: f64) -> Result<f64, MathError> {
    within(what, value, MAX_COORDINATE, "machine units")
}

/// `value`, degrees, when it is finite and within ±[`MAX_ROTATION_DEG`].
///
/// # Errors
/// [`MathError::NonFinite`] or [`MathError::BeyondBound`], naming `what`.
pub fn rotation_deg(what: &'static str, value: f64) -> Result<f64, MathError> {
    within(what, value, MAX_ROTATION_DEG, "degrees")
}

fn within(what: &'static str, value: f64, limit: f64, unit: &'static str) -> Result<f64, MathError> {
    if !value.is_finite() {
        Err(MathError::NonFinite { what })
    } else if value.abs() > limit {
        Err(MathError::BeyondBound { what, value, limit, unit })
    } else {
        Ok(value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_past_a_bound_are_refused_readably() {
        assert_eq!(coordinate("X", -1e9), Ok(-1e9));
        let e = coordinate("the controller's X position", 1e308).expect_err("far");
        assert_eq!(
            e.to_string(),
            "the controller's X position is 1e308, beyond ±1e9 (machine units); check the controller's value and units"
        );
        assert!(matches!(rotation_deg("R", f64::NAN), Err(MathError::NonFinite { what: "R" })));
        assert!(matches!(rotation_deg("R", 1.000_001e6), Err(MathError::BeyondBound { .. })));
        assert_eq!(rotation_deg("R", -359.5), Ok(-359.5));
    }
}
