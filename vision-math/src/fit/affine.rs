//! Affine: shift and a full 2×2 matrix.

use nalgebra::{Complex, Matrix2, Point2, UnitComplex, Vector2};

use super::{unit, Fit, LinearPart, Model, Moments};
use crate::MathError;

/// Least-squares affine fit `o ≈ L·n + b` (6 parameters), closed form on centred moments:
/// `L = (Σ q·aᵀ)(Σ a·aᵀ)⁻¹`.
///
/// `L` is reported as `R(θ)·[[sx, shear], [0, sy]]` (QR with `sx > 0`). Lengths in machine
/// units, θ in radians.
///
/// # Errors
/// Too few points (< 3), length mismatch, non-finite input, coincident or collinear commanded
/// points, or a fitted matrix with a zero first column.
pub fn fit_affine(commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> Result<Fit, MathError> {
    Model::Affine.fit(commanded, observed)
}

#[inline(always)]
pub(super) fn solve(m: &Moments) -> Result<LinearPart, MathError> {
    m.require_area(Model::Affine)?;
    let det = m.sxx * m.syy - m.sxy * m.sxy;
    let cinv = Matrix2::new(m.syy, -m.sxy, -m.sxy, m.sxx) / det;
    let p = Matrix2::new(m.pxx, m.pyx, m.pxy, m.pyy);
    let l = p * cinv;
    let rotation =
        unit(l[(0, 0)], l[(1, 0)], l.norm()).map_or(UnitComplex::new_unchecked(Complex::new(1.0, 0.0)), |(r, _)| r);
    let (c, s) = (rotation.re, rotation.im);
    let sx = c * l[(0, 0)] + s * l[(1, 0)];
    let shear = c * l[(0, 1)] + s * l[(1, 1)];
    let sy = -s * l[(0, 1)] + c * l[(1, 1)];
    if sx.is_nan() || sx <= 0.0 {
        return Err(MathError::DegenerateObserved);
    }
    Ok(LinearPart { rotation, scale: Vector2::new(sx, sy), shear, linear: l })
}
