//! The readable form of a [`Report`].

use std::fmt::Write as _;

use vision_core::{ParamValue, Telemetry};
use vision_math::{Matrix2, Remap};

use super::report::{ProgramReport, Report, Step};

/// Lengths: 5 decimals (0.01 thou in inches, 10 nm in millimetres).
/// The working-distance change a calibration's K implies against the previous one's.
fn k_change(s: &mut String, change: Option<&vision_core::KChange>, unit: &str) {
    if let Some(c) = change {
        let _ = writeln!(
            s,
            "              working distance {:+.3} % ({:+.4} {unit}) from the previous calibration's K",
            c.change_pct, c.change
        );
    }
}

fn l(v: f64) -> String {
    vision_math::chain::fixed(v, 5)
}

/// The lens M283 measured with K, as the report's lines (without their indent): the four
/// coefficients with their 1σ, "(not measured)" for one the walk could not tell from K, how far
/// the lens moves the image's farthest corner, and the note.
fn lens_lines(lens: &vision_core::LensReport) -> Vec<String> {
    let Some(coefficients) = lens_coefficients(lens) else {
        return vec![format!("lens not measured: {}", lens.note.as_deref().unwrap_or("no lens grid was read"))];
    };
    let grid = match (lens.grid_found, lens.grid_asked) {
        (_, 0) => "no lens grid".to_string(),
        (found, asked) => format!("lens grid {found} of {asked}"),
    };
    let mut lines = vec![
        format!("lens {coefficients} (f {:.0} px)", lens.focal_px),
        format!(
            "lens moves the farthest corner {:.2} px; {} readings out to {:.0} px from the centre, rms {:.3} px, {grid}",
            lens.corner_px, lens.readings, lens.reach_px, lens.rms_px
        ),
    ];
    if let Some(note) = &lens.note {
        lines.push(format!("lens: {note}"));
    }
    lines
}

/// `k1 … ± …, k2 … ± …, p1 …, p2 …` with "(not measured)" for a coefficient the walk could not
/// tell from K; `None` when it measured none (no lens model: the report's note says why).
pub(crate) fn lens_coefficients(lens: &vision_core::LensReport) -> Option<String> {
    const NAMES: [&str; 4] = ["k1", "k2", "p1", "p2"];
    if !lens.measured.contains(&true) {
        return None;
    }
    let values = [lens.k1, lens.k2, lens.p1, lens.p2];
    let each: Vec<String> = (0..4)
        .map(|i| {
            if lens.measured[i] {
                format!("{} {} ± {}", NAMES[i], l(values[i]), l(lens.sigma[i]))
            } else {
                format!("{} (not measured)", NAMES[i])
            }
        })
        .collect();
    Some(each.join(", "))
}

/// `X… Y…` of a point or a vector.
fn xy(x: f64, y: f64) -> String {
    format!("X{} Y{}", l(x), l(y))
}

/// Renders the whole report.
pub(crate) fn render(r: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "mach-vision {}: world {}, camera: {}", r.command, r.world, r.camera);
    if let Some(p) = &r.profile {
        let _ = writeln!(s, "profile: {p}");
    }
    if let Some(t) = &r.streaming {
        let blocks = t.planner_blocks.map_or_else(String::new, |b| format!(", {b} planner blocks"));
        let _ = writeln!(
            s,
            "streamed to {} ({}, {}-byte buffer{blocks}): {} lines, {} bytes in {:.1} s; longest wait for buffer room \
             {:.0} ms; planner ran dry {} times",
            t.port, t.firmware, t.rx_buffer, t.lines_sent, t.bytes_sent, t.elapsed_s, t.longest_wait_ms, t.planner_dry
        );
    }
    for p in &r.programs {
        program(&mut s, p, r.world_unit);
    }
    let _ =
        writeln!(s, "\npound variables #{}..#{} (X, Y, width, height, angle, score):", r.pound.base, r.pound.base + 39);
    for (i, slot) in r.pound.slots.iter().enumerate() {
        let _ = writeln!(
            s,
            "  slot {i} #{:<5} {:>11} {:>11} {:>9} {:>9} {:>9} {:>7}",
            r.pound.base + 8 * u32::try_from(i).unwrap_or(0),
            l(slot[0]),
            l(slot[1]),
            l(slot[2]),
            l(slot[3]),
            vision_math::chain::fixed(slot[4], 3),
            vision_math::chain::fixed(slot[5], 3)
        );
    }
    let _ = writeln!(s, "\ntelemetry:");
    for spec in Telemetry::SPECS {
        let value = match r.telemetry.get(spec.name) {
            // Integers as they are; reals to 6 decimals (full precision is in --json).
            Some(ParamValue::Float(f)) => vision_math::chain::fixed(f, 6),
            Some(ParamValue::Int(i)) => i.to_string(),
            Some(ParamValue::Bool(b)) => b.to_string(),
            Some(ParamValue::Text(t)) => serde_json::Value::from(t).to_string(),
            None => continue,
        };
        let _ = writeln!(s, "  {:<22} {value}", spec.name);
    }
    s
}

