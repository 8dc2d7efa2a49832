//! [`Telemetry`]: what the last operation measured and emitted.

use super::checks::Check;

param_struct! {
    /// Telemetry: what the last operation measured and emitted, written by the module after
    /// each operation and never read back to decide anything (the run's own state is
    /// [`crate::module::Run`]). Read-only by name; never persisted.
    Telemetry (Telemetry) {
        /// `VisionLastJudgment`: 1 OK, 0 NG, −1 unknown, of the last trigger.
        (LastResult, "", "M281, M283") last_judgment: i64 => i64 = -1, "VisionLastJudgment", Check::ANY;
        /// `VisionLastOffsetPxX`: last centred pixel x (after the centre shift, before remap and K),
        /// pixels.
        (LastResult, "px", "M281, M283") last_offset_px_x: f64 => f64 = 0.0, "VisionLastOffsetPxX", Check::ANY;
        /// `VisionLastOffsetPxY`: last centred pixel y, pixels.
        (LastResult, "px", "M281, M283") last_offset_px_y: f64 => f64 = 0.0, "VisionLastOffsetPxY", Check::ANY;
        /// `VisionLastOffsetX`: last offset `d` from the camera to the mark, X, current units.
        (LastResult, "current units", "M281, M283") last_offset_x: f64 => f64 = 0.0, "VisionLastOffsetX", Check::ANY;
        /// `VisionLastOffsetY`: same, Y, current units.
        (LastResult, "current units", "M281, M283") last_offset_y: f64 => f64 = 0.0, "VisionLastOffsetY", Check::ANY;
        /// `VisionLastWidth`: last mark width, current units.
        (LastResult, "current units", "M281, M283") last_width: f64 => f64 = 0.0, "VisionLastWidth", Check::ANY;
        /// `VisionLastHeight`: last mark height, current units.
        (LastResult, "current units", "M281, M283") last_height: f64 => f64 = 0.0, "VisionLastHeight", Check::ANY;
        /// `VisionLastAngle`: last mark angle, degrees.
        (LastResult, "°", "M281, M283") last_angle: f64 => f64 = 0.0, "VisionLastAngle", Check::ANY;
        /// `VisionLastScore`: last match score (driver scale).
        (LastResult, "", "M281, M283") last_score: f64 => f64 = 0.0, "VisionLastScore", Check::ANY;
        /// `VisionLastStatus`: `OK` (possibly with a warning) or the last error text.
        (LastResult, "", "every M-code") last_status: String => &str = String::new(), "VisionLastStatus", Check::ANY;
        /// `VisionRun_Active`: 1 between M280 and a successful M282, else 0 (from the run).
        (RunState, "", "M280–M282") run_active: i64 => i64 = 0, "VisionRun_Active", Check::ANY;
        /// `VisionRun_Mode`: 4 rectangle, 3 similarity (from the run).
        (RunState, "", "M280–M282") run_mode: i64 => i64 = 4, "VisionRun_Mode", Check::ANY;
        /// `VisionRun_DotCount`: captures taken in the current run (the dot list's length).
        (RunState, "", "M280–M282") run_dot_count: i64 => i64 = 0, "VisionRun_DotCount", Check::ANY;
        /// `VisionRun_Tx`: emitted G52 X shift, current units.
        (RunState, "current units", "M282") run_tx: f64 => f64 = 0.0, "VisionRun_Tx", Check::ANY;
        /// `VisionRun_Ty`: emitted G52 Y shift, current units.
        (RunState, "current units", "M282") run_ty: f64 => f64 = 0.0, "VisionRun_Ty", Check::ANY;
        /// `VisionRun_Theta`: emitted rotation, radians (G68 R is its value in degrees).
        (RunState, "rad", "M282") run_theta: f64 => f64 = 0.0, "VisionRun_Theta", Check::ANY;
        /// `VisionRun_Sx`: emitted G51 X factor.
        (RunState, "", "M282") run_sx: f64 => f64 = 1.0, "VisionRun_Sx", Check::ANY;
        /// `VisionRun_Sy`: emitted G51 Y factor.
        (RunState, "", "M282") run_sy: f64 => f64 = 1.0, "VisionRun_Sy", Check::ANY;
        /// `VisionRun_CenterX`: emitted G68 X rotation centre, current units.
        (RunState, "current units", "M282") run_center_x: f64 => f64 = 0.0, "VisionRun_CenterX", Check::ANY;
        /// `VisionRun_CenterY`: emitted G68 Y rotation centre, current units.
        (RunState, "current units", "M282") run_center_y: f64 => f64 = 0.0, "VisionRun_CenterY", Check::ANY;
        /// `VisionRun_PredictedSigma`: the last fit's predicted cut error over the marks'
        /// bounding box, 1σ (root-mean-square length), current units.
        (RunState, "current units", "M282") run_predicted_sigma: f64 => f64 = 0.0, "VisionRun_PredictedSigma", Check::ANY;
        /// `VisionRun_PredictedBound`: a radius that holds the last fit's largest cut error over
        /// the marks' bounding box with ≥ 99 % probability, current units.
        (RunState, "current units", "M282") run_predicted_bound: f64 => f64 = 0.0, "VisionRun_PredictedBound", Check::ANY;
        /// `VisionRun_HeightChangePct`: the working-distance change the last fit's camera moves
        /// measured, percent of the calibration's (+ = the part farther from the camera); 0
        /// with `VisionRun_HeightSigmaPct` 0 when the run made no move to measure it.
        (RunState, "%", "M282") run_height_change_pct: f64 => f64 = 0.0, "VisionRun_HeightChangePct", Check::ANY;
        /// `VisionRun_HeightChange`: the same as a length (`VisionWorkingDistance` × the
        /// change), current units.
        (RunState, "current units", "M282") run_height_change: f64 => f64 = 0.0, "VisionRun_HeightChange", Check::ANY;
        /// `VisionRun_HeightSigmaPct`: the 1σ of `VisionRun_HeightChangePct`, percent.
        (RunState, "%", "M282") run_height_sigma_pct: f64 => f64 = 0.0, "VisionRun_HeightSigmaPct", Check::ANY;
    }
}

impl serde::Serialize for Telemetry {
    /// A map from each telemetry parameter's manual name to its value, in the manual's order.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        crate::ser::named_values(Telemetry::SPECS, |name| self.get(name), s)
    }
}
