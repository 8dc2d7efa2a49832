//! The calibration lift: the optical centre, measured by reading marks at two heights.

use vision_math::show::number;
use vision_math::{fit_centre, LengthUnit, Point2, Vector2};

use super::fail;
use super::report::CentreReport;
use super::walk::Walker;
use crate::error::VisionError;
use crate::params::Params;

/// Positions per axis of the calibration lift's grid (why 5: `docs/calibration-solve.md`).
pub const LIFT_GRID: usize = 5;

/// The lift's camera positions about `around` (program frame): a [`LIFT_GRID`]² grid `±step`
/// wide, serpentine so each move is one grid step, every position farther than `step` from
/// `around` brought in radially onto that circle.
///
/// Decision: the walk has read the mark `step` away from the image centre along each axis (its
/// probe moves), and no farther; a square grid's corners lie √2 × `step` out, where a camera
/// that searches only a disc about its centre does not find a mark. Within the circle every
/// reading lies where a probe proved the camera reads (`docs/calibration-solve.md`).
fn lift_positions(around: Point2<f64>, step: f64) -> Vec<Point2<f64>> {
    let g = LIFT_GRID;
    let t = |i: usize| -1.0 + 2.0 * i as f64 / (g - 1) as f64;
    (0..g)
        .flat_map(|i| (0..g).map(move |j| (i, if i % 2 == 0 { j } else { g - 1 - j })))
        .map(|(i, j)| {
            let v = Vector2::new(t(i), t(j));
            around + v / v.norm().max(1.0) * step
        })
        .collect()
}

/// What the calibration lift came to.
pub(super) struct Lifted {
    /// The measured `VisionPxCenterOffsetX/Y` (pixels) and 1σ (pixels), or `None` (keep both).
    pub(super) centre: Option<(Vector2<f64>, f64)>,
    pub(super) report: CentreReport,
    /// Why a lift that was asked for did not measure the centre.
    pub(super) warning: Option<String>,
    /// The lifted image scale over the calibration height's, when measured.
    pub(super) ratio: Option<f64>,
}

