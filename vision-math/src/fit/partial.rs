//! Partial alignments: one piece of the transform alone (M282 `P1` shift, `P2` rotation,
//! `P3` scale).
//!
//! Each piece is the least-squares optimum of a model that holds **only** that piece, so what
//! is emitted is the best transform of that kind, not a slice of a fuller fit:
//!
//! | piece | model `o ≈ f(n)` | least-squares solution |
//! | --- | --- | --- |
//! | shift | `n + t` | `t = ō − n̄` |
//! | rotation | `R(θ)·(n − n̄) + n̄` (about the commanded centroid, no shift) | `θ = atan2(Σa×q, Σa·q)`: the rigid Procrustes angle |
//! | scale | `S·(n − n̄) + n̄` (about the commanded centroid, no shift, no rotation) | per axis `sx = Σaₓqₓ/Σaₓ²`, `sy = Σa_yq_y/Σa_y²`; uniform `s = Σa·q/Σ‖a‖²` |
//!
//! (`a = n − n̄`, `q = o − ō`; because `Σa = 0`, the terms with `ō − n̄` drop out.)
//!
//! G51 scales about the program origin, so the scale piece's [`AlignmentChain`] carries the
//! compensating `G52` shift `n̄ − S·n̄` that keeps the commanded centroid in place; it is not a
//! measured shift.

use nalgebra::{Point2, Vector2};

use super::{unit, Model, Moments};
use crate::{AlignmentChain, MathError};

/// Which single piece of an alignment to solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Piece {
    /// Shift only (`G52`).
    Shift,
    /// Rotation only, about the commanded centroid (`G68`).
    Rotation,
    /// Scale only, about the commanded centroid (`G51`, with the compensating `G52`).
    /// `uniform` fits one factor for both axes (similarity runs), else one per axis.
    Scale {
        /// One factor for both axes.
        uniform: bool,
    },
}

/// A solved single-piece alignment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartialFit {
    /// The piece solved.
    pub piece: Piece,
    /// The chain that executes it (the other pieces are identity).
    pub chain: AlignmentChain,
    /// Number of point pairs used.
    pub len: usize,
    /// RMS of `‖chain(nᵢ) − oᵢ‖`, machine units.
    pub rms: f64,
    /// Largest `‖chain(nᵢ) − oᵢ‖`, machine units.
    pub max_residual: f64,
}

