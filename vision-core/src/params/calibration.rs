//! [`Calibration`]: K, the camera axis flags, `Cal_Units`, `Cal_Date`, the pixel centre offset,
//! and the limits a K must keep.

use vision_math::{LengthUnit, Matrix2, Remap, Vector2};

use super::checks::{
    Check, DRIVER_RECORD, FINITE, LENS_RADIAL, LENS_TANGENTIAL, NOISE_PX_WIDE, NON_NEGATIVE, PIXEL_OFFSET,
    RESOLUTION_RECORD, SHORT_TEXT, TOOL,
};
use super::ParamValue;
use crate::error::VisionError;

profile_part! {
    /// The calibration: K, the camera axis flags, `Cal_Units`, `Cal_Date` and the pixel centre
    /// offset. M283 replaces it as a whole (see [`crate::calibrate`]).
    ///
    /// Decision: `VisionPxCenterOffsetX/Y` belong here, as the manual lists them: they describe
    /// the camera's optics like K does, and are persisted with it. The sheet walk with
    /// `VisionCalibrationLift` > 0 measures them (the pixel that sees the same table point at
    /// two heights) with their 1σ (`VisionPxCenterSigmaPx`); a calibration that does not measure
    /// them keeps both: the walk solves the camera offset at whatever reference pixel the
    /// profile holds, so a centre measured before stays as good as it was.
    Calibration in calibration {
        /// `VisionCameraSwapXY`: swap the centred pixel x and y (set by M283's axis detect).
        (Calibration, "", "M283") camera_swap_xy: bool => bool = false, "VisionCameraSwapXY", Check::ANY;
        /// `VisionCameraInvertX`: negate pixel x after the swap (set by M283).
        (Calibration, "", "M283") camera_invert_x: bool => bool = false, "VisionCameraInvertX", Check::ANY;
        /// `VisionCameraInvertY`: negate pixel y after the swap (set by M283).
        (Calibration, "", "M283") camera_invert_y: bool => bool = false, "VisionCameraInvertY", Check::ANY;
        /// `VisionCal_K11`: K row 1 column 1, `Cal_Units` per pixel.
        (Calibration, "Cal_Units/px", "M283") cal_k11: f64 => f64 = 0.0, "VisionCal_K11", FINITE;
        /// `VisionCal_K12`: K row 1 column 2, `Cal_Units` per pixel.
        (Calibration, "Cal_Units/px", "M283") cal_k12: f64 => f64 = 0.0, "VisionCal_K12", FINITE;
        /// `VisionCal_K21`: K row 2 column 1, `Cal_Units` per pixel.
        (Calibration, "Cal_Units/px", "M283") cal_k21: f64 => f64 = 0.0, "VisionCal_K21", FINITE;
        /// `VisionCal_K22`: K row 2 column 2, `Cal_Units` per pixel.
        (Calibration, "Cal_Units/px", "M283") cal_k22: f64 => f64 = 0.0, "VisionCal_K22", FINITE;
        /// `VisionCal_Date`: ISO local time of the last successful calibration (empty = never).
        (Calibration, "", "M283") cal_date: String => &str = String::new(), "VisionCal_Date", SHORT_TEXT;
        /// `VisionCal_Units`: the unit K is calibrated in (`in` or `mm`).
        (Calibration, "", "M283") cal_units: LengthUnit => LengthUnit = LengthUnit::Inch, "VisionCal_Units", Check::ANY;
        /// `VisionPxCenterOffsetX`: optical-centre bias subtracted after the image-centre shift,
        /// pixels.
        (Calibration, "px", "M283 C/P with VisionCalibrationLift > 0, or the operator") px_center_offset_x: f64 => f64 = 0.0, "VisionPxCenterOffsetX", PIXEL_OFFSET;
        /// `VisionPxCenterOffsetY`: same, Y, pixels.
        (Calibration, "px", "M283 C/P with VisionCalibrationLift > 0, or the operator") px_center_offset_y: f64 => f64 = 0.0, "VisionPxCenterOffsetY", PIXEL_OFFSET;
        /// `VisionPxCenterSigmaPx`: the 1σ per pixel axis of the optical centre M283's lift
        /// measured (the larger axis's), pixels; 0 = not measured (the offset was set by hand, or
        /// never measured), and M282 assumes `VisionCenterUncertaintyPx` instead.
        (Calibration, "px", "M283 C/P with VisionCalibrationLift > 0, or the operator") px_center_sigma_px: f64 => f64 = 0.0, "VisionPxCenterSigmaPx", NOISE_PX_WIDE;
        /// `VisionLensK1`: the lens's first radial distortion coefficient (OpenCV's `k1`, on
        /// coordinates normalised by `VisionLensFocalPx`; − barrel, + pincushion). The pixel chain
        /// undoes the lens about the optical centre before K.
        (Calibration, "", "M283 C/P") lens_k1: f64 => f64 = 0.0, "VisionLensK1", LENS_RADIAL;
        /// `VisionLensK2`: the second radial coefficient (OpenCV's `k2`).
        (Calibration, "", "M283 C/P") lens_k2: f64 => f64 = 0.0, "VisionLensK2", LENS_RADIAL;
        /// `VisionLensP1`: the first tangential (decentring) coefficient (OpenCV's `p1`).
        (Calibration, "", "M283 C/P") lens_p1: f64 => f64 = 0.0, "VisionLensP1", LENS_TANGENTIAL;
        /// `VisionLensP2`: the second tangential coefficient (OpenCV's `p2`).
        (Calibration, "", "M283 C/P") lens_p2: f64 => f64 = 0.0, "VisionLensP2", LENS_TANGENTIAL;
        /// `VisionLensFocalPx`: the focal length the lens coefficients are normalised by, pixels
        /// (working distance / length per pixel); 0 = no lens model (a linear chain).
        (Calibration, "px", "M283 C/P") lens_focal_px: f64 => f64 = 0.0, "VisionLensFocalPx", NON_NEGATIVE;
        /// `VisionLensK1Sigma`: the 1σ M283 measured `VisionLensK1` to (dimensionless); M282
        /// widens its prediction by what it moves each capture. Likewise the three below.
        (Calibration, "", "M283 C/P") lens_k1_sigma: f64 => f64 = 0.0, "VisionLensK1Sigma", NON_NEGATIVE;
        /// `VisionLensK2Sigma`: the 1σ of `VisionLensK2`.
        (Calibration, "", "M283 C/P") lens_k2_sigma: f64 => f64 = 0.0, "VisionLensK2Sigma", NON_NEGATIVE;
        /// `VisionLensP1Sigma`: the 1σ of `VisionLensP1`.
        (Calibration, "", "M283 C/P") lens_p1_sigma: f64 => f64 = 0.0, "VisionLensP1Sigma", NON_NEGATIVE;
        /// `VisionLensP2Sigma`: the 1σ of `VisionLensP2`.
        (Calibration, "", "M283 C/P") lens_p2_sigma: f64 => f64 = 0.0, "VisionLensP2Sigma", NON_NEGATIVE;
        /// `VisionCal_ResX`: the image width M283 calibrated at, pixels (0 = not recorded: a
        /// calibration made before the record existed). M280–M282 refuse while
        /// `VisionCameraResX` or the camera's frames differ.
        (Calibration, "px", "M283") cal_res_x: i64 => i64 = 0, "VisionCal_ResX", RESOLUTION_RECORD;
        /// `VisionCal_ResY`: the image height M283 calibrated at, pixels (0 = not recorded).
        (Calibration, "px", "M283") cal_res_y: i64 => i64 = 0, "VisionCal_ResY", RESOLUTION_RECORD;
        /// `VisionCal_Driver`: the camera driver M283 calibrated with, as the driver names itself
        /// (`Keyence`, `Camera`, `Sim`; empty = not recorded). M280–M282 refuse under another.
        (Calibration, "", "M283") cal_driver: String => &str = String::new(), "VisionCal_Driver", DRIVER_RECORD;
        /// `VisionCal_Mark`: the mark the camera searched for when M283 calibrated (its
        /// driver's words, e.g. `dot, dark on light`; empty = not recorded or a camera that runs
        /// its own job). M281 warns while the camera searches for another.
        (Calibration, "", "M283") cal_mark: String => &str = String::new(), "VisionCal_Mark", SHORT_TEXT;
        /// `VisionCal_ToolNumber`: the camera tool whose X/Y offset the sheet walk (M283 C/P)
        /// wrote (0 = none recorded: M283 Q writes no offset).
        (Calibration, "", "M283 (0 after M283 Q)") cal_tool_number: i64 => i64 = 0, "VisionCal_ToolNumber", TOOL;
        /// `VisionCal_ToolOffsetX`: the X offset the sheet walk wrote to that tool, `Cal_Units`.
        /// M280–M282 refuse while the tool table holds another: every mark would be read off by
        /// the difference.
        (Calibration, "Cal_Units", "M283 C/P") cal_tool_offset_x: f64 => f64 = 0.0, "VisionCal_ToolOffsetX", FINITE;
        /// `VisionCal_ToolOffsetY`: the Y offset the sheet walk wrote, `Cal_Units`.
        (Calibration, "Cal_Units", "M283 C/P") cal_tool_offset_y: f64 => f64 = 0.0, "VisionCal_ToolOffsetY", FINITE;
    }
}

