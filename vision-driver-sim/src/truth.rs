//! What a perfect calibration would write, and how far a real one is from it.

use vision_core::calibrate::detect_remap;
use vision_core::{Params, VisionError};
use vision_math::{LengthUnit, Matrix2, Remap, Vector2};

use crate::sim::Sim;

/// How far a calibration is from the truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibrationError {
    /// `‖K − K_true‖ / ‖K_true‖` (Frobenius norms), dimensionless.
    pub k_relative: f64,
    /// Distance between the camera tool's X/Y tool-table offset and the true one, in `unit`.
    pub offset: f64,
    /// The unit of `offset`.
    pub unit: LengthUnit,
    /// True when the remap flags are the ones the axis detect should find.
    pub remap_matches: bool,
}

/// The optical centre's 1σ a perfect calibration states, pixels: a hundredth of a pixel (0 would
/// read as "never measured").
pub const PERFECT_CENTRE_SIGMA_PX: f64 = 0.01;

impl Sim {
    /// The remap the M283 axis detect finds for this camera (the signed permutation closest to
    /// the true image orientation).
    #[must_use]
    pub fn true_remap(&self) -> Remap {
        let o = self.optics();
        let inv = o.kr().try_inverse().unwrap_or_else(Matrix2::identity);
        // Pixel motion of a fixed mark when the camera moves +X, then +Y (100 px each).
        let along = |v: Vector2<f64>| {
            let p = inv * -v;
            p * (100.0 / p.norm())
        };
        detect_remap(along(Vector2::x()), along(Vector2::y())).unwrap_or_default()
    }

    /// The K a perfect calibration writes for `remap`, in `unit` per pixel: `K = (K·R)·Rᵀ`.
    #[must_use]
    pub fn true_k(&self, remap: Remap, unit: LengthUnit) -> Matrix2<f64> {
        self.optics().kr() * remap.matrix().transpose() * self.unit().factor_to(unit)
    }

    /// The camera tool's true X/Y tool-table offset in `unit`: the one that puts the reference
    /// pixel `res/2 + px_center_offset` (pixels) over the commanded point.
    #[must_use]
    pub fn true_camera_offset(&self, px_center_offset: Vector2<f64>, unit: LengthUnit) -> Vector2<f64> {
        let st = self.lock();
        let v = Vector2::from(st.world.camera.offset) + st.optics().kr() * (px_center_offset - st.optics().bias());
        v * st.world.length_unit().factor_to(unit)
    }

    /// The camera tool's X/Y table offset a perfect calibration writes (`unit`): the optical
    /// axis's, which [`Sim::calibrated_params`]' optical centre refers to; the simulated
    /// machine's tool table holds it unless the world sets `camera_table_offset`.
    #[must_use]
    pub fn calibrated_table_offset(&self, unit: LengthUnit) -> Vector2<f64> {
        let bias = self.lock().optics().bias();
        self.true_camera_offset(bias, unit)
    }

    /// `base` with Vision enabled, driver `Sim`, the camera tool number, and K, the remap flags,
    /// `Cal_Units` (the world unit), the optical centre and the lens as a perfect calibration
    /// would leave them.
    ///
    /// Decision: perfect includes the optical centre (`VisionPxCenterOffsetX/Y` = the camera's
    /// bias, 1σ [`PERFECT_CENTRE_SIGMA_PX`]), which the sheet walk's lift measures: a
    /// calibration that took the centre at the image centre is exact only at its own height,
    /// and at another every capture shifts by the height change × that error × K.
    ///
    /// # Errors
    /// Only if `base` holds a value the setters refuse (they do not for valid parameters).
    pub fn calibrated_params(&self, base: &Params) -> Result<Params, VisionError> {
        let mut p = base.clone();
        let unit = self.unit();
        let remap = self.true_remap();
        p.set("VisionEnabled", true)?;
        p.set("VisionDriver", "Sim")?;
        p.set("VisionCameraToolNumber", i64::from(self.world().machine.camera_tool))?;
        p.set("VisionCal_Units", unit.short_name())?;
        p.set_remap(remap);
        p.set_cal_k(self.true_k(remap, unit))?;
        let bias = self.lock().optics().bias();
        p.calibration = p.calibration.with_centre(bias, PERFECT_CENTRE_SIGMA_PX)?;
        // The world's lens as the profile holds one: k1, k2, p1, p2 on the focal length the
        // simulator normalises by (its k3, and a non-square pixel's second focal length, have
        // no place in the profile's model), with no uncertainty.
        let camera = &self.world().camera;
        if let Some([k1, k2, p1, p2, _]) = camera.distortion {
            let reference = camera.reference_working_distance.unwrap_or(camera.working_distance);
            let lens = vision_math::Lens::new([k1, k2, p1, p2], reference / camera.units_per_pixel)?;
            p.calibration = p.calibration.with_lens(Some((lens, [0.0; 4])))?;
        }
        Ok(p)
    }

