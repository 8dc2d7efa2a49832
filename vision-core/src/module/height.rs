//! The part's height, measured by the camera moves of M281 (issue 28).
//!
//! K is right only at the working distance it was calibrated at, and the image scale follows
//! the working distance (the manual's "Camera Z Height & Working Distance"). Every M281 that
//! reads a mark from two camera positions measures the scale at the part's height
//! ([`vision_math::scale`]); the run combines its marks, M282 corrects the captures for it and
//! widens its prediction by what remains uncertain, and reports the change. This file holds
//! the decision when M281 moves and the report M282 gives; the estimate itself is pure math.

use vision_math::{LengthUnit, ScaleEstimate};

use crate::params::Params;

/// The share of the camera's noise an unmeasured scale may add to a capture before M281 moves
/// the camera: 0.3 adds at most √(1 + 0.3²) − 1 = 4.4 % to that capture's error.
pub(crate) const BUDGET_SHARE: f64 = 0.3;

/// The scale's 1σ assumed before a run has measured it: 6 %, beyond the manual's "more than
/// ~5 % of the working distance" at which it asks for a new calibration anyway.
pub(crate) const PRIOR_SCALE_SIGMA: f64 = 0.06;

/// What M281 does after a reading.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum NextMove {
    /// Keep the reading nearest the image centre: it is within budget.
    Stay,
    /// Move the camera over the mark and read it again.
    Recentre,
    /// Move so the mark lands `VisionHeightProbePx` on the other side of the centre and read
    /// it again: a longer baseline for the scale than a short re-centring move.
    Probe,
}

/// The move after a reading: `best_px` is the distance from the image centre of the reading
/// nearest it so far (pixels), `scale_sigma` the 1σ of the scale the run and this mark have
/// measured (`None`: not yet measured), `probed` whether this mark was probed already.
pub(crate) fn next_move(params: &Params, best_px: f64, scale_sigma: Option<f64>, probed: bool) -> NextMove {
    let tolerance = params.recenter_tolerance_px();
    if tolerance > 0.0 {
        // Issue 25's fixed rule, kept reachable.
        return if best_px > tolerance { NextMove::Recentre } else { NextMove::Stay };
    }
    let sigma = scale_sigma.unwrap_or(PRIOR_SCALE_SIGMA);
    if sigma * best_px <= BUDGET_SHARE * noise_px(params) {
        return NextMove::Stay;
    }
    let probe = params.height_probe_px();
    // A re-centring move of a quarter of the probe or more measures the scale to within
    // √2·σ/(probe/4) (0.5 % at the defaults) and ends over the mark; a shorter one measures
    // little, where a probe's baseline is the probe's length.
    if probe > 0.0 && !probed && best_px < probe / 4.0 {
        NextMove::Probe
    } else {
        NextMove::Recentre
    }
}

/// The camera's noise per pixel axis, pixels, never below 0.001 px (a noiseless setting still
/// weighs readings, and a zero budget would move forever).
pub(crate) fn noise_px(params: &Params) -> f64 {
    params.camera_noise_px().max(1e-3)
}

/// The shift a working-distance change `error` (ε) makes of every capture when the calibration
/// never measured the optical centre, in `unit`: `|ε|` × `VisionCenterUncertaintyPx` × K's
/// largest singular value. `None` when the centre was measured (`VisionPxCenterSigmaPx` > 0).
///
/// Decision: a note, not a correction. At one working distance a misplaced centre is absorbed
/// into the camera offset exactly; at another it moves every capture by ε × its pixel error ×
/// K, the same for every mark, as the part's own shift does — camera moves at one height cannot
/// measure it, only a calibration that reads a mark from two heights (the lift) can. M282
/// widens its prediction by it; this says where the error comes from and what removes it.
pub(crate) fn unmeasured_centre_shift(params: &Params, error: f64, unit: LengthUnit) -> Option<f64> {
    if params.calibration.center_sigma().is_some() {
        return None;
    }
    let k = params.cal_k().singular_values().max() * params.cal_units().factor_to(unit);
    let shift = error.abs() * params.center_uncertainty_px() * k;
    (shift > 0.0 && shift.is_finite()).then_some(shift)
}

/// The working-distance change a run measured, with every fit (M282). Lengths in the report's
/// unit.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct HeightReport {
    /// The working-distance change, percent of the calibration's (+ = the part farther from
    /// the camera than where K was calibrated): `100·ε`, `ε` the scale error of K here.
    pub change_pct: f64,
    /// Its 1σ, percent.
    pub sigma_pct: f64,
    /// The change as a length: `VisionWorkingDistance` × `change_pct` / 100; 0 when
    /// `VisionWorkingDistance` is 0.
    pub change: f64,
    /// Its 1σ, same unit.
    pub sigma: f64,
    /// The marks read from more than one camera position that measured it.
    pub marks: u32,
    /// Whether the captures were corrected for it (`VisionHeightCorrection`).
    pub corrected: bool,
    /// What the marks' size says (`VisionMarkDiameter` set): the change the mean measured
    /// diameter implies, percent; `None` without a configured diameter.
    pub mark_size_pct: Option<f64>,
    /// Above `VisionHeightWarnPct`, or when the mark size disagrees: what to do.
    pub warning: Option<String>,
}