/// The smallest pixel footprint a K may give, inches per pixel (2.5 nm: beyond any microscope
/// objective a machine camera carries).
pub const K_SCALE_MIN_IN: f64 = 1e-7;
/// The largest pixel footprint a K may give, inches per pixel (a 1776-pixel image would see
/// 178 in, more than any machine table).
pub const K_SCALE_MAX_IN: f64 = 0.1;
/// The largest ratio between K's two axis scales (square-ish pixels and no more than a steep
/// viewing angle; a larger ratio is a nearly singular K).
pub const K_MAX_ANISOTROPY: f64 = 10.0;

impl Calibration {
    /// K as a matrix `[[K11, K12], [K21, K22]]`, `Cal_Units` per pixel.
    #[must_use]
    pub fn cal_k(&self) -> Matrix2<f64> {
        Matrix2::new(self.cal_k11, self.cal_k12, self.cal_k21, self.cal_k22)
    }

    /// Writes all four K entries at once (`Cal_Units` per pixel); nothing changes unless all
    /// four are finite.
    ///
    /// # Errors
    /// [`VisionError::InvalidParam`] for a non-finite entry.
    pub fn set_cal_k(&mut self, k: Matrix2<f64>) -> Result<(), VisionError> {
        if let Some(bad) = k.iter().find(|v| !v.is_finite()) {
            return Err(VisionError::InvalidParam {
                name: "VisionCal_K11..K22".into(),
                value: bad.to_string(),
                reason: "must be finite numbers".into(),
            });
        }
        self.cal_k11 = k[(0, 0)];
        self.cal_k12 = k[(0, 1)];
        self.cal_k21 = k[(1, 0)];
        self.cal_k22 = k[(1, 1)];
        Ok(())
    }

