//! Lens distortion: OpenCV's Brown–Conrady model (radial `k1`, `k2`; tangential `p1`, `p2`)
//! about the optical centre, in native pixels.
//!
//! A centred pixel `c` (native pixels from the optical centre) has normalised coordinates
//! `n = c / f`, `f` the focal length in pixels (working distance / length per pixel). An ideal
//! (pinhole) point `n = (x, y)` images at `D(n)`:
//!
//! `D_x = x·L + 2·p1·x·y + p2·(r² + 2x²)`, `D_y = y·L + p1·(r² + 2y²) + 2·p2·x·y`,
//! `L = 1 + k1·r² + k2·r⁴`, `r² = x² + y²`.
//!
//! The camera reports distorted pixels; the pixel chain needs the ideal one, `D⁻¹`, which has no
//! closed form: [`Lens::undistort`] solves it by Newton's method (the map is close to the
//! identity, so three steps from the first-order guess reach 1e-9 px over any field where the
//! lens does not fold; [`Lens::check_field`] proves that once, when a chain is built).
//!
//! Decision: the distortion centre is the optical centre the pixel chain uses
//! (`res/2 + PxCenterOffset`, the pixel M283's lift measures), not a separate principal point:
//! a decentred lens shows as `p1`/`p2`. `k3` is not modelled: within a machine camera's field
//! `k2` already reaches the corners' residue and a third radial term cannot be measured apart.

use nalgebra::{Matrix2, Vector2};

use crate::MathError;

/// Chord steps of [`Lens::undistort`] after the first-order guess: a k1 of −0.1 at a 1776 px
/// image's corner needs one, a wide-angle webcam's −0.4 three.
const CHORD_STEPS: usize = 3;
/// Largest undistortion error [`Lens::check_field`] accepts, pixels (2e-7 in at the built-in
/// camera's 0.002 in/px).
pub const FIELD_TOLERANCE_PX: f64 = 1e-4;
/// Grid points per axis [`Lens::check_field`] tries.
const FIELD_GRID: usize = 17;

/// A lens distortion: its four coefficients (dimensionless, OpenCV's convention) on
/// coordinates normalised by `focal_px`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lens {
    k1: f64,
    k2: f64,
    p1: f64,
    p2: f64,
    focal_px: f64,
    /// `1 / focal_px`.
    inv_focal: f64,
}

impl Lens {
    /// The lens `[k1, k2, p1, p2]` normalised by the focal length `focal_px` (pixels).
    ///
    /// # Errors
    /// [`MathError::NonFinite`] for a non-finite coefficient or a focal length that is not
    /// positive and finite.
    pub fn new(coefficients: [f64; 4], focal_px: f64) -> Result<Lens, MathError> {
        if !coefficients.iter().all(|k| k.is_finite()) {
            return Err(MathError::NonFinite { what: "a lens distortion coefficient" });
        }
        if !(focal_px.is_finite() && focal_px > 0.0) {
            return Err(MathError::NonFinite { what: "the lens's focal length" });
        }
        let [k1, k2, p1, p2] = coefficients;
        Ok(Lens { k1, k2, p1, p2, focal_px, inv_focal: 1.0 / focal_px })
    }

    /// `[k1, k2, p1, p2]`, dimensionless.
    #[must_use]
    pub fn coefficients(&self) -> [f64; 4] {
        [self.k1, self.k2, self.p1, self.p2]
    }

    /// The focal length the coefficients are normalised by, pixels.
    #[must_use]
    pub fn focal_px(&self) -> f64 {
        self.focal_px
    }

    /// True when every coefficient is zero (the lens moves no pixel).
    #[must_use]
    pub fn is_identity(&self) -> bool {
        self.coefficients().iter().all(|k| *k == 0.0)
    }

    /// Where the ideal centred pixel `c` images, centred pixels.
    #[inline]
    #[must_use]
    pub fn distort(&self, c: Vector2<f64>) -> Vector2<f64> {
        self.map(c * self.inv_focal) * self.focal_px
    }

