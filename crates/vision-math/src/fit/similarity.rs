//! Similarity: shift, rotation, one uniform scale.

use nalgebra::{Point2, Vector2};

use super::{unit, Fit, Model, Moments};
use crate::MathError;

/// Least-squares similarity from `commanded` to `observed` (closed form, Umeyama without SVD).
///
/// With centred `aᵢ = nᵢ − n̄`, `qᵢ = oᵢ − ō`: `s·cos θ = Σa·q / Σ‖a‖²`,
/// `s·sin θ = Σa×q / Σ‖a‖²`. Lengths in machine units, θ in radians (see [`Fit`]).
///
/// # Errors
/// Too few points (< 2), length mismatch, non-finite input, coincident commanded points, or
/// observed points that collapse to one point.
pub fn fit_similarity(commanded: &[nalgebra::Point2<f64>], observed: &[Point2<f64>]) -> Result<Fit, MathError> {
    let m = Moments::new(Model::Similarity, commanded, observed)?;
    let d = m.sxx + m.syy;
    let a = m.pxx + m.pyy;
    let b = m.pxy - m.pyx;
    let (rotation, h) = unit(a, b, d).ok_or(MathError::DegenerateObserved)?;
    let s = h / d;
    m.finish(Model::Similarity, rotation, Vector2::new(s, s), 0.0, commanded, observed)
}