    /// Checks K as a whole, as a profile load does: all zero ("not calibrated") or a pixel
    /// footprint `√|det K|` of [`K_SCALE_MIN_IN`]..[`K_SCALE_MAX_IN`] inches per pixel with its
    /// two axes within [`K_MAX_ANISOTROPY`]× of each other.
    ///
    /// # Errors
    /// [`VisionError::InvalidParam`] naming `VisionCal_K11..K22` and what is wrong.
    pub fn check_k(&self) -> Result<(), VisionError> {
        let k = self.cal_k();
        if k.iter().all(|v| *v == 0.0) {
            return Ok(());
        }
        let bad = |reason: String| VisionError::InvalidParam {
            name: "VisionCal_K11..K22".into(),
            value: format!("[[{:e}, {:e}], [{:e}, {:e}]]", k[(0, 0)], k[(0, 1)], k[(1, 0)], k[(1, 1)]),
            reason,
        };
        let in_per_unit = self.cal_units.factor_to(LengthUnit::Inch);
        // Singular values of K, in inches per pixel, by the closed form for 2×2 matrices.
        // Normalised first so 1e300 entries do not overflow.
        let k_in = k.map(|v| v * in_per_unit);
        let m = k_in.amax();
        let sv = (k_in / m).singular_values() * m;
        let (big, small) = (sv.max(), sv.min());
        if !(big.is_finite() && small > 0.0 && big / small <= K_MAX_ANISOTROPY) {
            return Err(bad(format!(
                "is singular or nearly so (the axes' scales differ by more than {K_MAX_ANISOTROPY}×) — \
                 recalibrate with M283, or set all four to 0 for \"not calibrated\""
            )));
        }
        let scale = big.sqrt() * small.sqrt();
        if !(K_SCALE_MIN_IN..=K_SCALE_MAX_IN).contains(&scale) {
            return Err(bad(format!(
                "gives {scale:.3e} in per pixel, outside the physical {K_SCALE_MIN_IN:e}..{K_SCALE_MAX_IN} in per \
                 pixel (VisionCal_Units is {}) — recalibrate with M283, or set all four to 0",
                self.cal_units.short_name()
            )));
        }
        Ok(())
    }

