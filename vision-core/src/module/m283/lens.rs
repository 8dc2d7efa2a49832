//! The lens: the last dot read far out in the image (the lens grid), then K, the lens and the
//! optical centre solved jointly from every reading of the walk ([`vision_math::fit_lens`];
//! `docs/calibration-solve.md`).

use vision_math::{fit_lens, LengthUnit, Lens, LensFitStart, Matrix2, PixelChain, Point2, Remap, Vector2, WalkReading};

use super::lift::Lifted;
use super::report::LensReport;
use super::walk::Walker;
use crate::error::VisionError;
use crate::module::capture::resolution;
use crate::params::Params;

/// How far out the lens grid puts the mark: this share of the half-image along each axis (a
/// 250 px mark stays whole inside a 1776 px image at the corners).
pub const LENS_GRID_REACH: f64 = 0.75;

/// Reads dot `dot` (near `around`, program frame) from the `VisionCalibrationGrid`² camera
/// positions that put it on a grid reaching [`LENS_GRID_REACH`] of the half-image, through
/// `kr` (K·R, units per pixel); serpentine. A position where the camera finds no mark is
/// skipped. Returns `(found, asked)`.
///
/// # Errors
/// A move or a trigger failed (not a mark missing).
pub(super) fn lens_grid(
    walker: &mut Walker<'_>,
    params: &Params,
    around: Point2<f64>,
    kr: Matrix2<f64>,
    dot: usize,
) -> Result<(usize, usize), VisionError> {
    let n = usize::try_from(params.calibration_grid()).unwrap_or(0);
    if n < 2 {
        return Ok((0, 0));
    }
    let half = resolution(params) * 0.5 * LENS_GRID_REACH;
    let t = |i: usize| -1.0 + 2.0 * i as f64 / (n - 1) as f64;
    walker.lifting = true;
    let mut found = 0;
    for i in 0..n {
        for j in 0..n {
            let j = if i % 2 == 0 { j } else { n - 1 - j };
            let pixel = Vector2::new(t(i) * half.x, t(j) * half.y);
            let read = walker.move_abs(around - kr * pixel).and_then(|()| walker.try_shoot(dot));
            match read {
                Ok(Some(_)) => found += 1,
                Ok(None) => {}
                Err(e) => {
                    walker.lifting = false;
                    return Err(e);
                }
            }
        }
    }
    walker.lifting = false;
    Ok((found, n * n))
}

/// What the joint solve gives the walk.
pub(super) struct Solved {
    /// K, units per pixel.
    pub(super) k: Matrix2<f64>,
    /// The optical centre `VisionPxCenterOffsetX/Y` (pixels) and its 1σ (pixels), when the lift
    /// measured it; else the lift's answer (`None`: keep).
    pub(super) centre: Option<(Vector2<f64>, f64)>,
    /// The lens and its coefficients' 1σ; `None`: no lens model (the solve failed).
    pub(super) lens: Option<(Lens, [f64; 4])>,
    pub(super) report: LensReport,
}

/// Solves K, the lens and (when the lift measured it) the optical centre from every reading the
/// walk took, starting from the linear `k` and the lift's centre. A solve that cannot be made
/// keeps the linear calibration and says why in the report's note.
pub(super) fn solve(
    walker: &Walker<'_>,
    params: &Params,
    k: Matrix2<f64>,
    remap: Remap,
    lifted: &Lifted,
    grid: (usize, usize),
) -> Solved {
    let res = resolution(params);
    let unit = walker.unit;
    let readings: Vec<WalkReading> = walker
        .shots
        .iter()
        .map(|s| WalkReading { camera: s.pos, native: s.native, mark: s.dot, lifted: s.lifted })
        .collect();
    let offset = lifted.centre.map_or(params.calibration.center_offset(), |(o, _)| o);
    let ratio = lifted.centre.and(lifted.ratio);
    let measured_wd = lifted.report.working_distance;
    let wd = if measured_wd > 0.0 { measured_wd } else { LengthUnit::Inch.convert(params.working_distance_in(), unit) };
    let pixel = k.determinant().abs().sqrt();
    let focal_px = if wd > 0.0 { wd / pixel } else { res.norm() / 2.0 };
    let kr = k * remap.matrix();
    let start = LensFitStart {
        kr,
        origin: Point2::from(res * 0.5 + offset),
        ratio,
        focal_px,
        noise_px: params.camera_noise_px().max(1e-3),
    };
    let linear = |note: String| Solved {
        k,
        centre: lifted.centre,
        lens: None,
        report: LensReport::none(focal_px, grid, readings.len(), note),
    };
    let fit = match fit_lens(&readings, &start) {
        Ok(fit) => fit,
        Err(e) => return linear(format!("the lens was not measured ({e}); the chain stays linear")),
    };
    // A lens the chain cannot undo over the image is not written.
    let chain = PixelChain::new(fit.kr, Remap::IDENTITY, res, fit.origin.coords - res * 0.5);
    if let Err(e) = chain.and_then(|c| c.with_lens(fit.lens)) {
        return linear(format!("the lens was not measured ({e}); the chain stays linear"));
    }
    let k = fit.kr * remap.matrix().transpose();
    let centre = match ratio {
        Some(_) => Some((fit.origin.coords - res * 0.5, fit.origin_sigma.x.max(fit.origin_sigma.y))),
        None => lifted.centre,
    };
    let corner = [Vector2::zeros(), Vector2::new(res.x, 0.0), Vector2::new(0.0, res.y), res]
        .iter()
        .map(|c| {
            let centred = c - fit.origin.coords;
            (fit.lens.undistort(centred) - centred).norm()
        })
        .fold(0.0, f64::max);
    let note = unmeasured_note(fit.measured, &fit.sigma, fit.reach_px, params.calibration_grid(), grid);
    let report = LensReport {
        k1: fit.lens.coefficients()[0],
        k2: fit.lens.coefficients()[1],
        p1: fit.lens.coefficients()[2],
        p2: fit.lens.coefficients()[3],
        sigma: fit.sigma,
        measured: fit.measured,
        focal_px,
        corner_px: corner,
        reach_px: fit.reach_px,
        rms_px: fit.rms_px,
        readings: readings.len(),
        grid_found: grid.0,
        grid_asked: grid.1,
        note,
    };
    Solved { k, centre, lens: Some((fit.lens, fit.sigma)), report }
}