/// The calibration lift (`docs/calibration-solve.md`): reads the mark of dot `dot` (its centre at
/// `around`, program frame) from the camera positions [`lift_positions`] gives at the
/// calibration height, rises `VisionCalibrationLift`, reads the same positions again, comes
/// back down and fits the pixel the image shrank about.
///
/// Decision: a lift that cannot measure (the rise refused, a mark lost, a fit without a scale
/// change) does not cost the calibration: the walk commits with the centre kept and a warning.
/// Only a head that cannot come back down fails the walk (the verify walk and the commit
/// would run at the wrong height).
///
/// # Errors
/// The move back down failed.
pub(super) fn lift_centre(
    walker: &mut Walker<'_>,
    params: &Params,
    around: Point2<f64>,
    step: f64,
    dot: usize,
) -> Result<Lifted, VisionError> {
    let lift_in = params.calibration_lift_in();
    let lift = LengthUnit::Inch.convert(lift_in, walker.unit);
    // `rose`: the head went up (and came back) before the lift gave up.
    let kept = |rose: bool, note: String, warn: bool| Lifted {
        centre: None,
        report: CentreReport {
            lift: if rose { lift } else { 0.0 },
            measured: false,
            offset_px: params.calibration.center_offset(),
            sigma_px: params.px_center_sigma_px(),
            pairs: 0,
            working_distance: 0.0,
            note: Some(note.clone()),
        },
        warning: warn.then_some(note),
        ratio: None,
    };
    if lift_in == 0.0 {
        return Ok(kept(false, "VisionCalibrationLift is 0: calibrated at one height".into(), false));
    }
    let positions = lift_positions(around, step);
    walker.lifting = true;
    let read = |walker: &mut Walker<'_>, at: &[Point2<f64>]| -> Result<Vec<Point2<f64>>, VisionError> {
        let mut out = Vec::with_capacity(at.len());
        for p in at {
            walker.move_abs(*p)?;
            let s = walker.shoot(dot)?;
            out.push(walker.shots[s].native);
        }
        Ok(out)
    };
    let cannot = |what: &str, e: &VisionError| {
        // The failure's own reason: the calibration stands, so nothing but the centre "failed"
        // or was "left unchanged".
        let why = match e {
            VisionError::Calibration { reason } => reason.clone(),
            other => other.to_string(),
        };
        format!(
            "the optical centre was not measured ({what}: {why}); VisionPxCenterOffset kept — the calibration \
             stands at this height"
        )
    };
    let before = match read(walker, &positions) {
        Ok(v) => v,
        // A stepwise walk that ran out of readings: the host captures, the replay goes on.
        Err(e) if walker.needed().is_some() => {
            walker.lifting = false;
            return Err(e);
        }
        Err(e) => {
            walker.lifting = false;
            return Ok(kept(false, cannot("a reading at the calibration height failed", &e), true));
        }
    };
    let risen;
    let after = match walker.move_z(lift) {
        Err((moved, e)) => {
            risen = moved;
            Err(cannot(if moved { "the lift did not settle" } else { "the lift move was refused" }, &e))
        }
        Ok(()) => {
            risen = true;
            let back: Vec<Point2<f64>> = positions.iter().rev().copied().collect();
            read(walker, &back)
                .map(|mut v| {
                    v.reverse();
                    v
                })
                .map_err(|e| cannot("a reading at the lifted height failed", &e))
        }
    };
    walker.lifting = false;
    if walker.needed().is_some() {
        return Err(fail("a capture is needed to go on (the stepwise M283 walk)"));
    }
    if risen {
        if let Err((moved, e)) = walker.move_z(-lift) {
            return Err(if moved {
                e
            } else {
                fail(format!(
                    "the camera could not come back down from the calibration lift ({e}): it is {} {} above the \
                     calibration height — lower Z by that much before cutting, then re-run M283",
                    number(lift),
                    walker.unit.short_name()
                ))
            });
        }
    }
    let after = match after {
        Ok(v) => v,
        Err(note) => return Ok(kept(risen, note, true)),
    };
    let res = crate::module::capture::resolution(params);
    let fit = match fit_centre(&before, &after, params.camera_noise_px()) {
        Ok(fit) if fit.ratio < 1.0 => fit,
        Ok(fit) => {
            return Ok(kept(
                true,
                format!(
                    "the optical centre was not measured: the image grew ×{} as the camera rose — check that +Z \
                     moves the head up; VisionPxCenterOffset kept",
                    number(1.0 / fit.ratio)
                ),
                true,
            ))
        }
        Err(e) => return Ok(kept(true, cannot("the fit", &e.into()), true)),
    };
    let inside = (0.0..=res.x).contains(&fit.centre.x) && (0.0..=res.y).contains(&fit.centre.y);
    if !inside {
        return Ok(kept(
            true,
            format!(
                "the optical centre was not measured: the lift put it at pixel ({:.1}, {:.1}), outside the \
                 {}×{} image — check VisionCameraResX/ResY; VisionPxCenterOffset kept",
                fit.centre.x, fit.centre.y, res.x, res.y
            ),
            true,
        ));
    }
    let offset = fit.centre.coords - res * 0.5;
    let sigma = fit.sigma.x.max(fit.sigma.y);
    Ok(Lifted {
        centre: Some((offset, sigma)),
        report: CentreReport {
            lift,
            measured: true,
            offset_px: offset,
            sigma_px: sigma,
            pairs: fit.pairs,
            working_distance: lift * fit.ratio / (1.0 - fit.ratio),
            note: None,
        },
        warning: None,
        ratio: Some(fit.ratio),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lift_positions_stay_within_the_probes_reach() {
        let around = Point2::new(1.0, -2.0);
        let at = lift_positions(around, 0.5);
        assert_eq!(at.len(), LIFT_GRID * LIFT_GRID);
        assert!(at.iter().all(|p| (p - around).norm() <= 0.5 + 1e-12));
        // The axes' ends, the centre and the inner ring as the square grid has them; the
        // corners on the circle.
        let corner = Vector2::new(1.0, 1.0).normalize() * 0.5;
        for want in
            [Vector2::new(0.5, 0.0), Vector2::new(0.0, -0.5), Vector2::zeros(), Vector2::new(0.25, 0.25), corner]
        {
            assert!(at.iter().any(|p| (p - around - want).norm() < 1e-12), "{want}");
        }
        // Serpentine: no move longer than one grid step (0.25) along an axis.
        assert!(at.windows(2).all(|w| (w[1] - w[0]).amax() <= 0.25 + 1e-12));
    }
}
