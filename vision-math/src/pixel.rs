//! The pixel chain of SPEC §2: native pixels → machine-unit offset from the camera position.
//!
//! `O = C + K · R · (p − res/2 − PxCenterOffset)`
//!
//! * `p`: native pixels, origin top-left, +x right, +y **down**.
//! * `R`: the discrete axis remap ([`Remap`]): swap, then invert X, then invert Y.
//! * `K`: 2×2, machine units per pixel (inch or mm, whichever the calibration used).
//!
//! With a lens ([`PixelChain::with_lens`]) the centred pixel is undistorted before `R` and `K`:
//! `O = C + K · R · D⁻¹(p − res/2 − PxCenterOffset)` ([`crate::lens`]).
//!
//! [`PixelChain`] folds `K · R` into one matrix when it is built, so a conversion costs four
//! multiplications and six additions.

use nalgebra::{Matrix2, Point2, Vector2};

use crate::{Lens, MathError};

/// The discrete axis remap applied after the centre shift (SPEC §2 step 3).
///
/// Order: if `swap_xy` swap the components; then if `invert_x` negate x; then if `invert_y`
/// negate y. Afterwards +x means machine +X and +y means machine +Y.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Remap {
    /// Swap the pixel x and y components first.
    pub swap_xy: bool,
    /// Then negate x.
    pub invert_x: bool,
    /// Then negate y.
    pub invert_y: bool,
}

impl Remap {
    /// No swap, no inversion.
    pub const IDENTITY: Remap = Remap { swap_xy: false, invert_x: false, invert_y: false };

    /// All eight remaps (4 rotations × mirror), in a fixed order.
    #[must_use]
    pub fn all() -> [Remap; 8] {
        let mut out = [Remap::IDENTITY; 8];
        for (i, r) in out.iter_mut().enumerate() {
            *r = Remap { swap_xy: i & 4 != 0, invert_x: i & 2 != 0, invert_y: i & 1 != 0 };
        }
        out
    }

    /// Applies the remap to a centred pixel vector (pixels in, pixels out).
    #[must_use]
    pub fn apply(self, v: Vector2<f64>) -> Vector2<f64> {
        let (mut x, mut y) = if self.swap_xy { (v.y, v.x) } else { (v.x, v.y) };
        if self.invert_x {
            x = -x;
        }
        if self.invert_y {
            y = -y;
        }
        Vector2::new(x, y)
    }

    /// Undoes [`Remap::apply`] (pixels in, pixels out).
    #[must_use]
    pub fn unapply(self, v: Vector2<f64>) -> Vector2<f64> {
        let x = if self.invert_x { -v.x } else { v.x };
        let y = if self.invert_y { -v.y } else { v.y };
        if self.swap_xy {
            Vector2::new(y, x)
        } else {
            Vector2::new(x, y)
        }
    }

    /// The remap as a signed permutation matrix, so that `apply(v) == matrix() * v`.
    #[must_use]
    pub fn matrix(self) -> Matrix2<f64> {
        let sx = if self.invert_x { -1.0 } else { 1.0 };
        let sy = if self.invert_y { -1.0 } else { 1.0 };
        if self.swap_xy {
            Matrix2::new(0.0, sx, sy, 0.0)
        } else {
            Matrix2::new(sx, 0.0, 0.0, sy)
        }
    }

    /// The remap whose matrix is `m`, if `m` is a signed permutation matrix (entries −1, 0, 1).
    #[must_use]
    pub fn from_matrix(m: &Matrix2<f64>) -> Option<Remap> {
        Remap::all().into_iter().find(|r| r.matrix() == *m)
    }
}

/// Everything that turns native pixels into a machine-unit offset, validated and pre-folded.
///
/// Built with [`PixelChain::new`], which refuses a zero K ("not calibrated"), a singular K and a
/// bad resolution, so every method after construction is total.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelChain {
    k: Matrix2<f64>,
    remap: Remap,
    resolution: Vector2<f64>,
    center_offset: Vector2<f64>,
    /// Native pixel that maps to the optical axis: `res/2 + PxCenterOffset`.
    origin: Vector2<f64>,
    /// `K · R`.
    kr: Matrix2<f64>,
    /// `(K · R)⁻¹`.
    kr_inv: Matrix2<f64>,
    /// The lens distortion undone before `K · R`; `None`: a linear chain.
    lens: Option<Lens>,
}

