//! The readable form of a [`Report`].

use std::fmt::Write as _;

use super::report::{ProgramReport, Report, Step};

/// Lengths: 5 decimals (0.01 thou in inches, 10 nm in millimetres).
fn l(v: f64) -> String {
    vision_math::chain::fixed(v, 5)
}

fn xy(p: [f64; 2]) -> String {
    format!("X{} Y{}", l(p[0]), l(p[1]))
}

/// Renders the whole report.
pub(crate) fn render(r: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "mach-vision run: world {}, camera: {}", r.world, r.camera);
    if let Some(p) = &r.profile {
        let _ = writeln!(s, "profile: {p}");
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
            r.pound.base + 8 * i64::try_from(i).unwrap_or(0),
            l(slot[0]),
            l(slot[1]),
            l(slot[2]),
            l(slot[3]),
            vision_math::chain::fixed(slot[4], 3),
            vision_math::chain::fixed(slot[5], 3)
        );
    }
    let _ = writeln!(s, "\ntelemetry:");
    for t in &r.telemetry {
        let value = match &t.value {
            // Integers as they are; reals to 6 decimals (full precision is in --json).
            serde_json::Value::Number(n) if n.is_f64() => {
                n.as_f64().map_or_else(|| n.to_string(), |f| vision_math::chain::fixed(f, 6))
            }
            serde_json::Value::Number(n) => n.to_string(),
            other => other.to_string(),
        };
        let _ = writeln!(s, "  {:<22} {value}", t.name);
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
    if let Some(e) = &p.error {
        let _ = writeln!(s, "  stopped: {e}");
    }
}

#[allow(clippy::too_many_lines)] // one arm per M-code, each a few lines
fn step(s: &mut String, step: &Step, world_unit: &str) {
    match step {
        Step::Begin { line, mode } => {
            let _ = writeln!(s, "  line {line:>4}  M280  begin a {mode} run");
        }
        Step::Capture { line, unit, commanded, pixels, observed, judgment, dot, warning, .. } => {
            let which = dot.map_or_else(|| "outside a run".to_string(), |d| format!("dot {d}"));
            let _ = writeln!(
                s,
                "  line {line:>4}  M281  {which}: commanded {} -> pixels {:+.3} {:+.3} -> observed {} {unit} [{judgment}]",
                xy(*commanded),
                pixels[0],
                pixels[1],
                xy(*observed)
            );
            if let Some(w) = warning {
                let _ = writeln!(s, "              warning: {w}");
            }
        }
        Step::Fit {
            line,
            unit,
            model,
            pieces,
            marks,
            theta_deg,
            scale,
            shift,
            center,
            residuals,
            rms,
            max_residual,
            gcode,
            cut_error,
        } => {
            let _ = writeln!(s, "  line {line:>4}  M282  {model} fit of {marks} marks, {pieces} pieces emitted:");
            let _ = writeln!(
                s,
                "              rotation {theta_deg:.6} deg, scale X {:.7} Y {:.7}, shift {}, centre {} ({unit})",
                scale[0],
                scale[1],
                xy(*shift),
                xy(*center)
            );
            for (i, r) in residuals.iter().enumerate() {
                let _ = writeln!(s, "              mark {} residual {} (|r| {})", i + 1, xy(*r), l(r[0].hypot(r[1])));
            }
            let _ = writeln!(s, "              rms {} {unit}, max {} {unit}", l(*rms), l(*max_residual));
            for g in gcode {
                let _ = writeln!(s, "              | {g}");
            }
            match cut_error {
                Some(c) => {
                    let _ = writeln!(
                        s,
                        "              truth: tool T{} lands at most {} {world_unit} from the real {} ({} points)",
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
        Step::SheetCalibration {
            line,
            unit,
            sheet,
            swap_xy,
            invert_x,
            invert_y,
            k,
            scale,
            camera_rotation_deg,
            sheet_rotation_deg,
            sheet_scale,
            walk_rms,
            tool,
            offset_before,
            offset_written,
            verify,
            verify_rms,
            verify_max,
            triggers,
            date,
        } => {
            let _ = writeln!(s, "  line {line:>4}  M283  calibration sheet {sheet}: {triggers} triggers, {date}");
            let _ = writeln!(s, "              axes: SwapXY {swap_xy}, InvertX {invert_x}, InvertY {invert_y}");
            let _ = writeln!(
                s,
                "              K = [{:.8} {:.8}; {:.8} {:.8}] {unit}/px",
                k[0][0], k[0][1], k[1][0], k[1][1]
            );
            let _ = writeln!(
                s,
                "              scale X {:.8} Y {:.8} {unit}/px ({:+.3} %), camera rotation {camera_rotation_deg:.4} deg",
                scale[0],
                scale[1],
                (scale[0] / scale[1] - 1.0) * 100.0
            );
            let _ = writeln!(
                s,
                "              sheet rotation {sheet_rotation_deg:.4} deg, printed scale X {:.5} Y {:.5}, walk rms {} {unit}",
                sheet_scale[0],
                sheet_scale[1],
                l(*walk_rms)
            );
            let _ =
                writeln!(s, "              T{tool} offset {} -> {} {unit}", xy(*offset_before), xy(*offset_written));
            for v in verify {
                let _ =
                    writeln!(s, "              verify dot {} at {}: residual {}", v.dot, xy(v.nominal), xy(v.residual));
            }
            let _ = writeln!(s, "              verify rms {} {unit}, max {} {unit}", l(*verify_rms), l(*verify_max));
        }
        Step::QuickCalibration {
            line,
            unit,
            swap_xy,
            invert_x,
            invert_y,
            k,
            diameter,
            size_px,
            size_error,
            bump_error,
            date,
        } => {
            let _ = writeln!(s, "  line {line:>4}  M283  quick calibration on a {diameter} {unit} dot, {date}");
            let _ = writeln!(s, "              axes: SwapXY {swap_xy}, InvertX {invert_x}, InvertY {invert_y}");
            let _ = writeln!(
                s,
                "              dot {:.2} x {:.2} px -> K = [{:.8} {:.8}; {:.8} {:.8}] {unit}/px",
                size_px[0], size_px[1], k[0][0], k[0][1], k[1][0], k[1][1]
            );
            let _ = writeln!(
                s,
                "              confirm size error {} {unit}, bump error {} {unit}",
                l(*size_error),
                l(*bump_error)
            );
        }
        Step::Job { line, job, switched } => {
            let what = if *switched { format!("camera job {job}") } else { "camera left on its job".to_string() };
            let _ = writeln!(s, "  line {line:>4}  M284  {what}");
        }
        Step::Refused { line, mcode, message } => {
            let _ = writeln!(s, "  line {line:>4}  M{mcode}  refused: {message}");
        }
    }
}
