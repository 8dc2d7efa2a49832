//! Rectangle: shift, rotation, separate X and Y scale, no shear.

use nalgebra::{Point2, Vector2};

use super::{unit, Fit, LinearPart, Model, Moments};
use crate::MathError;

/// The true least-squares rectangle fit `o ≈ R(θ)·diag(sx, sy)·n + b` (5 parameters).
///
/// For a fixed θ the best `sx`, `sy` and `b` are linear least squares; eliminating them leaves
/// `max over (cos θ, sin θ) on the unit circle of (c·Pxx + s·Pxy)²/Sxx + (c·Pyy − s·Pyx)²/Syy`,
/// a quadratic form whose maximiser is the top eigenvector of a symmetric 2×2 matrix — so the
/// global minimum comes in closed form, with one square root and no trigonometry.
/// (`Sxx = Σaₓ²`, `Pxy = Σaₓq_y`, … on centred points.) Of the two opposite eigenvectors the
/// one with `sx + sy > 0` is returned; a negative factor left after that is a real mirror.
///
/// Lengths in machine units, θ in radians (see [`Fit`]).
///
/// # Errors
/// Too few points (< 3), length mismatch, non-finite input, coincident or collinear commanded
/// points, or observed points that leave the rotation undetermined.
pub fn fit_rectangle(commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> Result<Fit, MathError> {
    Model::Rectangle.fit(commanded, observed)
}

#[inline(always)]
pub(super) fn solve(m: &Moments) -> Result<LinearPart, MathError> {
    m.require_area(Model::Rectangle)?;
    let (ix, iy) = (1.0 / m.sxx, 1.0 / m.syy);
    let m11 = m.pxx * m.pxx * ix + m.pyy * m.pyy * iy;
    let m22 = m.pxy * m.pxy * ix + m.pyx * m.pyx * iy;
    let m12 = m.pxx * m.pxy * ix - m.pyy * m.pyx * iy;
    let h = 0.5 * (m11 - m22);
    let r = (h * h + m12 * m12).sqrt();
    // Eigenvector of the larger eigenvalue (h + r ≥ 0 always); pick the better-conditioned form.
    let (vc, vs) = if h >= 0.0 { (h + r, m12) } else { (m12, r - h) };
    let reference = m11.abs() + m22.abs();
    if r.is_nan() || r <= 1e-13 * reference {
        // Equal eigenvalues: every rotation fits equally well.
        return Err(MathError::DegenerateObserved);
    }
    let (mut rotation, _) = unit(vc, vs, reference).ok_or(MathError::DegenerateObserved)?;
    let (c, s) = (rotation.re, rotation.im);
    let mut sx = (c * m.pxx + s * m.pxy) * ix;
    let mut sy = (c * m.pyy - s * m.pyx) * iy;
    if sx + sy < 0.0 {
        rotation = nalgebra::UnitComplex::new_unchecked(nalgebra::Complex::new(-c, -s));
        sx = -sx;
        sy = -sy;
    }
    Ok(LinearPart::from_parts(rotation, Vector2::new(sx, sy), 0.0))
}
