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
//! lens does not fold; [`Lens::fitted_to_field`] proves that once, when a chain is built).
//!
//! Decision: the distortion centre is the optical centre the pixel chain uses
//! (`res/2 + PxCenterOffset`, the pixel M283's lift measures), not a separate principal point:
//! a decentred lens shows as `p1`/`p2`. `k3` is not modelled: within a machine camera's field
//! `k2` already reaches the corners' residue and a third radial term cannot be measured apart.

use nalgebra::{Matrix2, Vector2};

use crate::MathError;

/// Most chord steps [`Lens::undistort`] takes after the first-order guess (a wide-angle
/// webcam's k1 of −0.4 needs three at its corners; a k1 of −0.1 one).
const MAX_CHORD_STEPS: u8 = 4;
/// Largest undistortion error [`Lens::fitted_to_field`] accepts, pixels: 4e-7 in at the built-in
/// camera's 0.002 in/px, below the 1e-6 in a noiseless cut must reach; one chord step reaches
/// it over the built-in camera's whole image with a k1 of −0.1 (1.1e-4 px at its corners).
pub const FIELD_TOLERANCE_PX: f64 = 2e-4;
/// Grid points per axis [`Lens::fitted_to_field`] tries.
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
    /// Chord steps [`Lens::undistort`] takes: [`MAX_CHORD_STEPS`] until
    /// [`Lens::fitted_to_field`] found how few its field needs.
    steps: u8,
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
        Ok(Lens { k1, k2, p1, p2, focal_px, inv_focal: 1.0 / focal_px, steps: MAX_CHORD_STEPS })
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

    /// Where the ideal centred pixel `c` images, centred pixels.
    #[inline]
    #[must_use]
    pub fn distort(&self, c: Vector2<f64>) -> Vector2<f64> {
        self.map(c * self.inv_focal) * self.focal_px
    }

    /// `D` on normalised coordinates.
    #[inline]
    fn map(&self, n: Vector2<f64>) -> Vector2<f64> {
        let (x, y) = self.map_xy(n.x, n.y);
        Vector2::new(x, y)
    }

    /// `D(x, y)`.
    #[inline]
    fn map_xy(&self, x: f64, y: f64) -> (f64, f64) {
        let r2 = x * x + y * y;
        let l = 1.0 + r2 * (self.k1 + self.k2 * r2);
        let xy2 = 2.0 * x * y;
        (x * l + self.p1 * xy2 + self.p2 * (r2 + 2.0 * x * x), y * l + self.p1 * (r2 + 2.0 * y * y) + self.p2 * xy2)
    }

    /// The Jacobian of `D` at normalised `n` (dimensionless; equal to that of
    /// [`Lens::distort`] in pixels).
    #[inline]
    fn jacobian(&self, n: Vector2<f64>) -> Matrix2<f64> {
        let (a, cross, d) = self.jacobian_terms(n.x, n.y);
        Matrix2::new(a, cross, cross, d)
    }

    /// The Jacobian of `D` at `(x, y)` as its three distinct entries `(∂x/∂x, ∂x/∂y, ∂y/∂y)`
    /// (it is symmetric).
    #[inline]
    fn jacobian_terms(&self, x: f64, y: f64) -> (f64, f64, f64) {
        let r2 = x * x + y * y;
        let l = 1.0 + r2 * (self.k1 + self.k2 * r2);
        let dl = 2.0 * (self.k1 + 2.0 * self.k2 * r2);
        let cross = x * y * dl + 2.0 * (self.p1 * x + self.p2 * y);
        (
            l + x * x * dl + 2.0 * self.p1 * y + 6.0 * self.p2 * x,
            cross,
            l + y * y * dl + 6.0 * self.p1 * y + 2.0 * self.p2 * x,
        )
    }

    /// The ideal centred pixel that images at the distorted centred pixel `c`, pixels: `D⁻¹`
    /// by the chord method (Newton's with the Jacobian of the first-order guess, inverted once:
    /// the map is so near the identity that the Jacobian barely changes between guess and
    /// answer). Within a field [`Lens::fitted_to_field`] accepted it is exact to
    /// [`FIELD_TOLERANCE_PX`]; outside, where the lens may fold, it returns the first-order guess.
    #[inline]
    #[must_use]
    pub fn undistort(&self, c: Vector2<f64>) -> Vector2<f64> {
        let (tx, ty) = (c.x * self.inv_focal, c.y * self.inv_focal);
        // First order: D(n) ≈ n + (D(t) − t) near t.
        let (dx, dy) = self.map_xy(tx, ty);
        let (mut x, mut y) = (2.0 * tx - dx, 2.0 * ty - dy);
        // The Jacobian there (symmetric), inverted once.
        let (a, cross, d) = self.jacobian_terms(x, y);
        let det = a * d - cross * cross;
        if !(det > 0.0) {
            return Vector2::new(x, y) * self.focal_px;
        }
        let inv = 1.0 / det;
        let (ia, ib, id) = (d * inv, -cross * inv, a * inv);
        for _ in 0..self.steps {
            let (mx, my) = self.map_xy(x, y);
            let (ex, ey) = (mx - tx, my - ty);
            x -= ia * ex + ib * ey;
            y -= ib * ex + id * ey;
        }
        Vector2::new(x * self.focal_px, y * self.focal_px)
    }

    /// How [`Lens::undistort`]`(c)` moves per unit of each coefficient `[k1, k2, p1, p2]`,
    /// pixels: `−J⁻¹ · ∂D/∂coefficient` at the undistorted point (zero where `J` is singular).
    #[must_use]
    pub fn sensitivity(&self, c: Vector2<f64>) -> [Vector2<f64>; 4] {
        let n = self.undistort(c) * self.inv_focal;
        let Some(inv) = self.jacobian(n).try_inverse() else { return [Vector2::zeros(); 4] };
        coefficient_derivatives(n).map(|d| -(inv * d) * self.focal_px)
    }

    /// This lens for an image reaching `lo`..`hi` (centred pixels: the image's corners less the
    /// optical centre: a mark is read inside the image), taking the fewest chord steps that undistort all of it
    /// to [`FIELD_TOLERANCE_PX`].
    ///
    /// # Errors
    /// [`MathError::LensFolds`] where the map folds, or where [`MAX_CHORD_STEPS`] do not reach
    /// the tolerance.
    pub fn fitted_to_field(&self, lo: Vector2<f64>, hi: Vector2<f64>) -> Result<Lens, MathError> {
        let mut first_failure = None;
        for steps in 1..=MAX_CHORD_STEPS {
            let lens = Lens { steps, ..*self };
            match lens.field_failure(lo, hi) {
                None => return Ok(lens),
                Some(at) => first_failure = first_failure.or(Some(at)),
            }
        }
        let at = first_failure.unwrap_or_default();
        Err(MathError::LensFolds { x: at.x, y: at.y })
    }

    /// The first grid point of the field `lo`..`hi` this lens does not undo.
    fn field_failure(&self, lo: Vector2<f64>, hi: Vector2<f64>) -> Option<Vector2<f64>> {
        let step = |a: f64, b: f64, i: usize| a + (b - a) * i as f64 / (FIELD_GRID - 1) as f64;
        for i in 0..FIELD_GRID {
            for j in 0..FIELD_GRID {
                let c = Vector2::new(step(lo.x, hi.x, i), step(lo.y, hi.y, j));
                let u = self.undistort(c);
                let n = u * self.inv_focal;
                let jac = self.jacobian(n);
                let folds = jac.determinant() <= 0.0 || n.dot(&(jac * n)) < 0.0;
                if folds || !((self.distort(u) - c).norm() <= FIELD_TOLERANCE_PX) {
                    return Some(c);
                }
            }
        }
        None
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
        assert!(matches!(l.fitted_to_field(-half, half), Err(MathError::LensFolds { .. })));
        // A mild lens needs one chord step over the built-in camera's image, two over a wider
        // one; a wide-angle lens more.
        let mild = lens([-0.1, 0.0, 0.002, -0.001]).fitted_to_field(-half, half).expect("fits");
        assert_eq!(mild.steps, 1);
        let wider = lens([-0.1, 0.0, 0.002, -0.001]).fitted_to_field(-half * 1.5, half * 1.5).expect("fits");
        assert_eq!(wider.steps, 2);
        let wide = lens([-0.4, 0.1, 0.0, 0.0]).fitted_to_field(-half, half).expect("fits");
        assert!(wide.steps > mild.steps, "{wide:?}");
        // Every pixel of a field off its centre is undone, not only the grid's.
        let (lo, hi) = (Vector2::new(-0.05 * F, -0.1 * F), Vector2::new(0.4 * F, 0.3 * F));
        let skewed = lens([-0.2, 0.05, 0.002, -0.001]).fitted_to_field(lo, hi).expect("fits");
        for i in 0..=50 {
            for j in 0..=50 {
                let c = lo + (hi - lo).component_mul(&Vector2::new(f64::from(i), f64::from(j))) / 50.0;
                let back = skewed.distort(skewed.undistort(c));
                assert!((back - c).norm() <= FIELD_TOLERANCE_PX, "{c}: {back}");
            }
        }
        // Where the map folds, the first-order guess, in pixels.
        let far = Vector2::new(0.6 * F, 0.0);
        let guess = l.undistort(far);
        assert!(guess.x.is_finite() && guess.norm() > 0.1 * far.norm(), "{guess}");
    }

    proptest! {
        #[test]
        fn undistort_inverts_distort_over_a_machine_cameras_field(
            k1 in -0.3f64..0.3, k2 in -0.1f64..0.1, p1 in -0.005f64..0.005, p2 in -0.005f64..0.005,
            x in -0.45f64..0.45, y in -0.45f64..0.45,
        ) {
            let l = lens([k1, k2, p1, p2]);
            let half = Vector2::new(0.35 * F, 0.35 * F);
            let Ok(l) = l.fitted_to_field(-half, half) else { return Ok(()) };
            let u = Vector2::new(x, y) * 0.3 * F / 0.45;
            let back = l.undistort(l.distort(u));
            prop_assert!((back - u).norm() <= FIELD_TOLERANCE_PX, "{u} -> {back}");
        }
    }
}
