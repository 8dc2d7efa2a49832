//! [`Config`]: the operator's settings.

use super::checks::{any, driver_name, job, noise_px, non_negative, passes, pound_base, resolution, seconds_60, tool};

profile_part! {
    /// The persisted configuration: the driver's name, the camera, pound-variable output and the
    /// fit quality gates (a driver's own settings, e.g. the camera's address, are its
    /// [`DriverSettings`](super::DriverSettings)). Written by the operator (profile, CLI, DRO) and by M284
    /// (`VisionActiveJob`).
    Config in config {
        /// `VisionEnabled`: master enable. When No, every Vision M-code fails with "Vision is not
        /// enabled" and no driver is loaded.
        (Connection) enabled: bool => bool = false, "VisionEnabled", any;
        /// `VisionDriver`: the camera driver's registry name (default `Keyence`).
        (Connection) driver: String => &str = "Keyence".to_string(), "VisionDriver", driver_name;
        /// `VisionActiveJob`: camera job 0..999 applied by M284 without P; written by M284. 0 =
        /// leave the camera on its loaded job.
        (Connection) active_job: i64 => i64 = 0, "VisionActiveJob", job;
        /// `VisionCameraResX`: image width, pixels.
        (Connection) camera_res_x: i64 => i64 = 1776, "VisionCameraResX", resolution;
        /// `VisionCameraResY`: image height, pixels.
        (Connection) camera_res_y: i64 => i64 = 1776, "VisionCameraResY", resolution;
        /// `VisionTriggerSettleSec`: dwell M283 inserts after each move before triggering, seconds.
        (Connection) trigger_settle_s: f64 => f64 = 0.25, "VisionTriggerSettleSec", seconds_60;
        /// `VisionCameraNoisePx`: the camera's repeatability, the standard deviation of a
        /// reported mark centre on each pixel axis, pixels. M282 turns it into machine units
        /// with K for the fit's predicted error (the residuals' own σ is used when larger).
        /// Default 0.1 px: what a sub-pixel pattern search on a sharp dot typically repeats
        /// to, and the simulator's σ in the acceptance tests.
        (Connection) camera_noise_px: f64 => f64 = 0.1, "VisionCameraNoisePx", noise_px;
        /// `VisionRecenterPasses`: how many times M281 may move the camera over a mark it saw
        /// off the image centre and trigger again (0 = read in one shot, as the seed did).
        /// Default 2: one pass brings the mark to within K's error times its first distance,
        /// the second to the noise.
        (Connection) recenter_passes: i64 => i64 = 2, "VisionRecenterPasses", passes;
        /// `VisionRecenterTolerance`: M281 re-centres while the mark is farther than this from
        /// the image centre, pixels. Default 16 px: with the part 4 % closer or farther than at
        /// calibration a mark 16 px off centre is read 0.64 px (0.0013 in at 0.002 in/px) wrong,
        /// and the acceptance runs at ±4 % then cut within 0.002 in; on example 4 it re-reads
        /// one mark of four, adding 21 % to the alignment time (the issue allows 25 %).
        (Connection) recenter_tolerance_px: f64 => f64 = 16.0, "VisionRecenterTolerance", non_negative;
        /// `VisionMarkDiameter`: the fiducial's true diameter, inches (0 disables the height
        /// check). M281 compares the measured mark size with it and warns when they differ by
        /// more than `VisionMarkSizeTolerance`, with the implied working-distance change.
        (Connection) mark_diameter_in: f64 => f64 = 0.0, "VisionMarkDiameter", non_negative;
        /// `VisionMarkSizeTolerance`: the height check's threshold, percent of the diameter.
        /// Default 2 %: a mark's edge is found to a fraction of a pixel, so 2 % of a 0.25 in
        /// dot (~2.5 px at 0.002 in/px) is a real height change of about 2 %, the change at
        /// which a mark half a field (0.9 in) off centre is read 0.018 in wrong in one shot.
        (Connection) mark_size_tolerance_pct: f64 => f64 = 2.0, "VisionMarkSizeTolerance", non_negative;
        /// `VisionCameraToolNumber`: the camera's tool number; M280–M283 require it active. 0
        /// disables the check.
        (Output) camera_tool_number: i64 => i64 = 0, "VisionCameraToolNumber", tool;
        /// `VisionPoundVarBase`: base B of the 5-slot × 8-field pound-variable block `#B..#B+39`.
        /// B ≥ 100, block outside 5061..5081 and 5201..5500.
        (Output) pound_var_base: i64 => i64 = 500, "VisionPoundVarBase", pound_base;
        /// `VisionFitMaxScaleDev`: M282 refuses a fit whose X or Y scale deviates from 1 by more
        /// than this, percent (0 disables). Default 2 %: prints and sheet goods stay well inside
        /// it, while a wrong unit (25.4×) or a wrong mark is far outside.
        (Quality) fit_max_scale_dev_pct: f64 => f64 = 2.0, "VisionFitMaxScaleDev", non_negative;
        /// `VisionFitMaxShift`: M282 refuses a fit whose shift (observed centroid − commanded
        /// centroid) is longer than this, inches (25.4 mm per inch under G21; 0 disables).
        /// Default 2.5 in: the manual's workflow places parts within roughly 2 in of nominal,
        /// and a capture that far off is still a real mark, not a sign of the wrong program.
        (Quality) fit_max_shift_in: f64 => f64 = 2.5, "VisionFitMaxShift", non_negative;
        /// `VisionFitMaxResidual`: M282 refuses a fit whose worst mark residual exceeds this,
        /// inches (0 disables). Default 0.020 in: a mark the model cannot follow (a burr, a
        /// wrong feature) beyond ten times the cut budget; the finer model error is
        /// `VisionFitMaxAxisScaleError`'s, a single bad mark `VisionOutlierFactor`'s.
        (Quality) fit_max_residual_in: f64 => f64 = 0.020, "VisionFitMaxResidual", non_negative;
        /// `VisionFitMaxAxisScaleError`: M282 refuses a similarity fit when the marks show X
        /// and Y scaled differently by enough to miss a mark by more than this, inches (0
        /// disables). Default 0.002 in: the cut-error budget; such a part needs rectangle mode.
        (Quality) fit_max_axis_scale_error_in: f64 => f64 = 0.002, "VisionFitMaxAxisScaleError", non_negative;
        /// `VisionOutlierFactor`: with five marks or more, M282 leaves out the one mark whose
        /// distance from the fit of the others exceeds this many times the noise (the larger
        /// of the camera's and the others' residual σ), and reports it; 0 disables. Default
        /// 6: clean marks stay under it (at most 1 % false alarms in vision-math's test of 500
        /// noisy six-mark fits), while a 0.05 in slip is over a hundred σ of a 0.1 px camera.
        (Quality) outlier_factor: f64 => f64 = 6.0, "VisionOutlierFactor", non_negative;
    }
}

impl Config {
    /// The camera tool number, or `None` when the check is disabled (0).
    #[must_use]
    pub fn camera_tool(&self) -> Option<u32> {
        u32::try_from(self.camera_tool_number).ok().filter(|t| *t != 0)
    }
}