    /// Compares `params` (K in `Cal_Units`, remap, PxCenterOffset) and the camera tool's table
    /// offset `table_offset` (in `unit`) with the truth.
    #[must_use]
    pub fn calibration_error(&self, params: &Params, table_offset: Vector2<f64>, unit: LengthUnit) -> CalibrationError {
        let truth = self.true_k(params.remap(), params.cal_units());
        let k_relative = (params.cal_k() - truth).norm() / truth.norm();
        let px = Vector2::new(params.px_center_offset_x(), params.px_center_offset_y());
        let offset = (table_offset - self.true_camera_offset(px, unit)).norm();
        CalibrationError { k_relative, offset, unit, remap_matches: params.remap() == self.true_remap() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::World;
    use approx::assert_relative_eq;
    use vision_math::PixelChain;

    #[test]
    fn the_true_k_makes_the_core_chain_invert_the_optics_for_all_eight_orientations() {
        for rotation in [0.0, 90.0, 180.0, 270.0, 2.5, 92.9, -177.0] {
            for mirror in [false, true] {
                let mut w = World::default_world();
                w.camera.rotation_deg = rotation;
                w.camera.mirror = mirror;
                w.camera.pixel_aspect = 1.003;
                let sim = Sim::new(w).expect("sim");
                let remap = sim.true_remap();
                let k = sim.true_k(remap, LengthUnit::Millimetre);
                // The remapped K is nearly diagonal with positive entries: the detect is right.
                assert!(k[(0, 0)] > 0.0 && k[(1, 1)] > 0.0, "{rotation} {mirror}: {k}");
                assert!(k[(0, 1)].abs() < 0.06 * k[(0, 0)], "{rotation} {mirror}: {k}");
                let bias = sim.optics().bias();
                let chain = PixelChain::new(k, remap, sim.optics().resolution(), bias).expect("chain");
                let v = Vector2::new(0.4, -0.25);
                let seen = chain.delta(sim.optics().pixel(v));
                assert_relative_eq!(seen, v * 25.4, epsilon = 1e-9);
            }
        }
    }

    #[test]
    fn calibrated_params_have_no_error() {
        let sim = Sim::new(World::default_world()).expect("sim");
        let p = sim.calibrated_params(&Params::default()).expect("params");
        assert!(p.enabled());
        // A perfect calibration knows the optical centre, the bias (3, −2) px, and refers the
        // camera offset to it: the optical axis's.
        assert_eq!(p.calibration.center_offset(), Vector2::new(3.0, -2.0));
        assert_eq!(p.calibration.center_sigma(), Some(PERFECT_CENTRE_SIGMA_PX));
        let truth = sim.calibrated_table_offset(LengthUnit::Inch);
        assert!((truth - Vector2::new(-3.25, 1.75)).norm() < 1e-12, "{truth}");
        assert!((sim.true_camera_offset(Vector2::zeros(), LengthUnit::Inch) - truth).norm() > 0.004);
        let e = sim.calibration_error(&p, truth, LengthUnit::Inch);
        assert!(e.k_relative < 1e-15 && e.offset < 1e-15 && e.remap_matches, "{e:?}");
        assert_eq!(p.calibration.lens(), None, "the built-in world has no lens");
        let mut w = World::default_world();
        w.camera.distortion = Some([-0.1, 0.01, 0.002, -0.001, 0.0]);
        let p = Sim::new(w).expect("sim").calibrated_params(&Params::default()).expect("params");
        let lens = p.calibration.lens().expect("the world's lens");
        assert!(lens.coefficients().iter().zip([-0.1, 0.01, 0.002, -0.001]).all(|(a, b)| (a - b).abs() < 1e-15));
        assert!((lens.focal_px() - 6.0 / 0.00203).abs() < 1e-9);
        let mm = sim.calibration_error(&p, truth * 25.4, LengthUnit::Millimetre);
        assert!(mm.offset < 1e-12, "{mm:?}");
    }
}
