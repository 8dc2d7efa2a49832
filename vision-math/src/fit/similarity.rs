//! Similarity: shift, rotation, one uniform scale.

use nalgebra::{Matrix2, Point2, Vector2};

use super::{unit, Fit, LinearPart, Model, Moments};
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
pub(super) fn solve(m: &Moments) -> Result<LinearPart, MathError> {
    let d = m.sxx + m.syy;
    let (re, im) = (m.pxx + m.pyy, m.pxy - m.pyx);
    // L = s·R(θ) = [[re, −im], [im, re]] / d needs no square root; only splitting it into s and
    // θ does, and that runs beside the residual pass.
    let inv_d = 1.0 / d;
    let (a, b) = (re * inv_d, im * inv_d);
    let (rotation, h) = unit(re, im, d).ok_or(MathError::DegenerateObserved)?;
    let s = h * inv_d;
    Ok(LinearPart { rotation, scale: Vector2::new(s, s), shear: 0.0, linear: Matrix2::new(a, -b, b, a) })
}