/// [`Lens::undistort`] out of line: the linear chain's inlined path stays a branch and a
/// matrix product.
#[inline(never)]
fn undo(lens: &Lens, c: Vector2<f64>) -> Vector2<f64> {
    lens.undistort(c)
}

/// Relative determinant below which K counts as singular (`|det K| < 1e-12 · ‖K‖²`).
const SINGULAR_K: f64 = 1e-12;

impl PixelChain {
    /// Builds the chain.
    ///
    /// * `k`: K, machine units per pixel (row-major `[[K11, K12], [K21, K22]]`).
    /// * `remap`: the axis remap.
    /// * `resolution`: `(ResX, ResY)` in pixels.
    /// * `center_offset`: `(PxCenterOffsetX, PxCenterOffsetY)` in pixels.
    ///
    /// # Errors
    /// [`MathError::NotCalibrated`] when K is all zero, [`MathError::SingularK`] when it cannot be
    /// inverted, [`MathError::NonFinite`] for NaN/∞ and [`MathError::BadResolution`].
    pub fn new(
        k: Matrix2<f64>,
        remap: Remap,
        resolution: Vector2<f64>,
        center_offset: Vector2<f64>,
    ) -> Result<Self, MathError> {
        if !k.iter().all(|v| v.is_finite()) {
            return Err(MathError::NonFinite { what: "K" });
        }
        if !center_offset.iter().all(|v| v.is_finite()) {
            return Err(MathError::NonFinite { what: "pixel centre offset" });
        }
        if !(resolution.x > 0.0 && resolution.y > 0.0 && resolution.x.is_finite() && resolution.y.is_finite()) {
            return Err(MathError::BadResolution { x: resolution.x, y: resolution.y });
        }
        if k.iter().all(|v| *v == 0.0) {
            return Err(MathError::NotCalibrated);
        }
        let norm2 = k.norm_squared();
        let det = k.determinant();
        if det.abs() < SINGULAR_K * norm2 {
            return Err(MathError::SingularK);
        }
        let kr = k * remap.matrix();
        let kr_inv = kr.try_inverse().ok_or(MathError::SingularK)?;
        let origin = resolution * 0.5 + center_offset;
        Ok(PixelChain { k, remap, resolution, center_offset, origin, kr, kr_inv, lens: None })
    }

    /// The chain with `lens` undone before K (kept even when it moves no pixel: its
    /// coefficients' uncertainty still reaches [`PixelChain::lens_sensitivity`]).
    ///
    /// # Errors
    /// [`MathError::LensFolds`] when the lens cannot be undone over the image (with 10 %
    /// margin): it folds there.
    pub fn with_lens(self, lens: Lens) -> Result<Self, MathError> {
        let lens = lens.fitted_to_field(-self.origin, self.resolution - self.origin)?;
        Ok(PixelChain { lens: Some(lens), ..self })
    }

    /// The lens undone before K, if any.
    #[must_use]
    pub fn lens(&self) -> Option<&Lens> {
        self.lens.as_ref()
    }

    /// K, machine units per pixel.
    #[must_use]
    pub fn k(&self) -> Matrix2<f64> {
        self.k
    }

    /// The axis remap.
    #[must_use]
    pub fn remap(&self) -> Remap {
        self.remap
    }

    /// `(ResX, ResY)`, pixels.
    #[must_use]
    pub fn resolution(&self) -> Vector2<f64> {
        self.resolution
    }

    /// `(PxCenterOffsetX, PxCenterOffsetY)`, pixels.
    #[must_use]
    pub fn center_offset(&self) -> Vector2<f64> {
        self.center_offset
    }

    /// Step 2: native pixel → pixel offset from the optical centre (pixels, native axes).
    #[must_use]
    pub fn centred(&self, native: Point2<f64>) -> Vector2<f64> {
        native.coords - self.origin
    }