    /// `D` on normalised coordinates.
    #[inline]
    fn map(&self, n: Vector2<f64>) -> Vector2<f64> {
        let (x, y) = (n.x, n.y);
        let r2 = x * x + y * y;
        let l = 1.0 + r2 * (self.k1 + self.k2 * r2);
        Vector2::new(
            x * l + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x),
            y * l + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y,
        )
    }

    /// The Jacobian of `D` at normalised `n` (dimensionless; equal to that of
    /// [`Lens::distort`] in pixels).
    #[inline]
    fn jacobian(&self, n: Vector2<f64>) -> Matrix2<f64> {
        let (x, y) = (n.x, n.y);
        let r2 = x * x + y * y;
        let l = 1.0 + r2 * (self.k1 + self.k2 * r2);
        let dl = 2.0 * (self.k1 + 2.0 * self.k2 * r2);
        let cross = x * y * dl + 2.0 * self.p1 * x + 2.0 * self.p2 * y;
        Matrix2::new(
            l + x * x * dl + 2.0 * self.p1 * y + 6.0 * self.p2 * x,
            cross,
            cross,
            l + y * y * dl + 6.0 * self.p1 * y + 2.0 * self.p2 * x,
        )
    }

    /// The ideal centred pixel that images at the distorted centred pixel `c`, pixels: `D⁻¹`
    /// by the chord method (Newton's with the Jacobian of the first-order guess, inverted once:
    /// the map is so near the identity that the Jacobian barely changes between guess and
    /// answer). Within a field [`Lens::check_field`] accepted it is exact to
    /// [`FIELD_TOLERANCE_PX`]; outside, where the lens may fold, it returns the first-order guess.
    #[inline]
    #[must_use]
    pub fn undistort(&self, c: Vector2<f64>) -> Vector2<f64> {
        let target = c * self.inv_focal;
        // First order: D(n) ≈ n + (D(t) − t) near t.
        let mut n = 2.0 * target - self.map(target);
        let j = self.jacobian(n);
        let det = j.m11 * j.m22 - j.m12 * j.m21;
        if !(det > 0.0) {
            return n * self.focal_px;
        }
        let inv = Matrix2::new(j.m22, -j.m12, -j.m21, j.m11) / det;
        for _ in 0..CHORD_STEPS {
            n -= inv * (self.map(n) - target);
        }
        n * self.focal_px
    }

    /// How [`Lens::undistort`]`(c)` moves per unit of each coefficient `[k1, k2, p1, p2]`,
    /// pixels: `−J⁻¹ · ∂D/∂coefficient` at the undistorted point (zero where `J` is singular).
    #[must_use]
    pub fn sensitivity(&self, c: Vector2<f64>) -> [Vector2<f64>; 4] {
        let n = self.undistort(c) * self.inv_focal;
        let Some(inv) = self.jacobian(n).try_inverse() else { return [Vector2::zeros(); 4] };
        coefficient_derivatives(n).map(|d| -(inv * d) * self.focal_px)
    }

    /// Refuses a lens that does not undistort every pixel of an image reaching `lo`..`hi`
    /// (centred pixels: the image's corners less the optical centre) with 10 % margin: the map
    /// folds there, or Newton's method does not reach [`FIELD_TOLERANCE_PX`].
    ///
    /// # Errors
    /// [`MathError::LensFolds`].
    pub fn check_field(&self, lo: Vector2<f64>, hi: Vector2<f64>) -> Result<(), MathError> {
        let (lo, hi) = (lo * 1.1, hi * 1.1);
        let step = |a: f64, b: f64, i: usize| a + (b - a) * i as f64 / (FIELD_GRID - 1) as f64;
        for i in 0..FIELD_GRID {
            for j in 0..FIELD_GRID {
                let c = Vector2::new(step(lo.x, hi.x, i), step(lo.y, hi.y, j));
                let u = self.undistort(c);
                let n = u * self.inv_focal;
                let j = self.jacobian(n);
                let folds = j.determinant() <= 0.0 || n.dot(&(j * n)) < 0.0;
                if folds || !((self.distort(u) - c).norm() <= FIELD_TOLERANCE_PX) {
                    return Err(MathError::LensFolds { x: c.x, y: c.y });
                }
            }
        }
        Ok(())
    }
}

/// `∂D/∂[k1, k2, p1, p2]` at normalised `n` (normalised units per unit coefficient).
#[inline]
pub(crate) fn coefficient_derivatives(n: Vector2<f64>) -> [Vector2<f64>; 4] {
    let (x, y) = (n.x, n.y);
    let r2 = x * x + y * y;
    [n * r2, n * r2 * r2, Vector2::new(2.0 * x * y, r2 + 2.0 * y * y), Vector2::new(r2 + 2.0 * x * x, 2.0 * x * y)]
}

