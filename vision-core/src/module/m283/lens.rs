//! The lens: the last dot read far out in the image (the lens grid), then K, the lens and the
//! optical centre solved jointly from every reading of the walk ([`vision_math::fit_lens`];
//! `docs/calibration-solve.md`).

use vision_math::{fit_lens, LengthUnit, Lens, LensFitStart, Matrix2, Point2, Remap, Vector2, WalkReading};

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
    let pixels = grid_pixels(n, resolution(params) * 0.5 * LENS_GRID_REACH);
    walker.lifting = true;
    let mut found = 0;
    for pixel in &pixels {
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
    walker.lifting = false;
    Ok((found, pixels.len()))
}

/// Where the lens grid puts the mark, centred pixels: an `n` × `n` grid reaching `half` along
/// each axis, serpentine so each move is one grid step; none for `n` < 2 (one position says
/// nothing of the lens).
fn grid_pixels(n: usize, half: Vector2<f64>) -> Vec<Vector2<f64>> {
    if n < 2 {
        return Vec::new();
    }
    let t = |i: usize| -1.0 + 2.0 * i as f64 / (n - 1) as f64;
    (0..n)
        .flat_map(|i| (0..n).map(move |j| (i, if i % 2 == 0 { j } else { n - 1 - j })))
        .map(|(i, j)| Vector2::new(t(i) * half.x, t(j) * half.y))
        .collect()
}

/// The focal length the lens is normalised by, pixels: the working distance (the lift's
/// measured one when > 0, else the configured one, both in the unit of `pixel`) over the pixel
/// size `pixel` (units per pixel); the image's half-diagonal `res` when neither is known.
fn focal_length(measured_wd: f64, configured_wd: f64, pixel: f64, res: Vector2<f64>) -> f64 {
    let wd = if measured_wd > 0.0 { measured_wd } else { configured_wd };
    if wd > 0.0 && pixel > 0.0 {
        wd / pixel
    } else {
        res.norm() / 2.0
    }
}

/// How far `lens` moves the farthest of the image's corners (`res`, the optical centre at
/// native pixel `origin`), pixels.
fn corner_displacement(lens: &Lens, origin: Vector2<f64>, res: Vector2<f64>) -> f64 {
    [Vector2::zeros(), Vector2::new(res.x, 0.0), Vector2::new(0.0, res.y), res]
        .iter()
        .map(|c| {
            let centred = c - origin;
            (lens.undistort(centred) - centred).norm()
        })
        .fold(0.0, f64::max)
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
    let configured_wd = LengthUnit::Inch.convert(params.working_distance_in(), unit);
    let focal_px = focal_length(lifted.report.working_distance, configured_wd, k.determinant().abs().sqrt(), res);
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
    if let Err(e) = fit.lens.fitted_to_field(-fit.origin.coords, res - fit.origin.coords) {
        return linear(format!("the lens was not measured ({e}); the chain stays linear"));
    }
    let k = fit.kr * remap.matrix().transpose();
    let centre = match ratio {
        Some(_) => Some((fit.origin.coords - res * 0.5, fit.origin_sigma.x.max(fit.origin_sigma.y))),
        None => lifted.centre,
    };
    let corner = corner_displacement(&fit.lens, fit.origin.coords, res);
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
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;

    #[test]
    fn the_grid_is_serpentine_and_reaches_its_half_width() {
        let half = Vector2::new(600.0, 400.0);
        let g = grid_pixels(5, half);
        assert_eq!(g.len(), 25);
        assert_eq!((g[0], g[4], g[5], g[24]), (-half, Vector2::new(-600.0, 400.0), Vector2::new(-300.0, 400.0), half));
        assert!(g.windows(2).all(|w| (w[1] - w[0]).abs().iter().zip([300.0, 200.0]).all(|(d, s)| *d <= s + 1e-9)));
        assert!(grid_pixels(1, half).is_empty() && grid_pixels(0, half).is_empty());
        assert_eq!(grid_pixels(2, half), vec![-half, Vector2::new(-600.0, 400.0), half, Vector2::new(600.0, -400.0)]);
    }

    #[test]
    fn the_focal_length_is_the_measured_working_distance_over_the_pixel() {
        let res = Vector2::new(600.0, 800.0);
        assert!((focal_length(6.0, 10.0, 0.002, res) - 3000.0).abs() < 1e-9, "the lift's");
        assert!((focal_length(0.0, 10.0, 0.002, res) - 5000.0).abs() < 1e-9, "the configured");
        assert_eq!(focal_length(0.0, 0.0, 0.002, res), 500.0, "the half-diagonal");
        assert_eq!(focal_length(6.0, 10.0, 0.0, res), 500.0);
    }

    #[test]
    fn the_corner_displacement_is_the_farthest_corners() {
        let lens = Lens::new([-0.1, 0.0, 0.0, 0.0], 1000.0).expect("lens");
        // Centre at (100, 100) of a 400 × 300 image: the far corner (400, 300) is (300, 200)
        // out, r² = 0.13, moved by k1·r² of its length.
        let d = corner_displacement(&lens, Vector2::new(100.0, 100.0), Vector2::new(400.0, 300.0));
        let far = Vector2::new(300.0, 200.0);
        let want = (lens.undistort(far) - far).norm();
        assert!((d - want).abs() < 1e-12 && (d - 0.1 * 0.13 * far.norm()).abs() < 0.2, "{d} vs {want}");
        let none = Lens::new([0.0; 4], 1000.0).expect("lens");
        assert_eq!(corner_displacement(&none, Vector2::new(100.0, 100.0), Vector2::new(400.0, 300.0)), 0.0);
    }

    #[test]
    fn only_an_unmeasured_k1_or_a_failed_solve_warns() {
        let lens = Lens::new([-0.1, 0.0, 0.0, 0.0], 1000.0).expect("lens");
        let solved = |measured: [bool; 4], with_lens: bool| {
            let mut report = LensReport::none(1000.0, (25, 25), 80, "the note".into());
            report.measured = measured;
            Solved { k: Matrix2::identity(), centre: None, lens: with_lens.then_some((lens, [0.0; 4])), report }
        };
        assert_eq!(solved([true, false, true, true], true).warning(), None);
        assert_eq!(solved([false, true, true, true], true).warning().as_deref(), Some("the note"));
        assert_eq!(solved([true; 4], false).warning().as_deref(), Some("the note"));
    }

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
        let note = unmeasured_note([false, true, true, true], &[0.3, 0.01, 1e-4, 1e-4], 360.0, 2, (4, 4)).expect("k1");
        assert!(note.contains("raise VisionCalibrationGrid (now 2)"), "a 2 × 2 grid is a grid: {note}");
        let note = unmeasured_note([true, false, true, true], &[0.3, 0.3, 1e-4, 1e-4], 97.0, 5, (5, 25)).expect("k2");
        assert!(note.contains("only 5 of the lens grid's 25") && note.contains("VisionCameraSearchRadius"), "{note}");
    }
}