    /// Step 2 with the lens undone: native pixel → the ideal (undistorted) offset from the
    /// optical centre, pixels, native axes; [`PixelChain::centred`] without a lens.
    #[inline]
    #[must_use]
    pub fn undistorted(&self, native: Point2<f64>) -> Vector2<f64> {
        let c = native.coords - self.origin;
        match &self.lens {
            Some(lens) => undo(lens, c),
            None => c,
        }
    }

    /// Steps 2–4: native pixel → offset `d = K·R·D⁻¹(c)` from the camera position, machine
    /// units.
    #[inline]
    #[must_use]
    pub fn delta(&self, native: Point2<f64>) -> Vector2<f64> {
        let c = native.coords - self.origin;
        match &self.lens {
            None => self.kr * c,
            Some(lens) => self.kr * undo(lens, c),
        }
    }

    /// Step 5: the observed point `O = C + d`, with `commanded` the camera position `C` and the
    /// result in the same machine units and frame as `C`.
    #[inline]
    #[must_use]
    pub fn observed(&self, commanded: Point2<f64>, native: Point2<f64>) -> Point2<f64> {
        commanded + self.delta(native)
    }

    /// The inverse of [`PixelChain::delta`]: a machine-unit offset from the camera position →
    /// the native pixel where a mark at that offset appears.
    #[inline]
    #[must_use]
    pub fn native_pixels(&self, delta: Vector2<f64>) -> Point2<f64> {
        let ideal = self.kr_inv * delta;
        let c = match &self.lens {
            Some(lens) => lens.distort(ideal),
            None => ideal,
        };
        Point2::from(c + self.origin)
    }

    /// How [`PixelChain::delta`] at `native` moves per unit of each lens coefficient
    /// `[k1, k2, p1, p2]`, machine units (zero without a lens): what an uncertain lens costs a
    /// reading there.
    #[must_use]
    pub fn lens_sensitivity(&self, native: Point2<f64>) -> [Vector2<f64>; 4] {
        match &self.lens {
            Some(lens) => lens.sensitivity(native.coords - self.origin).map(|s| self.kr * s),
            None => [Vector2::zeros(); 4],
        }
    }