fn program(s: &mut String, p: &ProgramReport, world_unit: &str) {
    let cycle = p.cycle_time_s.map_or_else(|| "no cycle time".to_string(), |t| format!("cycle time {t:.3} s"));
    let _ = writeln!(s, "\n== {}: {} ({} moves, {cycle})", p.program, p.outcome, p.moves);
    if let Some(note) = &p.cycle_note {
        let _ = writeln!(s, "  (cycle time: {note})");
    }
    for step in &p.steps {
        self::step(s, step, world_unit);
    }
    if p.steps_not_listed > 0 {
        let _ = writeln!(
            s,
            "  ... {} more Vision M-codes ran but are not listed (the report keeps the first {})",
            p.steps_not_listed,
            vision_host::MAX_RECORDS
        );
    }
    if let Some(t) = p.alignment_time_s {
        let _ = writeln!(s, "  alignment time (M280 to M282) {t:.3} s");
    }
    if let Some(note) = &p.alignment_note {
        let _ = writeln!(s, "  alignment time (M280 to M282): {note}");
    }
    if let Some(t) = &p.calibration_truth {
        let _ = writeln!(
            s,
            "  truth: K off by {:.4} %, camera offset off by {} {}{}",
            t.k_relative * 100.0,
            l(t.offset_error),
            t.unit,
            if t.remap_matches { "" } else { ", axis flags WRONG" }
        );
    }
    match (&p.error, p.stopped_by_refusal) {
        // The refusal's line above says why, once.
        (Some(_), Some(line)) => {
            let _ = writeln!(s, "  stopped at line {line} by the refusal above");
        }
        (Some(e), None) => {
            let _ = writeln!(s, "  stopped: {e}");
        }
        (None, _) => {}
    }
}

/// The progress line of a step as it happens: its first line in the report (a refusal without
/// its reason, which the report and the error line give).
pub(crate) fn progress_line(step: &Step, world_unit: &str) -> String {
    if let Step::Refused { line, mcode, .. } = step {
        return format!("  line {line:>4}  M{mcode}  refused");
    }
    let mut s = String::new();
    self::step(&mut s, step, world_unit);
    s.lines().next().unwrap_or_default().to_string()
}