/// Solves `piece` alone from `commanded` to `observed` by least squares (see the module doc).
///
/// # Errors
/// Fewer than 2 points, length mismatch, non-finite input, coincident commanded points; for a
/// rotation, observed points that carry no rotation; for a per-axis scale, commanded points
/// that do not spread along both axes; for a scale, a factor that is not positive.
pub fn fit_piece(piece: Piece, commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> Result<PartialFit, MathError> {
    let m = Moments::new(Model::Rigid, commanded, observed)?;
    let cn = Point2::from(m.cn);
    let chain = match piece {
        Piece::Shift => AlignmentChain { center: cn, shift: m.co - m.cn, ..AlignmentChain::IDENTITY },
        Piece::Rotation => {
            let (r, _) = unit(m.pxx + m.pyy, m.pxy - m.pyx, m.sxx + m.syy).ok_or(MathError::DegenerateObserved)?;
            AlignmentChain { center: cn, rotation_deg: r.im.atan2(r.re).to_degrees(), ..AlignmentChain::IDENTITY }
        }
        Piece::Scale { uniform } => {
            let scale = if uniform {
                let s = (m.pxx + m.pyy) / (m.sxx + m.syy);
                Vector2::new(s, s)
            } else {
                let spread = m.sxx + m.syy;
                if m.sxx <= 1e-9 * spread || m.syy <= 1e-9 * spread {
                    return Err(MathError::CollinearPoints { model: "per-axis scale" });
                }
                Vector2::new(m.pxx / m.sxx, m.pyy / m.syy)
            };
            if !(scale.x > 0.0 && scale.y > 0.0 && scale.x.is_finite() && scale.y.is_finite()) {
                return Err(MathError::DegenerateObserved);
            }
            let shift = m.cn - Vector2::new(scale.x * m.cn.x, scale.y * m.cn.y);
            AlignmentChain { scale, center: cn, shift, ..AlignmentChain::IDENTITY }
        }
    };
    let mut sum2 = 0.0;
    let mut max2: f64 = 0.0;
    for (n, o) in commanded.iter().zip(observed) {
        let r2 = (chain.apply(*n) - o).norm_squared();
        sum2 += r2;
        max2 = max2.max(r2);
    }
    let rms = (sum2 / m.len as f64).sqrt();
    if !(rms.is_finite() && max2.is_finite()) {
        return Err(MathError::NonFinite { what: "a residual" });
    }
    Ok(PartialFit { piece, chain, len: m.len, rms, max_residual: max2.sqrt() })
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;
    use crate::fit::fit_rigid;
    use approx::assert_relative_eq;

    fn square() -> Vec<Point2<f64>> {
        vec![Point2::new(0.0, 0.0), Point2::new(6.0, 0.0), Point2::new(6.0, 4.0), Point2::new(0.0, 4.0)]
    }

    #[test]
    fn shift_is_the_centroid_difference() {
        let n = square();
        let o: Vec<_> = n.iter().map(|p| p + Vector2::new(0.1, -0.2)).collect();
        let f = fit_piece(Piece::Shift, &n, &o).expect("fit");
        assert_relative_eq!(f.chain.shift, Vector2::new(0.1, -0.2), epsilon = 1e-12);
        assert_eq!(f.chain.rotation_deg, 0.0);
        assert_eq!(f.chain.scale, Vector2::new(1.0, 1.0));
        assert!(f.max_residual < 1e-12);
    }

    #[test]
    fn rotation_about_the_centroid_matches_rigid_angle_and_no_shift() {
        let n = square();
        let c = Vector2::new(3.0, 2.0);
        let th = 0.7f64.to_radians();
        let (s, co) = th.sin_cos();
        let o: Vec<_> = n
            .iter()
            .map(|p| {
                let a = p.coords - c;
                Point2::from(Vector2::new(co * a.x - s * a.y, s * a.x + co * a.y) + c)
            })
            .collect();
        let f = fit_piece(Piece::Rotation, &n, &o).expect("fit");
        assert_relative_eq!(f.chain.rotation_deg, 0.7, epsilon = 1e-12);
        assert_eq!(f.chain.shift, Vector2::zeros());
        assert!(f.max_residual < 1e-12);
        // With an added shift, the angle is still the rigid Procrustes angle.
        let o2: Vec<_> = o.iter().map(|p| p + Vector2::new(0.3, 0.1)).collect();
        let f2 = fit_piece(Piece::Rotation, &n, &o2).expect("fit");
        let rigid = fit_rigid(&n, &o2).expect("rigid");
        assert_relative_eq!(f2.chain.rotation_deg, rigid.transform.theta_deg(), epsilon = 1e-12);
    }

    #[test]
    fn scale_keeps_the_centroid_and_executes_exactly() {
        let n = square();
        let c = Vector2::new(3.0, 2.0);
        let o: Vec<_> = n.iter().map(|p| Point2::new(1.01 * (p.x - c.x) + c.x, 0.98 * (p.y - c.y) + c.y)).collect();
        let f = fit_piece(Piece::Scale { uniform: false }, &n, &o).expect("fit");
        assert_relative_eq!(f.chain.scale, Vector2::new(1.01, 0.98), epsilon = 1e-12);
        assert_relative_eq!(f.chain.apply(Point2::from(c)), Point2::from(c), epsilon = 1e-12);
        assert!(f.max_residual < 1e-12);
        let u = fit_piece(Piece::Scale { uniform: true }, &n, &o).expect("fit");
        assert_relative_eq!(u.chain.scale.x, u.chain.scale.y);
        assert!(u.rms > 0.0);
    }

    #[test]
    fn degenerate_input_is_an_error() {
        let n = [Point2::new(0.0, 0.0), Point2::new(1.0, 0.0)];
        let o = [Point2::new(0.0, 0.0), Point2::new(1.0, 0.0)];
        assert!(matches!(fit_piece(Piece::Scale { uniform: false }, &n, &o), Err(MathError::CollinearPoints { .. })));
        assert!(fit_piece(Piece::Shift, &n[..1], &o[..1]).is_err());
        let bad = [Point2::new(f64::NAN, 0.0), Point2::new(1.0, 0.0)];
        assert!(fit_piece(Piece::Shift, &n, &bad).is_err());
        let flipped = [Point2::new(1.0, 0.0), Point2::new(0.0, 0.0)];
        assert!(fit_piece(Piece::Scale { uniform: true }, &n, &flipped).is_err());
        let same = [Point2::new(0.5, 0.5), Point2::new(0.5, 0.5)];
        assert!(matches!(fit_piece(Piece::Rotation, &n, &same), Err(MathError::DegenerateObserved)));
    }
}