impl Solved {
    /// The calibration's warning from the lens: its note when the solve failed or `k1`, the
    /// term that reaches nearest the centre, was not measured; the others' note stays in the
    /// report (they move only readings far out, and M282 widens those by their σ).
    pub(super) fn warning(&self) -> Option<String> {
        let k1_missing = self.lens.is_none() || !self.report.measured[0];
        self.report.note.clone().filter(|_| k1_missing)
    }
}

/// What to say when the walk could not separate a coefficient from K (its σ near its prior's):
/// which ones, how far out the readings reached, and how to read farther.
fn unmeasured_note(
    measured: [bool; 4],
    sigma: &[f64; 4],
    reach_px: f64,
    grid: i64,
    (found, asked): (usize, usize),
) -> Option<String> {
    const NAMES: [&str; 4] = ["k1", "k2", "p1", "p2"];
    let missing: Vec<String> =
        (0..4).filter(|i| !measured[*i]).map(|i| format!("{} (±{:.3})", NAMES[i], sigma[i])).collect();
    if missing.is_empty() {
        return None;
    }
    let how = if grid < 2 {
        format!("set VisionCalibrationGrid (now {grid}) to 5 or more so the walk reads the mark near the image's edges")
    } else if found < asked {
        format!(
            "the camera found the mark at only {found} of the lens grid's {asked} positions: widen its search \
             (VisionCameraSearchRadius for the Camera driver, the job's search window on a Keyence) so it reads \
             out to three quarters of the way to the image's edges"
        )
    } else {
        format!(
            "raise VisionCalibrationGrid (now {grid}), and check that the camera finds the mark out to three \
             quarters of the way to the image's edges"
        )
    };
    Some(format!(
        "the lens's {} could not be told from K (the walk's readings reached {reach_px:.0} px from the optical \
         centre): kept near 0 with that 1σ, which M282 adds to captures far from the centre — {how}",
        missing.join(", ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_note_names_what_was_not_measured_and_how_to_measure_it() {
        let all = [true; 4];
        assert_eq!(unmeasured_note(all, &[0.01; 4], 900.0, 5, (25, 25)), None);
        let note = unmeasured_note([true, false, true, true], &[0.003, 0.4, 1e-4, 1e-4], 360.0, 0, (0, 0))
            .expect("k2 missing");
        assert!(note.contains("k2 (±0.400)") && !note.contains("k1") && note.contains("360 px"), "{note}");
        assert!(note.contains("set VisionCalibrationGrid (now 0) to 5"), "{note}");
        let note =
            unmeasured_note([false, true, true, true], &[0.3, 0.01, 1e-4, 1e-4], 360.0, 5, (25, 25)).expect("k1");
        assert!(note.contains("raise VisionCalibrationGrid (now 5)"), "{note}");
        let note = unmeasured_note([true, false, true, true], &[0.3, 0.3, 1e-4, 1e-4], 97.0, 5, (5, 25)).expect("k2");
        assert!(note.contains("only 5 of the lens grid's 25") && note.contains("VisionCameraSearchRadius"), "{note}");
    }
}
