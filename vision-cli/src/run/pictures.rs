//! `run --report DIR`: one SVG per fit and per sheet calibration of the run (see
//! [`crate::picture`]), built from the report the text and JSON show.

use std::path::Path;

use vision_math::LengthUnit;

use super::report::{Report, Step};
use crate::picture::{svg, LensField, MarkPair, Sheet};
use crate::Failure;

/// The pictures of `report`, each with its file name (`<program>-line<N>-fit.svg`,
/// `<program>-line<N>-calibration.svg`).
pub(crate) fn sheets(report: &Report) -> Vec<(String, Sheet)> {
    let mut out = Vec::new();
    for p in &report.programs {
        let stem =
            Path::new(&p.program).file_stem().map_or_else(|| "program".into(), |s| s.to_string_lossy().into_owned());
        let name =
            Path::new(&p.program).file_name().map_or_else(|| "program".into(), |s| s.to_string_lossy().into_owned());
        program(&mut out, &stem, &name, &p.steps, report.world_unit);
    }
    out
}

/// The pictures of one program's `steps` (`stem`, `name`: its file's), each with its file name;
/// the panel shows the last one as the program runs.
pub(crate) fn program(out: &mut Vec<(String, Sheet)>, stem: &str, name: &str, steps: &[Step], world_unit: &str) {
    // The run's captures so far: (commanded, observed), in dot order.
    let mut captures: Vec<([f64; 2], [f64; 2])> = Vec::new();
    for step in steps {
        match step {
            Step::Begin { .. } => captures.clear(),
            Step::Capture { report: c, .. } if c.dot_index.is_some() => {
                captures.push(([c.commanded.x, c.commanded.y], [c.observed.x, c.observed.y]));
            }
            Step::Fit { line, report: a, cut_error, .. } => {
                let unit = a.unit.short_name();
                let marks = captures
                    .iter()
                    .zip(&a.residuals)
                    .enumerate()
                    .map(|(i, ((commanded, observed), r))| MarkPair {
                        label: (i + 1).to_string(),
                        commanded: *commanded,
                        observed: *observed,
                        residual: [r.x, r.y],
                        dropped: a.dropped.is_some_and(|d| d.mark == i + 1),
                    })
                    .collect();
                // The simulator's truth is in the world's unit; the picture in the fit's.
                let from = if world_unit == "mm" { LengthUnit::Millimetre } else { LengthUnit::Inch };
                let truth = cut_error.as_ref().map(|c| c.max * from.factor_to(a.unit));
                let c = &a.chain;
                let mut lines = vec![
                    format!(
                        "rotation {:.4} deg, scale X {:.6} Y {:.6}, shift X{:.5} Y{:.5} {unit}",
                        c.rotation_deg, c.scale.x, c.scale.y, c.shift.x, c.shift.y
                    ),
                    format!(
                        "rms {:.5} {unit}, max {:.5} {unit}; predicted {:.5} {unit} (1σ), below {:.5} {unit} (99 %)",
                        a.rms, a.max_residual, a.predicted.sigma, a.predicted.bound99
                    ),
                ];
                if let Some(d) = &a.dropped {
                    lines.push(format!("mark {} left out: {:.5} {unit} from the others' fit", d.mark, d.residual));
                }
                if let Some(t) = truth {
                    lines.push(format!("simulator: the cutter lands at most {t:.5} {unit} from the real part"));
                }
                out.push((
                    format!("{stem}-line{line}-fit.svg"),
                    Sheet {
                        title: format!("{name}: M282 {} fit, line {line}", a.mode.name()),
                        lines,
                        unit,
                        marks,
                        outline: Vec::new(),
                        band: Some(a.predicted.bound99),
                        truth,
                        lens: None,
                    },
                ));
            }
            Step::SheetCalibration { line, report: r } => {
                let unit = r.unit.short_name();
                let marks = r
                    .verify
                    .iter()
                    .map(|v| MarkPair {
                        label: v.dot.to_string(),
                        commanded: [v.expected.x, v.expected.y],
                        observed: [v.observed.x, v.observed.y],
                        residual: [v.residual.x, v.residual.y],
                        dropped: false,
                    })
                    .collect();
                let mut lines = vec![
                    format!(
                        "K = [{:.8} {:.8}; {:.8} {:.8}] {unit}/px, camera rotation {:.4} deg",
                        r.k[(0, 0)],
                        r.k[(0, 1)],
                        r.k[(1, 0)],
                        r.k[(1, 1)],
                        r.camera_rotation_deg
                    ),
                    format!(
                        "sheet printed X {:.5} Y {:.5}; verify rms {:.5} {unit}, max {:.5} {unit}",
                        r.sheet_scale.x, r.sheet_scale.y, r.verify_rms, r.verify_max
                    ),
                ];
                // The lens in two short lines (the text report has the whole note).
                match super::text::lens_coefficients(&r.lens) {
                    Some(c) => {
                        lines.push(format!("lens {c}"));
                        let note = if r.lens.note.is_some() { "; see the report's note" } else { "" };
                        lines.push(format!(
                            "lens moves the farthest corner {:.2} px (f {:.0} px){note}",
                            r.lens.corner_px, r.lens.focal_px
                        ));
                    }
                    None => lines.push("lens not measured: see the report's note".to_string()),
                }
                out.push((
                    format!("{stem}-line{line}-calibration.svg"),
                    Sheet {
                        title: format!("{name}: M283 calibration on sheet {}, line {line}: verify re-walk", r.sheet),
                        lines,
                        unit,
                        marks,
                        outline: Vec::new(),
                        band: None,
                        truth: None,
                        lens: lens_field(&r.lens),
                    },
                ));
            }
            _ => {}
        }
    }
}

/// Writes the pictures of `report` into `dir` (created if missing); returns their paths.
pub(crate) fn write(report: &Report, dir: &Path) -> Result<Vec<std::path::PathBuf>, Failure> {
    std::fs::create_dir_all(dir)
        .map_err(|e| Failure::Input(format!("cannot create the report folder {}: {e}", dir.display())))?;
    let mut written = Vec::new();
    for (name, sheet) in &sheets(report) {
        let path = dir.join(name);
        std::fs::write(&path, svg(sheet))
            .map_err(|e| Failure::Input(format!("cannot write {}: {e}", path.display())))?;
        written.push(path);
    }
    Ok(written)
}

/// The lens a calibration measured as a 5 × 5 grid of arrows out to the farthest reading (its
/// corners there); `None` when it measured no coefficient.
fn lens_field(report: &vision_core::LensReport) -> Option<LensField> {
    let k = [report.k1, report.k2, report.p1, report.p2];
    let lens = vision_math::Lens::new(k, report.focal_px).ok()?;
    let half_px = report.reach_px / std::f64::consts::SQRT_2;
    if !(report.measured.contains(&true) && half_px > 0.0) {
        return None;
    }
    let at = |i: usize| half_px * (i as f64 / 2.0 - 1.0);
    let arrows = (0..25)
        .map(|i| {
            let c = vision_math::Vector2::new(at(i % 5), at(i / 5));
            let d = lens.distort(c) - c;
            ([c.x, c.y], [d.x, d.y])
        })
        .collect();
    Some(LensField { half_px, arrows })
}
