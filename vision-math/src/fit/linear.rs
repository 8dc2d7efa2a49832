//! The 2×2 least-squares solve `M·pᵢ ≈ qᵢ` (no translation) that calibration needs.

use nalgebra::{Matrix2, Vector2};

use crate::MathError;

/// Result of [`solve_linear`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearFit {
    /// The matrix `M` (units of q per unit of p).
    pub m: Matrix2<f64>,
    /// RMS of `‖M·pᵢ − qᵢ‖`, units of q.
    pub rms: f64,
    /// Largest `‖M·pᵢ − qᵢ‖`, units of q.
    pub max_residual: f64,
}

/// Solves `M·pᵢ ≈ qᵢ` for the 2×2 `M` by least squares: `M = (Σ q·pᵀ)(Σ p·pᵀ)⁻¹`.
///
/// Calibration uses it with `p` = pixel displacements and `q` = machine moves, giving K.
///
/// # Errors
/// Fewer than 2 pairs, length mismatch, non-finite input, or `p` vectors that do not span the
/// plane (all zero or all parallel).
pub fn solve_linear(p: &[Vector2<f64>], q: &[Vector2<f64>]) -> Result<LinearFit, MathError> {
    if p.len() != q.len() {
        return Err(MathError::LengthMismatch { commanded: p.len(), observed: q.len() });
    }
    if p.len() < 2 {
        return Err(MathError::TooFewPoints { model: "2x2 linear", needed: 2, got: p.len() });
    }
    let mut pp = Matrix2::zeros();
    let mut qp = Matrix2::zeros();
    for (a, b) in p.iter().zip(q) {
        pp += a * a.transpose();
        qp += b * a.transpose();
    }
    if !pp.iter().all(|v| v.is_finite()) {
        return Err(MathError::NonFinite { what: "a source vector" });
    }
    if !qp.iter().all(|v| v.is_finite()) {
        return Err(MathError::NonFinite { what: "a target vector" });
    }
    let tr = pp[(0, 0)] + pp[(1, 1)];
    let det = pp.determinant();
    // λmin·λmax = det, λmax ≤ tr: λmin/λmax ≥ det/tr².
    if tr == 0.0 {
        return Err(MathError::CoincidentPoints);
    }
    if det <= 1e-9 * tr * tr {
        return Err(MathError::CollinearPoints { model: "2x2 linear" });
    }
    let inv = Matrix2::new(pp[(1, 1)], -pp[(0, 1)], -pp[(1, 0)], pp[(0, 0)]) / det;
    let m = qp * inv;
    let mut sum2 = 0.0;
    let mut max2: f64 = 0.0;
    for (a, b) in p.iter().zip(q) {
        let r2 = (m * a - b).norm_squared();
        sum2 += r2;
        max2 = max2.max(r2);
    }
    let rms = (sum2 / p.len() as f64).sqrt();
    Ok(LinearFit { m, rms, max_residual: max2.sqrt() })
}