    /// Mark width and height in machine units from its size in pixels:
    /// `(width_px · ‖K column 1‖, height_px · ‖K column 2‖)`.
    #[must_use]
    pub fn mark_size(&self, width_px: f64, height_px: f64) -> (f64, f64) {
        (width_px * self.k.column(0).norm(), height_px * self.k.column(1).norm())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use proptest::prelude::*;

    fn chain(k: Matrix2<f64>, remap: Remap) -> PixelChain {
        PixelChain::new(k, remap, Vector2::new(1776.0, 1776.0), Vector2::zeros()).expect("valid chain")
    }

    #[test]
    fn remap_matrix_matches_apply_for_all_eight() {
        let v = Vector2::new(3.0, -7.0);
        let all = Remap::all();
        for r in all {
            assert_eq!(r.apply(v), r.matrix() * v, "{r:?}");
            assert_eq!(r.unapply(r.apply(v)), v, "{r:?}");
            assert_eq!(Remap::from_matrix(&r.matrix()), Some(r));
        }
        // The eight are distinct.
        for (i, a) in all.iter().enumerate() {
            for b in &all[i + 1..] {
                assert_ne!(a.matrix(), b.matrix());
            }
        }
    }

    #[test]
    fn swap_happens_before_inversion() {
        let r = Remap { swap_xy: true, invert_x: true, invert_y: false };
        // swap (1, 2) -> (2, 1), then negate x -> (-2, 1)
        assert_eq!(r.apply(Vector2::new(1.0, 2.0)), Vector2::new(-2.0, 1.0));
    }

    #[test]
    fn seed_numbers_centre_and_scale() {
        // Manual: 0.00203 in/px, 1776 px square image, camera looking down with image +y down.
        let k = Matrix2::new(0.00203, 0.0, 0.0, 0.00203);
        let c = chain(k, Remap { swap_xy: false, invert_x: false, invert_y: true });
        // The centre pixel maps to the camera position.
        let o = c.observed(Point2::new(1.0, 2.0), Point2::new(888.0, 888.0));
        assert_eq!(o, Point2::new(1.0, 2.0));
        // 100 px right and 100 px down is +0.203 in X and -0.203 in Y.
        let d = c.delta(Point2::new(988.0, 988.0));
        assert_relative_eq!(d.x, 0.203, epsilon = 1e-15);
        assert_relative_eq!(d.y, -0.203, epsilon = 1e-15);
        // The field of view is 1776 * 0.00203 = 3.605 in.
        let edge = c.delta(Point2::new(1776.0, 888.0));
        assert_relative_eq!(2.0 * edge.x, 3.60528, epsilon = 1e-12);
        // A 0.5 in mark is about 246 px wide.
        let (w, h) = c.mark_size(246.305, 246.305);
        assert_relative_eq!(w, 0.5, epsilon = 1e-5);
        assert_relative_eq!(h, 0.5, epsilon = 1e-5);
    }

    #[test]
    fn centre_offset_shifts_the_optical_axis() {
        let k = Matrix2::new(0.01, 0.0, 0.0, 0.01);
        let c =
            PixelChain::new(k, Remap::IDENTITY, Vector2::new(640.0, 480.0), Vector2::new(5.0, -3.0)).expect("valid");
        assert_eq!(c.delta(Point2::new(325.0, 237.0)), Vector2::zeros());
        assert_eq!(c.centred(Point2::new(326.0, 237.0)), Vector2::new(1.0, 0.0));
    }

    #[test]
    fn refuses_zero_singular_nonfinite_k_and_bad_resolution() {
        let res = Vector2::new(1776.0, 1776.0);
        let z = Vector2::zeros();
        assert_eq!(PixelChain::new(Matrix2::zeros(), Remap::IDENTITY, res, z), Err(MathError::NotCalibrated));
        assert_eq!(
            PixelChain::new(Matrix2::new(1.0, 2.0, 2.0, 4.0), Remap::IDENTITY, res, z),
            Err(MathError::SingularK)
        );
        assert_eq!(
            PixelChain::new(Matrix2::new(f64::NAN, 0.0, 0.0, 1.0), Remap::IDENTITY, res, z),
            Err(MathError::NonFinite { what: "K" })
        );
        assert!(matches!(
            PixelChain::new(Matrix2::identity(), Remap::IDENTITY, Vector2::new(0.0, 10.0), z),
            Err(MathError::BadResolution { .. })
        ));
        assert!(matches!(
            PixelChain::new(Matrix2::identity(), Remap::IDENTITY, res, Vector2::new(f64::INFINITY, 0.0)),
            Err(MathError::NonFinite { .. })
        ));
    }

    #[test]
    fn a_lens_is_undone_before_k_and_redone_by_the_inverse() {
        let k = Matrix2::new(0.002, 0.0, 0.0, -0.002);
        let linear =
            PixelChain::new(k, Remap::IDENTITY, Vector2::new(1776.0, 1776.0), Vector2::new(3.0, -2.0)).expect("valid");
        let lens = Lens::new([-0.1, 0.0, 0.002, -0.001], 3000.0).expect("lens");
        let chain = linear.with_lens(lens).expect("does not fold");
        assert_eq!(chain.lens().map(Lens::coefficients), Some(lens.coefficients()));
        let p = Point2::new(1500.0, 200.0);
        let fitted = chain.lens().expect("a lens");
        let ideal = fitted.undistort(p.coords - Vector2::new(891.0, 886.0));
        let exact = lens.undistort(p.coords - Vector2::new(891.0, 886.0));
        assert!((ideal - exact).norm() <= crate::lens::FIELD_TOLERANCE_PX, "as many steps as needed");
        assert_eq!(chain.undistorted(p), ideal);
        assert_eq!(chain.delta(p), k * ideal);
        assert!((chain.native_pixels(chain.delta(p)) - p).norm() <= crate::lens::FIELD_TOLERANCE_PX);
        // The optical centre does not move; a linear chain is unchanged.
        assert_eq!(chain.delta(Point2::new(891.0, 886.0)), Vector2::zeros());
        assert_eq!(linear.undistorted(p), linear.centred(p));
        assert_eq!(linear.lens_sensitivity(p), [Vector2::zeros(); 4]);
        let s = chain.lens_sensitivity(p);
        assert!((s[0] - k * fitted.sensitivity(p.coords - Vector2::new(891.0, 886.0))[0]).norm() < 1e-15);
        // A lens that moves nothing moves nothing, but says what its coefficients would; one
        // that folds is refused.
        let none = Lens::new([0.0; 4], 3000.0).expect("lens");
        let flat = linear.with_lens(none).expect("identity");
        assert_eq!(flat.delta(p), linear.delta(p));
        assert!(flat.lens_sensitivity(p)[0].norm() > 1e-3, "{:?}", flat.lens_sensitivity(p));
        let folding = Lens::new([-8.0, 0.0, 0.0, 0.0], 3000.0).expect("lens");
        assert!(matches!(linear.with_lens(folding), Err(MathError::LensFolds { .. })));
        // The whole image is checked about its own centre: a k1 of −0.1 on f = 2000 px is undone
        // over a centred 1776 px image, not out to the far corner of one centred 600 px off.
        let barrel = Lens::new([-0.1, 0.0, 0.0, 0.0], 2000.0).expect("lens");
        let at = |off: f64| PixelChain::new(k, Remap::IDENTITY, Vector2::new(1776.0, 1776.0), Vector2::new(off, off));
        assert!(at(0.0).expect("valid").with_lens(barrel).is_ok());
        assert!(matches!(at(600.0).expect("valid").with_lens(barrel), Err(MathError::LensFolds { .. })));
    }

    fn well_conditioned_k() -> impl Strategy<Value = Matrix2<f64>> {
        // Scale 1e-4..1e-1 units/px, any rotation, up to 5 % anisotropy and 2 % skew.
        (-4.0f64..-1.0, -std::f64::consts::PI..std::f64::consts::PI, 0.95f64..1.05, -0.02f64..0.02).prop_map(
            |(log_s, th, aniso, skew)| {
                let s = 10f64.powf(log_s);
                let (sn, cs) = th.sin_cos();
                let rot = Matrix2::new(cs, -sn, sn, cs);
                rot * Matrix2::new(s, s * skew, 0.0, s * aniso)
            },
        )
    }

    proptest! {
        #[test]
        fn units_to_pixels_to_units_is_identity(
            k in well_conditioned_k(),
            remap_idx in 0usize..8,
            res in (16.0f64..5000.0, 16.0f64..5000.0),
            off in (-50.0f64..50.0, -50.0f64..50.0),
            d in (-1.0f64..1.0, -1.0f64..1.0),
        ) {
            let remap = Remap::all()[remap_idx];
            let chain = PixelChain::new(k, remap, Vector2::new(res.0, res.1), Vector2::new(off.0, off.1)).expect("valid");
            // Offsets up to a half field of view.
            let half_fov = k * Vector2::new(res.0, res.1) * 0.5;
            let delta = Vector2::new(d.0 * half_fov.x.abs().max(1e-6), d.1 * half_fov.y.abs().max(1e-6));
            let px = chain.native_pixels(delta);
            let back = chain.delta(px);
            let scale = delta.norm().max(k.norm());
            prop_assert!((back - delta).norm() <= 1e-12 * scale, "{back:?} vs {delta:?}");
            // And pixels -> units -> pixels.
            let p = Point2::new(d.0 * res.0, d.1 * res.1);
            let p2 = chain.native_pixels(chain.delta(p));
            prop_assert!((p2 - p).norm() <= 1e-12 * (res.0 + res.1), "{p2:?} vs {p:?}");
            // delta agrees with the unfolded chain K · R · (p − res/2 − off).
            let direct = k * remap.apply(p.coords - Vector2::new(res.0, res.1) * 0.5 - Vector2::new(off.0, off.1));
            prop_assert!((direct - chain.delta(p)).norm() <= 1e-12 * direct.norm().max(1e-12));
        }
    }
}
