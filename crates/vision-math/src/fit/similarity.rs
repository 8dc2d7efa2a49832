//! Similarity: shift, rotation, one uniform scale.

use nalgebra::{Point2, Vector2};

use super::{unit, Fit, Model, Moments, Params};
use crate::MathError;

/// Least-squares similarity from `commanded` to `observed` (closed form, Umeyama without SVD).
///
/// With centred `aᵢ = nᵢ − n̄`, `qᵢ = oᵢ − ō`: `s·cos θ = Σa·q / Σ‖a‖²`,
/// `s·sin θ = Σa×q / Σ‖a‖²`. Lengths in machine units, θ in radians (see [`Fit`]).
///
/// # Errors
/// Too few points (< 2), length mismatch, non-finite input, coincident commanded points, or
/// observed points that collapse to one point.
pub fn fit_similarity(commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> Result<Fit, MathError> {
    Model::Similarity.fit(commanded, observed)
}

#[inline(always)]
pub(super) fn solve(m: &Moments) -> Result<Params, MathError> {
    let d = m.sxx + m.syy;
    let (rotation, h) = unit(m.pxx + m.pyy, m.pxy - m.pyx, d).ok_or(MathError::DegenerateObserved)?;
    let s = h / d;
    Ok(Params { rotation, scale: Vector2::new(s, s), shear: 0.0 })
}