/// The Jacobian of `D` at `n` for `lens`, for the calibration solve.
pub(crate) fn jacobian(lens: &Lens, n: Vector2<f64>) -> Matrix2<f64> {
    lens.jacobian(n)
}

/// `D(n)` for `lens` on normalised coordinates, for the calibration solve.
pub(crate) fn map(lens: &Lens, n: Vector2<f64>) -> Vector2<f64> {
    lens.map(n)
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The built-in camera: 1776 px square, f = 6 in / 0.00203 in/px.
    const F: f64 = 2956.0;

    fn lens(k: [f64; 4]) -> Lens {
        Lens::new(k, F).expect("valid")
    }

    #[test]
    fn the_model_is_opencvs() {
        // x = 0.2, y = 0.1: r² = 0.05; L = 1 − 0.1·0.05 + 0.01·0.0025 = 0.995025.
        let l = lens([-0.1, 0.01, 0.002, -0.001]);
        let d = l.distort(Vector2::new(0.2 * F, 0.1 * F)) / F;
        let x = 0.2 * 0.995_025 + 2.0 * 0.002 * 0.02 - 0.001 * (0.05 + 0.08);
        let y = 0.1 * 0.995_025 + 0.002 * (0.05 + 0.02) - 2.0 * 0.001 * 0.02;
        assert!((d.x - x).abs() < 1e-15 && (d.y - y).abs() < 1e-15, "{d:?}");
        assert!(lens([0.0; 4]).is_identity() && !l.is_identity());
        assert_eq!(l.coefficients(), [-0.1, 0.01, 0.002, -0.001]);
        assert_eq!(l.focal_px(), F);
    }

    #[test]
    fn bad_coefficients_and_focal_lengths_are_refused() {
        assert!(Lens::new([f64::NAN, 0.0, 0.0, 0.0], F).is_err());
        assert!(Lens::new([0.0, 0.0, 0.0, f64::INFINITY], F).is_err());
        for f in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(Lens::new([0.0; 4], f).is_err(), "{f}");
        }
    }

    #[test]
    fn the_jacobian_and_sensitivities_match_finite_differences() {
        let l = lens([-0.12, 0.03, 0.002, -0.0015]);
        let c = Vector2::new(700.0, -450.0);
        let n = c / F;
        let h = 1e-6;
        let j = l.jacobian(n);
        for (col, e) in [Vector2::x(), Vector2::y()].iter().enumerate() {
            let fd = (l.map(n + e * h) - l.map(n - e * h)) / (2.0 * h);
            assert!((j.column(col) - fd).norm() < 1e-8, "column {col}: {} vs {fd}", j.column(col));
        }
        let s = l.sensitivity(c);
        for (i, si) in s.iter().enumerate() {
            let mut plus = l.coefficients();
            let mut minus = plus;
            plus[i] += h;
            minus[i] -= h;
            let fd = (lens(plus).undistort(c) - lens(minus).undistort(c)) / (2.0 * h);
            assert!((si - fd).norm() < 1e-4 * fd.norm().max(1.0), "coefficient {i}: {si} vs {fd}");
        }
    }

    #[test]
    fn a_folding_lens_is_refused_over_its_field() {
        // Strong barrel turns back before 0.6 of f: r·(1 − 2r²) peaks at r = 0.41.
        let l = lens([-2.0, 0.0, 0.0, 0.0]);
        let half = Vector2::new(0.3 * F, 0.3 * F);
        assert!(matches!(l.check_field(-half, half), Err(MathError::LensFolds { .. })));
        assert_eq!(lens([-0.1, 0.0, 0.002, -0.001]).check_field(-half, half), Ok(()));
    }

    proptest! {
        #[test]
        fn undistort_inverts_distort_over_a_machine_cameras_field(
            k1 in -0.3f64..0.3, k2 in -0.1f64..0.1, p1 in -0.005f64..0.005, p2 in -0.005f64..0.005,
            x in -0.45f64..0.45, y in -0.45f64..0.45,
        ) {
            let l = lens([k1, k2, p1, p2]);
            let half = Vector2::new(0.35 * F, 0.35 * F);
            prop_assume!(l.check_field(-half, half).is_ok());
            let u = Vector2::new(x, y) * 0.3 * F / 0.45;
            let back = l.undistort(l.distort(u));
            prop_assert!((back - u).norm() < 1e-6, "{u} -> {back}");
        }
    }
}
