//! Similarity: shift, rotation, one uniform scale.

use nalgebra::{Complex, Matrix2, Point2, UnitComplex, Vector2};

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
    let h = (re * re + im * im).sqrt();
    let s = h * inv_d;
    // One test for the common case: a scale in range is finite and far above `unit`'s
    // 10⁻¹⁴ (d > 0 after the spread check), so it implies everything `unit` tests; only a
    // refused scale asks `unit` and `LinearPart::check` which error it is.
    if !LinearPart::scale_in_range(s) {
        return Err(refusal(re, im, d, s, Matrix2::new(a, -b, b, a)));
    }
    let rotation = UnitComplex::new_unchecked(Complex::new(re / h, im / h));
    Ok(LinearPart { rotation, scale: Vector2::new(s, s), shear: 0.0, linear: Matrix2::new(a, -b, b, a) })
}

/// The error the checks in order give for a scale out of range: no direction (`unit`), else
/// what `LinearPart::check` says of the parameters.
#[cold]
#[inline(never)]
fn refusal(re: f64, im: f64, d: f64, s: f64, linear: Matrix2<f64>) -> MathError {
    match unit(re, im, d) {
        None => MathError::DegenerateObserved,
        Some((rotation, _)) => LinearPart { rotation, scale: Vector2::new(s, s), shear: 0.0, linear }.refusal(),
    }
}