fn step(s: &mut String, step: &Step, world_unit: &str) {
    match step {
        Step::Begin { line, mode } => {
            let _ = writeln!(s, "  line {line:>4}  M280  begin a {} run", mode.name());
        }
        Step::Capture { line, report: c } => {
            let which = c.dot_index.map_or_else(|| "outside a run".to_string(), |d| format!("dot {d}"));
            let _ = writeln!(
                s,
                "  line {line:>4}  M281  {which}: commanded {} -> pixels {:+.3} {:+.3} -> observed {} {} [{}]",
                xy(c.commanded.x, c.commanded.y),
                c.centred_px.x,
                c.centred_px.y,
                xy(c.observed.x, c.observed.y),
                c.unit.short_name(),
                c.judgment.label()
            );
            if let Some(r) = &c.recentred {
                let _ = writeln!(
                    s,
                    "              {} in {} pass{}: first seen at pixels {:+.3} {:+.3}",
                    if r.probe { "probed (scale) and kept the reading nearest the centre" } else { "re-centred" },
                    r.passes,
                    if r.passes == 1 { "" } else { "es" },
                    r.first_px.x,
                    r.first_px.y
                );
            }
            warning(s, c.warning.as_deref());
        }
        Step::Fit { line, report: a, gcode, cut_error } => {
            let unit = a.unit.short_name();
            let chain = &a.chain;
            let _ = writeln!(
                s,
                "  line {line:>4}  M282  {} fit of {} marks, {} pieces emitted:",
                a.mode.name(),
                a.fit.len,
                a.pieces.name()
            );
            let _ = writeln!(
                s,
                "              rotation {:.6} deg, scale X {:.7} Y {:.7}, shift {}, centre {} ({unit})",
                chain.rotation_deg,
                chain.scale.x,
                chain.scale.y,
                xy(chain.shift.x, chain.shift.y),
                xy(chain.center.x, chain.center.y)
            );
            if a.how.by == vision_core::controller::AppliedBy::Host {
                let _ =
                    writeln!(s, "              applied by the host: every later move mapped through it, no G-code run");
            }
            if let Some(l) = a.how.scale_left_out.as_ref().filter(|l| l.is_scaled()) {
                let _ = writeln!(
                    s,
                    "              {}: scale X {:.7} Y {:.7} left out ({:.4} % from 1)",
                    l.reason,
                    l.scale.x,
                    l.scale.y,
                    l.dev_pct()
                );
            }
            for (i, r) in a.residuals.iter().enumerate() {
                let _ =
                    writeln!(s, "              mark {} residual {} (|r| {})", i + 1, xy(r.x, r.y), l(r.x.hypot(r.y)));
            }
            let _ = writeln!(s, "              rms {} {unit}, max {} {unit}", l(a.rms), l(a.max_residual));
            if let Some(d) = &a.dropped {
                let _ = writeln!(
                    s,
                    "              mark {} left out: {} {unit} from the others' fit, over {} x the noise {} {unit}",
                    d.mark,
                    l(d.residual),
                    vision_math::chain::fixed(d.residual / d.noise, 1),
                    l(d.noise)
                );
            }
            let p = &a.predicted;
            let _ = writeln!(
                s,
                "              predicted cut error over the marks: {} {unit} (1 sigma), below {} {unit} (99 %), noise {} {unit}",
                l(p.sigma),
                l(p.bound99),
                l(p.noise)
            );
            match &a.height {
                Some(h) => {
                    let _ = writeln!(
                        s,
                        "              working distance {:+.3} % ({:+.4} {unit}) +/- {:.3} % from the calibration's, \
                         measured by {} mark{}; captures {}",
                        h.change_pct,
                        h.change,
                        h.sigma_pct,
                        h.marks,
                        if h.marks == 1 { "" } else { "s" },
                        if h.corrected { "corrected" } else { "not corrected (VisionHeightCorrection off)" }
                    );
                    if let Some(size) = h.mark_size_pct {
                        let _ = writeln!(s, "              mark size says {size:+.3} %");
                    }
                    warning(s, h.warning.as_deref());
                }
                None => {
                    let _ =
                        writeln!(s, "              working distance not measured: no M281 of the run moved the camera");
                }
            }
            for g in gcode {
                let _ = writeln!(s, "              | {g}");
            }
            match cut_error {
                Some(c) => {
                    let of = if c.tools.len() > 1 {
                        let names: Vec<String> = c.tools.iter().map(|t| format!("T{t}")).collect();
                        format!("; the farthest of {}", names.join(", "))
                    } else {
                        String::new()
                    };
                    let _ = writeln!(
                        s,
                        "              truth: tool T{} lands at most {} {world_unit} from the real {} ({} points{of})",
                        c.tool,
                        l(c.max),
                        c.fixture,
                        c.points
                    );
                }
                None => {
                    let _ = writeln!(s, "              truth: no fixture on the table carries these marks");
                }
            }
        }
        Step::SheetCalibration { line, report: r } => {
            let unit = r.unit.short_name();
            let _ = writeln!(
                s,
                "  line {line:>4}  M283  calibration sheet {}: {} triggers, {}",
                r.sheet, r.triggers, r.date
            );
            axes(s, r.axis.remap);
            let _ = writeln!(s, "              K = [{}] {unit}/px", k_text(&r.k));
            let _ = writeln!(
                s,
                "              scale X {:.8} Y {:.8} {unit}/px ({:+.3} %), camera rotation {:.4} deg",
                r.scale.x,
                r.scale.y,
                (r.scale.x / r.scale.y - 1.0) * 100.0,
                r.camera_rotation_deg
            );
            let _ = writeln!(
                s,
                "              sheet rotation {:.4} deg, printed scale X {:.5} Y {:.5}, walk rms {} {unit}",
                r.sheet_rotation_deg,
                r.sheet_scale.x,
                r.sheet_scale.y,
                l(r.walk_rms)
            );
            let (b, w) = (r.offset_before, r.offset_written);
            let _ = writeln!(s, "              T{} offset {} -> {} {unit}", r.tool, xy(b.x, b.y), xy(w.x, w.y));
            k_change(s, r.k_change.as_ref(), unit);
            let c = &r.centre;
            if c.measured {
                let _ = writeln!(
                    s,
                    "              optical centre: offset ({:.2}, {:.2}) px ± {:.2} px from a {} {unit} lift ({} pairs, \
                     working distance {} {unit})",
                    c.offset_px.x,
                    c.offset_px.y,
                    c.sigma_px,
                    l(c.lift),
                    c.pairs,
                    l(c.working_distance)
                );
            } else {
                let sigma = if c.sigma_px > 0.0 { format!(" ± {:.2} px", c.sigma_px) } else { String::new() };
                let _ = writeln!(
                    s,
                    "              optical centre not measured, offset ({:.2}, {:.2}) px{sigma} kept: {}",
                    c.offset_px.x,
                    c.offset_px.y,
                    c.note.as_deref().unwrap_or("no lift")
                );
            }
            for line in lens_lines(&r.lens) {
                let _ = writeln!(s, "              {line}");
            }
            for v in &r.verify {
                let _ = writeln!(
                    s,
                    "              verify dot {} at {}: residual {}",
                    v.dot,
                    xy(v.nominal.x, v.nominal.y),
                    xy(v.residual.x, v.residual.y)
                );
            }
            let _ = writeln!(s, "              verify rms {} {unit}, max {} {unit}", l(r.verify_rms), l(r.verify_max));
            warning(s, r.warning.as_deref());
        }
        Step::QuickCalibration { line, report: q } => {
            let unit = q.unit.short_name();
            let _ = writeln!(s, "  line {line:>4}  M283  quick calibration on a {} {unit} dot, {}", q.diameter, q.date);
            axes(s, q.axis.remap);
            let _ = writeln!(
                s,
                "              dot {:.2} x {:.2} px -> K = [{}] {unit}/px",
                q.size_px.x,
                q.size_px.y,
                k_text(&q.k)
            );
            let _ = writeln!(
                s,
                "              confirm size error {} {unit}, bump error {} {unit}",
                l(q.size_error),
                l(q.bump_error)
            );
            k_change(s, q.k_change.as_ref(), unit);
            warning(s, q.warning.as_deref());
        }
        Step::Job { line, report } => {
            let what = if report.switched {
                format!("camera job {}", report.job)
            } else {
                "camera left on its job".to_string()
            };
            let _ = writeln!(s, "  line {line:>4}  M284  {what}");
        }
        Step::Refused { line, mcode, message } => {
            let _ = writeln!(s, "  line {line:>4}  M{mcode}  refused: {message}");
        }
    }
}

