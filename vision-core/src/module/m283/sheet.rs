//! `M283 Cn`: the sheet walk, its solve and its verify.

use vision_math::{fit_rectangle, Matrix2, PixelChain, Point2, Vector2};

use super::axis::solve_k;
use super::fail;
use super::lens::{lens_grid, solve};
use super::lift::lift_centre;
use super::report::{
    k_change, resolution_warning, CalReport, CentreReport, DotVerify, LensUpdate, SheetReport, Solution,
};
use super::walk::{Shot, Walker};
use crate::controller::{program_to_machine, rotation};
use crate::error::VisionError;
use crate::module::capture::chain_with;
use crate::module::dro::WalkProgress;
use crate::params::Params;
use crate::sheets::{cal_sheet, known_sheets};

/// Probe moves around each dot, as a fraction of the smaller field-of-view side.
pub const PROBE_FOV_FRACTION: f64 = 0.2;
/// Largest sheet print-scale error accepted, as a fraction (10 %).
pub const MAX_SHEET_SCALE_DEV: f64 = 0.10;

/// `M283 Cn`: walk, solve, verify (compensating for the offset not yet written); writes nothing.
pub(super) fn sheet_walk(walker: &mut Walker<'_>, params: &Params, n: u32, tool: u32) -> Result<Solution, VisionError> {
    let sheet = cal_sheet(n).ok_or_else(|| VisionError::UnknownSheet { sheet: n, known: known_sheets() })?;
    // The walk measures the lens afresh: until it has, its pixels go through a linear chain.
    let mut linear = params.clone();
    linear.calibration = linear.calibration.with_lens(None)?;
    let params = &linear;
    let unit = walker.unit;
    let nominal = sheet.dots(unit);
    let offset_before = crate::controller::tool_offset(&*walker.machine, tool)?;

    // 1. Axis detect: the remap and a first K from the two bumps.
    let (axis, bumps) = walker.axis_detect()?;
    let remap = axis.remap;
    let mut pairs: Vec<(usize, usize)> = bumps.to_vec();
    let (mut k, _) = solve_k(&walker.shots, &pairs, remap)?;
    walker.known = Some((k, remap));
    let res = crate::module::capture::resolution(params);
    let pixel = k.determinant().abs().sqrt();
    let probe = (PROBE_FOV_FRACTION * res.x.min(res.y) * pixel).max(axis.bump);
    let probes =
        [Vector2::new(probe, 0.0), Vector2::new(0.0, probe), Vector2::new(-probe, 0.0), Vector2::new(0.0, -probe)];

    // 2. Walk: centre each dot, probe around it, refine K as pairs accumulate.
    let d_of = |shot: &Shot, k: Matrix2<f64>| -> Result<Point2<f64>, VisionError> {
        Ok(shot.pos + chain_with(params, k, remap)?.delta(shot.native))
    };
    let mut station = d_of(&walker.shots[0], k)?;
    for (i, n_i) in nominal.iter().enumerate() {
        walker.progress(WalkProgress::SheetDot { dot: i + 1, dots: nominal.len() });
        if i > 0 {
            station += n_i - nominal[i - 1];
        }
        walker.move_to(station)?;
        let base = walker.shoot(i)?;
        for m in probes {
            walker.move_to(station + m)?;
            let s = walker.shoot(i)?;
            pairs.push((base, s));
        }
        k = solve_k(&walker.shots, &pairs, remap)?.0;
        walker.known = Some((k, remap));
        // Next station from where this dot really is.
        station = d_of(&walker.shots[base], k)?;
    }

    // 3. The final K over every pair.
    let (k, k_rms) = solve_k(&walker.shots, &pairs, remap)?;
    walker.known = Some((k, remap));

    // 3b. The lens grid and the lift over the last dot, then K, the lens and the optical
    //     centre jointly from every reading; the offset below is solved at that centre.
    let last = nominal.len() - 1;
    walker.progress(WalkProgress::Lens);
    let grid = lens_grid(walker, params, station, k * remap.matrix(), last)?;
    walker.progress(WalkProgress::Lift);
    let lifted = lift_centre(walker, params, station, probe, last)?;
    let joint = solve(walker, params, k, remap, &lifted, grid);
    let k = joint.k;
    walker.known = Some((k, remap));
    let mut solved = params.clone();
    if let Some((offset, sigma)) = joint.centre {
        solved.calibration = solved.calibration.with_centre(offset, sigma)?;
    }
    solved.calibration = solved.calibration.with_lens(joint.lens)?;
    let params = &solved;
    let chain: PixelChain = chain_with(params, k, remap)
        .map_err(|e| fail(format!("the solved K is unusable ({e}); check that the camera is rigidly mounted")))?;
    if k.determinant() <= 0.0 {
        return Err(fail("the solved K is mirrored against the axis detect — the mark moved during the walk; retry"));
    }

    // 4. Sheet pose and camera offset from the dots.
    let mut sums = vec![(Vector2::zeros(), 0.0f64); nominal.len()];
    for s in walker.shots.iter().filter(|s| s.in_fit) {
        sums[s.dot].0 += (s.pos + chain.delta(s.native)).coords;
        sums[s.dot].1 += 1.0;
    }
    let seen: Vec<Point2<f64>> = sums.iter().map(|(sum, count)| Point2::from(sum / *count)).collect();
    let fit = fit_rectangle(&nominal, &seen).map_err(|e| fail(format!("sheet fit: {e}")))?;
    let dev = (fit.transform.scale.x - 1.0).abs().max((fit.transform.scale.y - 1.0).abs());
    if dev > MAX_SHEET_SCALE_DEV {
        return Err(fail(format!(
            "the sheet measures {:.4} x {:.4} of its nominal size — wrong sheet number, a sheet printed with \
             'Fit to Page', or the camera found other marks",
            fit.transform.scale.x, fit.transform.scale.y
        )));
    }
    let b = fit.transform.offset();
    // K and the tool offset are kept along the machine axes; the walk measured in the program
    // frame, which a G5x rotation θ₀ (LinuxCNC) turns against them.
    let theta0 = walker.machine.controller().base_rotation(&*walker.machine)?;
    let offset_written = offset_before - program_to_machine(b, theta0);

    // 5. Verify: the optical axis on every dot's nominal position in G90 with the new K, seen
    //    as the new offset will see it (`docs/calibration-solve.md` explains the `+ b`).
    let mut verify = Vec::with_capacity(nominal.len());
    for (i, n_i) in nominal.iter().enumerate() {
        walker.progress(WalkProgress::Verify { dot: i + 1, dots: nominal.len() });
        walker.move_abs(n_i + b)?;
        let s = walker.shoot(i)?;
        let shot = walker.shots[s];
        let observed = shot.pos - b + chain.delta(shot.native);
        let expected = fit.transform.apply(*n_i) - b;
        verify.push(DotVerify { dot: i + 1, nominal: *n_i, expected, observed, residual: observed - expected });
    }
    let verify_rms = (verify.iter().map(|v| v.residual.norm_squared()).sum::<f64>() / verify.len() as f64).sqrt();
    let verify_max = verify.iter().map(|v| v.residual.norm()).fold(0.0, f64::max);
    let k = if theta0 == 0.0 { k } else { rotation(theta0) * k };
    let report = SheetReport {
        sheet: n,
        unit,
        axis,
        k,
        scale: Vector2::new(k.column(0).norm(), k.column(1).norm()),
        camera_rotation_deg: (k[(1, 0)] - k[(0, 1)]).atan2(k[(0, 0)] + k[(1, 1)]).to_degrees(),
        k_rms,
        sheet_rotation_deg: fit.transform.theta_deg(),
        sheet_scale: fit.transform.scale,
        walk_rms: fit.rms,
        tool,
        offset_before,
        offset_written,
        verify,
        verify_rms,
        verify_max,
        centre: CentreReport {
            offset_px: solved.calibration.center_offset(),
            sigma_px: solved.px_center_sigma_px(),
            ..lifted.report
        },
        lens: joint.report.clone(),
        k_change: k_change(params, unit, k),
        triggers: walker.triggers,
        date: walker.machine.now().iso_local(),
        warning: resolution_warning(params, &walker.shots).or(lifted.warning).or(joint.warning()),
    };
    Ok(Solution {
        k,
        remap,
        tool_offset: Some((tool, offset_written)),
        centre: joint.centre,
        lens: LensUpdate::Write(joint.lens),
        report: CalReport::Sheet(report),
    })
}
