//! [`Telemetry`]: what the last operation measured and emitted.

use super::checks::any;

param_struct! {
    /// Telemetry: what the last operation measured and emitted, written by the module after
    /// each operation and never read back to decide anything (the run's own state is
    /// [`crate::module::Run`]). Read-only by name; never persisted.
    Telemetry (Telemetry) {
        /// `VisionLastJudgment`: 1 OK, 0 NG, −1 unknown, of the last trigger.
        (LastResult) last_judgment: i64 => i64 = -1, "VisionLastJudgment", any;
        /// `VisionLastOffsetPxX`: last centred pixel x (after the centre shift, before remap and K),
        /// pixels.
        (LastResult) last_offset_px_x: f64 => f64 = 0.0, "VisionLastOffsetPxX", any;
        /// `VisionLastOffsetPxY`: last centred pixel y, pixels.
        (LastResult) last_offset_px_y: f64 => f64 = 0.0, "VisionLastOffsetPxY", any;
        /// `VisionLastOffsetX`: last offset `d` from the camera to the mark, X, current units.
        (LastResult) last_offset_x: f64 => f64 = 0.0, "VisionLastOffsetX", any;
        /// `VisionLastOffsetY`: same, Y, current units.
        (LastResult) last_offset_y: f64 => f64 = 0.0, "VisionLastOffsetY", any;
        /// `VisionLastWidth`: last mark width, current units.
        (LastResult) last_width: f64 => f64 = 0.0, "VisionLastWidth", any;
        /// `VisionLastHeight`: last mark height, current units.
        (LastResult) last_height: f64 => f64 = 0.0, "VisionLastHeight", any;
        /// `VisionLastAngle`: last mark angle, degrees.
        (LastResult) last_angle: f64 => f64 = 0.0, "VisionLastAngle", any;
        /// `VisionLastScore`: last match score (driver scale).
        (LastResult) last_score: f64 => f64 = 0.0, "VisionLastScore", any;
        /// `VisionLastStatus`: `OK` (possibly with a warning) or the last error text.
        (LastResult) last_status: String => &str = String::new(), "VisionLastStatus", any;
        /// `VisionRun_Active`: 1 between M280 and a successful M282, else 0 (from the run).
        (RunState) run_active: i64 => i64 = 0, "VisionRun_Active", any;
        /// `VisionRun_Mode`: 4 rectangle, 3 similarity (from the run).
        (RunState) run_mode: i64 => i64 = 4, "VisionRun_Mode", any;
        /// `VisionRun_DotCount`: captures taken in the current run (the dot list's length).
        (RunState) run_dot_count: i64 => i64 = 0, "VisionRun_DotCount", any;
        /// `VisionRun_Tx`: emitted G52 X shift, current units.
        (RunState) run_tx: f64 => f64 = 0.0, "VisionRun_Tx", any;
        /// `VisionRun_Ty`: emitted G52 Y shift, current units.
        (RunState) run_ty: f64 => f64 = 0.0, "VisionRun_Ty", any;
        /// `VisionRun_Theta`: emitted rotation, radians (G68 R is its value in degrees).
        (RunState) run_theta: f64 => f64 = 0.0, "VisionRun_Theta", any;
        /// `VisionRun_Sx`: emitted G51 X factor.
        (RunState) run_sx: f64 => f64 = 1.0, "VisionRun_Sx", any;
        /// `VisionRun_Sy`: emitted G51 Y factor.
        (RunState) run_sy: f64 => f64 = 1.0, "VisionRun_Sy", any;
        /// `VisionRun_CenterX`: emitted G68 X rotation centre, current units.
        (RunState) run_center_x: f64 => f64 = 0.0, "VisionRun_CenterX", any;
        /// `VisionRun_CenterY`: emitted G68 Y rotation centre, current units.
        (RunState) run_center_y: f64 => f64 = 0.0, "VisionRun_CenterY", any;
        /// `VisionRun_PredictedSigma`: the last fit's predicted cut error over the marks'
        /// bounding box, 1σ (root-mean-square length), current units.
        (RunState) run_predicted_sigma: f64 => f64 = 0.0, "VisionRun_PredictedSigma", any;
        /// `VisionRun_PredictedBound`: a radius that holds the last fit's largest cut error over
        /// the marks' bounding box with ≥ 99 % probability, current units.
        (RunState) run_predicted_bound: f64 => f64 = 0.0, "VisionRun_PredictedBound", any;
        /// `VisionRun_HeightChangePct`: the working-distance change the last fit's camera moves
        /// measured, percent of the calibration's (+ = the part farther from the camera); 0
        /// with `VisionRun_HeightSigmaPct` 0 when the run made no move to measure it.
        (RunState) run_height_change_pct: f64 => f64 = 0.0, "VisionRun_HeightChangePct", any;
        /// `VisionRun_HeightChange`: the same as a length (`VisionWorkingDistance` × the
        /// change), current units.
        (RunState) run_height_change: f64 => f64 = 0.0, "VisionRun_HeightChange", any;
        /// `VisionRun_HeightSigmaPct`: the 1σ of `VisionRun_HeightChangePct`, percent.
        (RunState) run_height_sigma_pct: f64 => f64 = 0.0, "VisionRun_HeightSigmaPct", any;
    }
}

impl serde::Serialize for Telemetry {
    /// A map from each telemetry parameter's manual name to its value, in the manual's order.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        crate::ser::named_values(Telemetry::SPECS, |name| self.get(name), s)
    }
}
