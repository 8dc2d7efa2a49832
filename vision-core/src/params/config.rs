//! [`Config`]: the operator's settings.

use super::checks::{
    Check, DRIVER_NAME, JOB, LENS_GRID, LIFT_IN, NOISE_PX, NOISE_PX_WIDE, NON_NEGATIVE, PASSES, POUND_BASE, RESOLUTION,
    SECONDS_60, TOOL,
};

profile_part! {
    /// The persisted configuration: the driver's name, the camera, pound-variable output and the
    /// fit quality gates (a driver's own settings, e.g. the camera's address, are its
    /// [`DriverSettings`](super::DriverSettings)). Written by the operator (profile, CLI, DRO) and by M284
    /// (`VisionActiveJob`).
    Config in config {
        /// `VisionEnabled`: master enable. When No, every Vision M-code fails with "Vision is not
        /// enabled" and no driver is loaded.
        (Connection, "", "operator") enabled: bool => bool = false, "VisionEnabled", Check::ANY;
        /// `VisionDriver`: the camera driver's registry name (default `Keyence`).
        (Connection, "", "operator") driver: String => &str = "Keyence".to_string(), "VisionDriver", DRIVER_NAME;
        /// `VisionActiveJob`: camera job 0..999 applied by M284 without P; written by M284. 0 =
        /// leave the camera on its loaded job.
        (Connection, "", "operator, M284") active_job: i64 => i64 = 0, "VisionActiveJob", JOB;
        /// `VisionCameraResX`: image width, pixels.
        (Connection, "px", "operator") camera_res_x: i64 => i64 = 1776, "VisionCameraResX", RESOLUTION;
        /// `VisionCameraResY`: image height, pixels.
        (Connection, "px", "operator") camera_res_y: i64 => i64 = 1776, "VisionCameraResY", RESOLUTION;
        /// `VisionTriggerSettleSec`: dwell M283 inserts after each move before triggering, seconds.
        (Connection, "s", "operator") trigger_settle_s: f64 => f64 = 0.25, "VisionTriggerSettleSec", SECONDS_60;
        /// `VisionCameraNoisePx`: the camera's repeatability, the standard deviation of a
        /// reported mark centre on each pixel axis, pixels. M282 turns it into machine units
        /// with K for the fit's predicted error (the residuals' own σ is used when larger).
        /// Default 0.1 px: what a sub-pixel pattern search on a sharp dot typically repeats
        /// to, and the simulator's σ in the acceptance tests.
        (Connection, "px", "operator") camera_noise_px: f64 => f64 = 0.1, "VisionCameraNoisePx", NOISE_PX;
        /// `VisionRecenterPasses`: how many times M281 may move the camera over a mark it saw
        /// off the image centre and trigger again (0 = read in one shot, as the seed did).
        /// Default 2: one pass brings the mark to within K's error times its first distance,
        /// the second to the noise.
        (Connection, "", "operator") recenter_passes: i64 => i64 = 2, "VisionRecenterPasses", PASSES;
        /// `VisionRecenterTolerance`: 0 (default) = M281 decides from the error budget when to
        /// move (see `VisionHeightProbePx`); > 0 = the fixed rule of issue 25, pixels: re-centre
        /// while the mark is farther than this from the image centre, and make no probe move.
        /// Why 0: a fixed 16 px left marks 3–11 px off centre read in one shot, so a part 4 %
        /// higher than at calibration cut 3.5× the floor and nothing measured it; the budget
        /// moves only when the scale's remaining uncertainty times the mark's distance would
        /// add more than 0.3 of the camera's noise (≤ 4.4 % in quadrature).
        (Connection, "px", "operator") recenter_tolerance_px: f64 => f64 = 0.0, "VisionRecenterTolerance", NON_NEGATIVE;
        /// `VisionHeightProbePx`: the length of M281's deliberate probe move, pixels: when the
        /// scale's budget asks for a move and the mark is seen closer to the centre than a
        /// quarter of this (a re-centring move would measure little), the camera moves so the
        /// mark lands this far
        /// on the other side, reads it, and keeps the reading nearer the centre. 0 = never
        /// probe (only re-centring moves measure the scale). Default 120 px: with the mark
        /// first seen ~16 px off centre the two readings lie ~136 px apart and measure the scale
        /// to √2 × 0.1 px / 136 px = 0.10 % (1σ), so every later mark within 29 px is read in
        /// one shot within budget; on example 4 the probe costs 0.94 s (+31 % over one shot,
        /// 200 px would cost +34 %, a 16 px re-centring pass +24 %).
        (Connection, "px", "operator") height_probe_px: f64 => f64 = 120.0, "VisionHeightProbePx", NON_NEGATIVE;
        /// `VisionHeightCorrection`: M282 corrects the run's captures for the image scale the
        /// camera moves measured (scale ∝ working distance: each capture's offset from the
        /// camera × (1 + ε)) and widens its predicted error by the scale's remaining 1σ. Off:
        /// the captures are used as read (the manual's behaviour) and the prediction is widened
        /// by the whole measured scale error instead. Default on: at the calibration height it
        /// changes the cut by less than the noise (ε ≈ 0 ± 0.1 %), and off it a part 4 % higher
        /// cuts at 3.5× the floor with a bound that misses three fits in four.
        (Connection, "", "operator") height_correction: bool => bool = true, "VisionHeightCorrection", Check::ANY;
        /// `VisionHeightWarnPct`: M282's report warns, with the manual's advice, when the
        /// measured working-distance change exceeds this, percent (0 disables). Default 1 %:
        /// the manual's "even a 1 % standoff change … puts the verify residual out of spec".
        (Connection, "%", "operator") height_warn_pct: f64 => f64 = 1.0, "VisionHeightWarnPct", NON_NEGATIVE;
        /// `VisionCenterUncertaintyPx`: how far, 1σ per pixel axis, the optical axis may meet the
        /// image from the centre the profile assumes (image centre + `VisionPxCenterOffset`),
        /// pixels. The sheet walk cannot see that error at its own height — it is absorbed into
        /// the camera offset exactly — but at a height `ε` away it shifts every capture by
        /// `ε` × it × K, a shift no camera move can measure (it looks like the part's own).
        /// M282 widens its prediction by it whenever the run measured a height change, unless
        /// the calibration measured the centre (`VisionPxCenterSigmaPx` > 0): then by that.
        /// Default 3 px: the simulator's cameras are off by up to ±5 px per axis (σ 2.9 px); a
        /// real lens can be off by tens of pixels — a camera calibrated at the part's height
        /// (the manual's advice) carries none of it.
        (Connection, "px", "operator") center_uncertainty_px: f64 => f64 = 3.0, "VisionCenterUncertaintyPx", NOISE_PX_WIDE;
        /// `VisionCalibrationLift`: how far M283's sheet walk raises the camera (machine +Z) to
        /// measure the optical centre, inches (25.4 mm per inch under G21); 0 = the manual's
        /// walk at one height, which leaves the centre where `VisionPxCenterOffset` says. The
        /// image shrinks about the pixel that sees the same table point at both heights; the
        /// walk writes that pixel to `VisionPxCenterOffsetX/Y`, its 1σ to
        /// `VisionPxCenterSigmaPx`, and solves the camera offset at it. Default 0.25 in: ~4 %
        /// of a 6 in working distance, which with 25 pairs of readings at 0.1 px finds the
        /// centre to ~0.7 px (without it a ±4 % height change cuts at up to 1.7× the floor); the
        /// camera rises, away from the part, and comes back before the verify walk.
        (Connection, "in", "operator") calibration_lift_in: f64 => f64 = 0.25, "VisionCalibrationLift", LIFT_IN;
        /// `VisionCalibrationGrid`: positions per axis of the lens grid M283's sheet walk reads
        /// the last dot from, putting it up to three quarters of the way to the image's edges,
        /// where a lens's distortion shows (0 = no lens grid: the walk's probes alone cannot tell
        /// the radial distortion from K, and M283 says so). Default 5: 25 readings measure a
        /// k1 of −0.10 to about 3 % at 0.1 px; a camera that finds no mark out there skips
        /// those positions.
        (Connection, "", "operator") calibration_grid: i64 => i64 = 5, "VisionCalibrationGrid", LENS_GRID;
        /// `VisionWorkingDistance`: the lens-to-part distance at which K was calibrated, inches
        /// (25.4 mm per inch); it turns the measured relative change into a length in the
        /// reports (0 = report the percentage only). Default 6 in: the manual's "typical 6″
        /// working distance"; set it to the machine's.
        (Connection, "in", "operator") working_distance_in: f64 => f64 = 6.0, "VisionWorkingDistance", NON_NEGATIVE;
        /// `VisionMarkDiameter`: the fiducial's true diameter, inches (0 disables the height
        /// check). M281 compares the measured mark size with it and warns when they differ by
        /// more than `VisionMarkSizeTolerance`, with the implied working-distance change.
        (Connection, "in", "operator") mark_diameter_in: f64 => f64 = 0.0, "VisionMarkDiameter", NON_NEGATIVE;
        /// `VisionMarkSizeTolerance`: the height check's threshold, percent of the diameter.
        /// Default 2 %: a mark's edge is found to a fraction of a pixel, so 2 % of a 0.25 in
        /// dot (~2.5 px at 0.002 in/px) is a real height change of about 2 %, the change at
        /// which a mark half a field (0.9 in) off centre is read 0.018 in wrong in one shot.
        (Connection, "%", "operator") mark_size_tolerance_pct: f64 => f64 = 2.0, "VisionMarkSizeTolerance", NON_NEGATIVE;
        /// `VisionCameraToolNumber`: the camera's tool number; M280–M283 require it active. 0
        /// disables the check.
        (Output, "", "operator") camera_tool_number: i64 => i64 = 0, "VisionCameraToolNumber", TOOL;
        /// `VisionPoundVarBase`: base B of the 5-slot × 8-field pound-variable block `#B..#B+39`.
        /// B ≥ 100, block outside 5061..5081 and 5201..5500.
        (Output, "", "operator") pound_var_base: i64 => i64 = 500, "VisionPoundVarBase", POUND_BASE;
        /// `VisionFitMaxScaleDev`: M282 refuses a fit whose X or Y scale deviates from 1 by more
        /// than this, percent (0 disables). Default 2 %: prints and sheet goods stay well inside
        /// it, while a wrong unit (25.4×) or a wrong mark is far outside.
        (Quality, "%", "operator") fit_max_scale_dev_pct: f64 => f64 = 2.0, "VisionFitMaxScaleDev", NON_NEGATIVE;
        /// `VisionFitMaxShift`: M282 refuses a fit whose shift (observed centroid − commanded
        /// centroid) is longer than this, inches (25.4 mm per inch under G21; 0 disables).
        /// Default 2.5 in: the manual's workflow places parts within roughly 2 in of nominal,
        /// and a capture that far off is still a real mark, not a sign of the wrong program.
        (Quality, "in", "operator") fit_max_shift_in: f64 => f64 = 2.5, "VisionFitMaxShift", NON_NEGATIVE;
        /// `VisionFitMaxResidual`: M282 refuses a fit whose worst mark residual exceeds this,
        /// inches (0 disables). Default 0.020 in: a mark the model cannot follow (a burr, a
        /// wrong feature) beyond ten times the cut budget; the finer model error is
        /// `VisionFitMaxAxisScaleError`'s, a single bad mark `VisionOutlierFactor`'s.
        (Quality, "in", "operator") fit_max_residual_in: f64 => f64 = 0.020, "VisionFitMaxResidual", NON_NEGATIVE;
        /// `VisionFitMaxAxisScaleError`: M282 refuses a similarity fit when the marks show X
        /// and Y scaled differently by enough to miss a mark by more than this, inches (0
        /// disables). Default 0.002 in: the cut-error budget; such a part needs rectangle mode.
        (Quality, "in", "operator") fit_max_axis_scale_error_in: f64 => f64 = 0.002, "VisionFitMaxAxisScaleError", NON_NEGATIVE;
        /// `VisionOutlierFactor`: with five marks or more, M282 leaves out the one mark whose
        /// distance from the fit of the others exceeds this many times the noise (the larger
        /// of the camera's and the others' residual σ), and reports it; 0 disables. Default
        /// 6: clean marks stay under it (at most 1 % false alarms in vision-math's test of 500
        /// noisy six-mark fits), while a 0.05 in slip is over a hundred σ of a 0.1 px camera.
        (Quality, "× noise σ", "operator") outlier_factor: f64 => f64 = 6.0, "VisionOutlierFactor", NON_NEGATIVE;
    }
}

impl Config {
    /// The camera tool number, or `None` when the check is disabled (0).
    #[must_use]
    pub fn camera_tool(&self) -> Option<u32> {
        u32::try_from(self.camera_tool_number).ok().filter(|t| *t != 0)
    }
}