    /// The axis remap from the three `VisionCamera*` flags.
    #[must_use]
    pub fn remap(&self) -> Remap {
        Remap { swap_xy: self.camera_swap_xy, invert_x: self.camera_invert_x, invert_y: self.camera_invert_y }
    }

    /// Writes the three remap flags at once.
    pub fn set_remap(&mut self, r: Remap) {
        self.camera_swap_xy = r.swap_xy;
        self.camera_invert_x = r.invert_x;
        self.camera_invert_y = r.invert_y;
    }

    /// The pixel centre offset, pixels.
    #[must_use]
    pub fn center_offset(&self) -> Vector2<f64> {
        Vector2::new(self.px_center_offset_x, self.px_center_offset_y)
    }

    /// The measured optical centre's 1σ per pixel axis, pixels, or `None` when it was not
    /// measured (`VisionPxCenterSigmaPx` = 0).
    #[must_use]
    pub fn center_sigma(&self) -> Option<f64> {
        (self.px_center_sigma_px > 0.0).then_some(self.px_center_sigma_px)
    }

    /// This calibration with the optical centre a lift measured: `offset` =
    /// `VisionPxCenterOffsetX/Y` (pixels) and `sigma` its 1σ per axis (pixels, > 0).
    ///
    /// # Errors
    /// [`VisionError::InvalidParam`] for an offset or σ out of range; `self` is unchanged.
    pub fn with_centre(&self, offset: Vector2<f64>, sigma: f64) -> Result<Calibration, VisionError> {
        let mut next = self.clone();
        next.set_raw("VisionPxCenterOffsetX", &ParamValue::from(offset.x))?;
        next.set_raw("VisionPxCenterOffsetY", &ParamValue::from(offset.y))?;
        next.set_raw("VisionPxCenterSigmaPx", &ParamValue::from(sigma))?;
        Ok(next)
    }

    /// The lens the pixel chain undoes, `None` without one (`VisionLensFocalPx` = 0).
    #[must_use]
    pub fn lens(&self) -> Option<vision_math::Lens> {
        let k = [self.lens_k1, self.lens_k2, self.lens_p1, self.lens_p2];
        vision_math::Lens::new(k, self.lens_focal_px).ok()
    }

    /// The 1σ of `[k1, k2, p1, p2]`.
    #[must_use]
    pub fn lens_sigma(&self) -> [f64; 4] {
        [self.lens_k1_sigma, self.lens_k2_sigma, self.lens_p1_sigma, self.lens_p2_sigma]
    }