/// A step's warning line, when it has one.
fn warning(s: &mut String, w: Option<&str>) {
    if let Some(w) = w {
        let _ = writeln!(s, "              warning: {w}");
    }
}

/// The axis flags line of both calibrations.
fn axes(s: &mut String, r: Remap) {
    let _ = writeln!(s, "              axes: SwapXY {}, InvertX {}, InvertY {}", r.swap_xy, r.invert_x, r.invert_y);
}

/// `K11 K12; K21 K22` to 8 decimals.
fn k_text(k: &Matrix2<f64>) -> String {
    format!("{:.8} {:.8}; {:.8} {:.8}", k[(0, 0)], k[(0, 1)], k[(1, 0)], k[(1, 1)])
}

#[cfg(test)]
mod tests {
    use super::lens_lines;
    use vision_core::LensReport;

    fn lens(measured: [bool; 4], note: Option<&str>) -> LensReport {
        LensReport {
            k1: -0.100_21,
            k2: 0.0102,
            p1: 0.002,
            p2: -0.001,
            sigma: [0.0012, 0.003, 0.000_05, 0.000_05],
            measured,
            focal_px: 2956.2,
            corner_px: 12.345,
            reach_px: 1100.4,
            rms_px: 0.0812,
            readings: 103,
            grid_found: 24,
            grid_asked: 25,
            note: note.map(str::to_string),
        }
    }

    #[test]
    fn the_lens_reads_with_its_sigmas_what_was_not_measured_and_the_note() {
        assert_eq!(
            lens_lines(&lens([true; 4], None)),
            [
                "lens k1 -0.10021 ± 0.00120, k2 0.01020 ± 0.00300, p1 0.00200 ± 0.00005, p2 -0.00100 ± 0.00005 (f 2956 px)",
                "lens moves the farthest corner 12.35 px; 103 readings out to 1100 px from the centre, rms 0.081 px, \
                 lens grid 24 of 25",
            ]
        );
        let lines = lens_lines(&lens([true, false, true, true], Some("the lens's k2 (±0.510) could not be told")));
        assert!(lines[0].starts_with("lens k1 -0.10021 ± 0.00120, k2 (not measured), p1 0.00200"), "{lines:?}");
        assert_eq!(lines[2], "lens: the lens's k2 (±0.510) could not be told");
        let none = LensReport { grid_asked: 0, ..lens([false; 4], Some("set VisionCalibrationGrid")) };
        assert_eq!(lens_lines(&none), ["lens not measured: set VisionCalibrationGrid"]);
    }
}