/// The report of `estimate` for a run: `mark_sizes` are the run's measured mean diameters in
/// `unit` (for the cross-check with `VisionMarkDiameter`); `sheet` is how the controller calls
/// the sheet calibration ([`crate::Controller::sheet_calibration`]), for the advice.
pub(crate) fn report(
    params: &Params,
    estimate: ScaleEstimate,
    unit: LengthUnit,
    mark_sizes: &[f64],
    sheet: &str,
) -> HeightReport {
    let distance = LengthUnit::Inch.convert(params.working_distance_in(), unit);
    let (change_pct, sigma_pct) = (estimate.error * 100.0, estimate.sigma * 100.0);
    let corrected = params.height_correction();
    let u = unit.short_name();
    let mut notes = Vec::new();
    let warn = params.height_warn_pct();
    if warn > 0.0 && change_pct.abs() > warn {
        let length =
            if distance > 0.0 { format!(", {:.4} {u}", (estimate.error * distance).abs()) } else { String::new() };
        notes.push(format!(
            "the part is {:.2} % (±{sigma_pct:.2} %{length}) {} the camera than where K was calibrated, more than \
             VisionHeightWarnPct = {warn} %; {} — re-run {sheet} at this height, or set the height back to the \
             calibration's",
            change_pct.abs(),
            if change_pct > 0.0 { "farther from" } else { "closer to" },
            if corrected {
                "the captures were corrected for it (VisionHeightCorrection)"
            } else {
                "the captures were NOT corrected (VisionHeightCorrection off)"
            }
        ));
        if let Some(shift) = unmeasured_centre_shift(params, estimate.error, unit) {
            notes.push(format!(
                "the optical centre was never measured (VisionPxCenterSigmaPx 0): away from the calibration height \
                 every capture may be shifted alike by about {shift:.4} {u} (the change × VisionCenterUncertaintyPx × \
                 K), which no camera move can tell from the part's own shift — {sheet} with VisionCalibrationLift > \
                 0 measures it"
            ));
        }
    }
    let diameter = LengthUnit::Inch.convert(params.mark_diameter_in(), unit);
    let measured: Vec<f64> = mark_sizes.iter().copied().filter(|m| *m > 0.0 && m.is_finite()).collect();
    let mark_size_pct = (diameter > 0.0 && !measured.is_empty()).then(|| {
        let mean = measured.iter().sum::<f64>() / measured.len() as f64;
        (diameter / mean - 1.0) * 100.0
    });
    if let Some(size_pct) = mark_size_pct {
        // The size's own uncertainty is the height check's tolerance (a print scale, an edge
        // threshold); the moves' is their 1σ, taken three times.
        let allowed = params.mark_size_tolerance_pct() + 3.0 * sigma_pct;
        if (size_pct - change_pct).abs() > allowed {
            notes.push(format!(
                "the marks' size says the part is {size_pct:+.2} % from the calibration's working distance, the camera \
                 moves {change_pct:+.2} % (±{sigma_pct:.2} %): they disagree by more than VisionMarkSizeTolerance + 3σ \
                 = {allowed:.2} % — check VisionMarkDiameter against the printed marks"
            ));
        }
    }
    HeightReport {
        change_pct,
        sigma_pct,
        change: estimate.error * distance,
        sigma: estimate.sigma * distance,
        marks: estimate.marks,
        corrected,
        mark_size_pct,
        warning: (!notes.is_empty()).then(|| notes.join("; ")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(f: impl FnOnce(&mut Params)) -> Params {
        let mut p = Params::default();
        f(&mut p);
        p
    }

    /// K = 0.002 in/px on both axes, the optical centre measured to `centre_sigma` px (0: never).
    fn calibrated(centre_sigma: f64) -> Params {
        params(|p| {
            p.set("VisionCal_Units", "in").expect("set");
            p.set_cal_k(vision_math::Matrix2::new(0.002, 0.0, 0.0, 0.002)).expect("set");
            p.set("VisionPxCenterSigmaPx", centre_sigma).expect("set");
        })
    }

    #[test]
    fn an_unmeasured_centre_shifts_every_capture_by_the_change_times_its_allowance() {
        // 4.17 % × 3 px × 0.002 in/px = 0.00025 in, either way round; 25.4 × that in mm.
        let p = calibrated(0.0);
        let shift = unmeasured_centre_shift(&p, 0.0417, LengthUnit::Inch).expect("unmeasured");
        assert!((shift - 2.502e-4).abs() < 1e-12, "{shift}");
        let mm = unmeasured_centre_shift(&p, -0.0417, LengthUnit::Millimetre).expect("unmeasured");
        assert!((mm - 2.502e-4 * 25.4).abs() < 1e-12, "{mm}");
        let wide = params(|q| {
            *q = p.clone();
            q.set("VisionCenterUncertaintyPx", 6.0).expect("set");
        });
        assert!(
            (unmeasured_centre_shift(&wide, 0.0417, LengthUnit::Inch).expect("unmeasured") - 5.004e-4).abs() < 1e-12
        );
        assert_eq!(unmeasured_centre_shift(&calibrated(0.7), 0.0417, LengthUnit::Inch), None, "the lift measured it");
        assert_eq!(unmeasured_centre_shift(&p, 0.0, LengthUnit::Inch), None, "no change, no shift");
        assert_eq!(unmeasured_centre_shift(&Params::default(), 0.0417, LengthUnit::Inch), None, "no K yet");
    }

    #[test]
    fn the_budget_moves_only_where_an_unmeasured_scale_would_show() {
        let p = Params::default();
        // Nothing measured yet: a mark 5 px off centre is probed, one 30 px off is re-centred.
        assert_eq!(next_move(&p, 5.0, None, false), NextMove::Probe);
        assert_eq!(next_move(&p, 29.0, None, false), NextMove::Probe);
        assert_eq!(next_move(&p, 30.0, None, false), NextMove::Recentre);
        assert_eq!(next_move(&p, 5.0, None, true), NextMove::Recentre);
        // Measured to 0.07 %: 40 px stays (0.028 px ≤ 0.03 px), 50 px is re-centred.
        assert_eq!(next_move(&p, 40.0, Some(0.0007), false), NextMove::Stay);
        assert_eq!(next_move(&p, 50.0, Some(0.0007), false), NextMove::Recentre);
        assert_eq!(next_move(&p, 0.3, None, false), NextMove::Stay, "0.3 px × 6 % is within budget");
        // No probes: re-centring only; the fixed tolerance of issue 25.
        let no_probe = params(|p| p.set("VisionHeightProbePx", 0.0).expect("set"));
        assert_eq!(next_move(&no_probe, 5.0, None, false), NextMove::Recentre);
        let fixed = params(|p| p.set("VisionRecenterTolerance", 16.0).expect("set"));
        assert_eq!(next_move(&fixed, 11.0, None, false), NextMove::Stay);
        assert_eq!(next_move(&fixed, 17.0, Some(1e-6), false), NextMove::Recentre);
    }

    #[test]
    fn the_report_warns_above_the_threshold_and_cross_checks_the_mark_size() {
        let est = |e: f64| ScaleEstimate { error: e, sigma: 0.0007, marks: 4 };
        let p = Params::default();
        let r = report(&p, est(0.0004), LengthUnit::Inch, &[], "M283 C1");
        assert_eq!((r.warning.clone(), r.mark_size_pct, r.corrected), (None, None, true));
        assert!((r.change - 0.0024).abs() < 1e-12 && (r.sigma - 0.0042).abs() < 1e-12, "{r:?}");
        let r = report(&p, est(0.0417), LengthUnit::Millimetre, &[], "M283 C1");
        let w = r.warning.expect("above 1 %");
        assert!(w.contains("4.17 %") && w.contains("farther") && w.contains("6.3551 mm"), "{w}");
        assert!(w.contains("re-run M283 C1 at this height") && w.contains("were corrected"), "{w}");
        // The mark size: 0.25 in marks measured 0.24 in say +4.2 %, agreeing with +4.17 %; a
        // diameter configured wrong (0.30 in) says +25 % and disagrees.
        let sized = params(|p| p.set("VisionMarkDiameter", 0.25).expect("set"));
        let r = report(&sized, est(0.0417), LengthUnit::Inch, &[0.24, 0.24], "M283 P1");
        assert!(
            (r.mark_size_pct.expect("configured") - 4.1667).abs() < 1e-3
                && !r.warning.as_deref().unwrap_or("").contains("disagree")
        );
        // The advice names the controller's own sheet word.
        assert!(r.warning.expect("above 1 %").contains("re-run M283 P1 at this height"));
        let wrong = params(|p| p.set("VisionMarkDiameter", 0.30).expect("set"));
        let r = report(&wrong, est(0.0), LengthUnit::Inch, &[0.24], "M283 C1");
        let w = r.warning.expect("disagreement");
        assert!(w.contains("disagree") && w.contains("VisionMarkDiameter") && !w.contains("re-run"), "{w}");
        // The default profile never measured the optical centre: a warning says so only once
        // calibrated (K set), and not after a lift measured it.
        assert!(!report(&p, est(0.0417), LengthUnit::Inch, &[], "M283 C1").warning.expect("warns").contains("never"));
        let r = report(&calibrated(0.0), est(0.0417), LengthUnit::Millimetre, &[], "M283 C1");
        let w = r.warning.expect("above 1 %");
        assert!(w.contains("never measured") && w.contains("0.0064 mm") && w.contains("M283 C1 with"), "{w}");
        assert_eq!(report(&calibrated(0.0), est(0.0004), LengthUnit::Inch, &[], "M283 C1").warning, None);
        let w = report(&calibrated(0.7), est(0.0417), LengthUnit::Inch, &[], "M283 C1").warning.expect("warns");
        assert!(!w.contains("never"), "{w}");
        let off = params(|p| p.set("VisionHeightCorrection", false).expect("set"));
        assert!(report(&off, est(-0.03), LengthUnit::Inch, &[], "M283 C1")
            .warning
            .expect("warns")
            .contains("closer to the camera"));
    }
}