    /// This calibration with `lens` and the 1σ of its coefficients (`None`: no lens model).
    ///
    /// # Errors
    /// [`VisionError::InvalidParam`] for a value out of its range; `self` is unchanged.
    pub fn with_lens(&self, lens: Option<(vision_math::Lens, [f64; 4])>) -> Result<Calibration, VisionError> {
        let mut next = self.clone();
        let (k, focal, sigma) = lens.map_or(([0.0; 4], 0.0, [0.0; 4]), |(l, s)| (l.coefficients(), l.focal_px(), s));
        let names = ["VisionLensK1", "VisionLensK2", "VisionLensP1", "VisionLensP2"];
        let sigmas = ["VisionLensK1Sigma", "VisionLensK2Sigma", "VisionLensP1Sigma", "VisionLensP2Sigma"];
        for i in 0..4 {
            next.set_raw(names[i], &ParamValue::from(k[i]))?;
            next.set_raw(sigmas[i], &ParamValue::from(sigma[i]))?;
        }
        next.set_raw("VisionLensFocalPx", &ParamValue::from(focal))?;
        Ok(next)
    }

    /// The image size this calibration was made at, pixels; `None` when not recorded.
    #[must_use]
    pub fn recorded_resolution(&self) -> Option<(i64, i64)> {
        (self.cal_res_x > 0 && self.cal_res_y > 0).then_some((self.cal_res_x, self.cal_res_y))
    }

    /// The driver this calibration was made with; `None` when not recorded.
    #[must_use]
    pub fn recorded_driver(&self) -> Option<&str> {
        (!self.cal_driver.is_empty()).then_some(self.cal_driver.as_str())
    }

    /// The mark the camera searched for when this calibration was made; `None` when not
    /// recorded.
    #[must_use]
    pub fn recorded_mark(&self) -> Option<&str> {
        (!self.cal_mark.is_empty()).then_some(self.cal_mark.as_str())
    }

    /// The camera tool and its X/Y offset (`Cal_Units`) this calibration was made with; `None`
    /// when not recorded.
    #[must_use]
    pub fn recorded_tool(&self) -> Option<(u32, Vector2<f64>)> {
        let tool = u32::try_from(self.cal_tool_number).ok().filter(|t| *t != 0)?;
        Some((tool, Vector2::new(self.cal_tool_offset_x, self.cal_tool_offset_y)))
    }

    /// This calibration with its record: the image size (pixels), the driver's name, the mark
    /// it searched for (empty: none known) and the camera tool with its X/Y offset in
    /// `Cal_Units` it was made with (`None`: no tool).
    ///
    /// # Errors
    /// [`VisionError::InvalidParam`] for a value out of its range; `self` is unchanged.
    pub fn recorded(
        &self,
        resolution: (i64, i64),
        driver: &str,
        mark: &str,
        tool: Option<(u32, Vector2<f64>)>,
    ) -> Result<Calibration, VisionError> {
        let mut next = self.clone();
        next.set_raw("VisionCal_Mark", &ParamValue::from(mark))?;
        next.set_raw("VisionCal_ResX", &ParamValue::from(resolution.0))?;
        next.set_raw("VisionCal_ResY", &ParamValue::from(resolution.1))?;
        next.set_raw("VisionCal_Driver", &ParamValue::from(driver))?;
        let (number, offset) = tool.map_or((0, Vector2::zeros()), |(t, o)| (i64::from(t), o));
        next.set_raw("VisionCal_ToolNumber", &ParamValue::from(number))?;
        next.set_raw("VisionCal_ToolOffsetX", &ParamValue::from(offset.x))?;
        next.set_raw("VisionCal_ToolOffsetY", &ParamValue::from(offset.y))?;
        Ok(next)
    }

    /// This calibration with a new K, remap, unit and date (the pixel centre offset is kept).
    ///
    /// # Errors
    /// [`VisionError::InvalidParam`] for a K [`Calibration::check_k`] refuses (a profile
    /// load would) or a date longer than the profile allows; `self` is unchanged either way.
    pub fn solved(
        &self,
        k: Matrix2<f64>,
        remap: Remap,
        units: LengthUnit,
        date: &str,
    ) -> Result<Calibration, VisionError> {
        let mut next = self.clone();
        next.set_cal_k(k)?;
        next.set_remap(remap);
        next.cal_units = units;
        next.set_raw("VisionCal_Date", &ParamValue::from(date))?;
        next.check_k()?;
        Ok(next)
    }
}
