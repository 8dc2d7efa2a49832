//! Rigid (Procrustes): shift and rotation.

use nalgebra::{Point2, Vector2};

use super::{unit, Fit, LinearPart, Model, Moments};
use crate::MathError;

/// Least-squares rigid transform (rotation + shift) from `commanded` to `observed`.
///
/// θ = atan2(Σa×q, Σa·q) on centred points; scale is fixed at 1. Lengths in machine units.
///
/// # Errors
/// Too few points (< 2), length mismatch, non-finite input, coincident commanded points, or
/// observed points that carry no rotation.
pub fn fit_rigid(commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> Result<Fit, MathError> {
    Model::Rigid.fit(commanded, observed)
}

#[inline(always)]
pub(super) fn solve(m: &Moments) -> Result<LinearPart, MathError> {
    let (rotation, _) = unit(m.pxx + m.pyy, m.pxy - m.pyx, m.sxx + m.syy).ok_or(MathError::DegenerateObserved)?;
    Ok(LinearPart::from_parts(rotation, Vector2::new(1.0, 1.0), 0.0))
}
