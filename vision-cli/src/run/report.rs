//! What `mach-vision run` reports, built from the Vision handler's records and the simulator's
//! truth. Serialised as-is for `--json`; [`super::text`] renders it for people.

use serde::Serialize;
use vision_core::{CalReport, Machine, ParamValue, Params, Pieces};
use vision_driver_sim::{Sim, SimMachine};
use vision_math::{LengthUnit, Point2, Vector2};
use vision_mcode::{Outcome, Record};

/// The whole run.
#[derive(Debug, Serialize)]
pub(crate) struct Report {
    /// `built-in` or the world file.
    pub world: String,
    /// The world's length unit (of every `truth` length).
    pub world_unit: &'static str,
    /// Which camera answered the triggers.
    pub camera: String,
    /// The profile file, if any.
    pub profile: Option<String>,
    /// One entry per program, in order.
    pub programs: Vec<ProgramReport>,
    /// The pound-variable block after the last program.
    pub pound: PoundReport,
    /// Every telemetry parameter after the last program.
    pub telemetry: Vec<Telemetry>,
}

/// One program.
#[derive(Debug, Serialize)]
pub(crate) struct ProgramReport {
    pub program: String,
    /// `completed`, `ended by M30 at line 22`, or `failed at line 13`.
    pub outcome: String,
    /// Motion events (moves and arcs) the machine executed.
    pub moves: u64,
    /// Cycle time of the motion and dwells on the world's machine (path planner), seconds.
    pub cycle_time_s: Option<f64>,
    /// Why there is no cycle time, if there is none.
    pub cycle_note: Option<String>,
    /// Every Vision M-code, in order.
    pub steps: Vec<Step>,
    /// What the simulator knows about the calibration after the program, when it calibrated.
    pub calibration_truth: Option<CalibrationTruth>,
    /// Why the program stopped, if it failed.
    pub error: Option<String>,
}

/// One Vision M-code.
#[derive(Debug, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub(crate) enum Step {
    Begin {
        line: u32,
        mode: &'static str,
    },
    Capture {
        line: u32,
        unit: &'static str,
        commanded: [f64; 2],
        /// Centred pixels (after the centre shift, before remap and K).
        pixels: [f64; 2],
        observed: [f64; 2],
        offset: [f64; 2],
        width: f64,
        height: f64,
        angle_deg: f64,
        score: f64,
        judgment: &'static str,
        dot: Option<usize>,
        slot: Option<u32>,
        warning: Option<String>,
    },
    Fit {
        line: u32,
        unit: &'static str,
        model: &'static str,
        pieces: &'static str,
        marks: usize,
        theta_deg: f64,
        scale: [f64; 2],
        shift: [f64; 2],
        center: [f64; 2],
        /// Residual of each mark under the emitted chain, capture order.
        residuals: Vec<[f64; 2]>,
        rms: f64,
        max_residual: f64,
        gcode: Vec<String>,
        cut_error: Option<CutError>,
    },
    SheetCalibration {
        line: u32,
        unit: &'static str,
        sheet: u32,
        swap_xy: bool,
        invert_x: bool,
        invert_y: bool,
        k: [[f64; 2]; 2],
        scale: [f64; 2],
        camera_rotation_deg: f64,
        sheet_rotation_deg: f64,
        sheet_scale: [f64; 2],
        walk_rms: f64,
        tool: u32,
        offset_before: [f64; 2],
        offset_written: [f64; 2],
        verify: Vec<VerifyDot>,
        verify_rms: f64,
        verify_max: f64,
        triggers: usize,
        date: String,
    },
    QuickCalibration {
        line: u32,
        unit: &'static str,
        swap_xy: bool,
        invert_x: bool,
        invert_y: bool,
        k: [[f64; 2]; 2],
        diameter: f64,
        size_px: [f64; 2],
        size_error: f64,
        bump_error: f64,
        date: String,
    },
    Job {
        line: u32,
        job: u32,
        switched: bool,
    },
    Refused {
        line: u32,
        mcode: u32,
        message: String,
    },
}

/// One dot of the calibration's verify walk.
#[derive(Debug, Serialize)]
pub(crate) struct VerifyDot {
    pub dot: usize,
    pub nominal: [f64; 2],
    pub residual: [f64; 2],
}

/// The simulator's verdict on a fit: how far the cutter lands from the real part.
#[derive(Debug, Serialize)]
pub(crate) struct CutError {
    pub fixture: String,
    /// The tool active at the end of the program, whose point is measured.
    pub tool: u32,
    /// Grid points over the run's marks (their bounding box, 5 × 5).
    pub points: usize,
    /// Largest distance, world unit.
    pub max: f64,
}

/// The simulator's verdict on a calibration.
#[derive(Debug, Serialize)]
pub(crate) struct CalibrationTruth {
    /// `‖K − K_true‖ / ‖K_true‖`.
    pub k_relative: f64,
    /// Camera tool offset error, `unit`.
    pub offset_error: f64,
    pub unit: &'static str,
    pub remap_matches: bool,
}

/// The pound-variable block.
#[derive(Debug, Serialize)]
pub(crate) struct PoundReport {
    pub base: i64,
    /// Slots 0–4, fields 0–7 (X, Y, width, height, angle, score, reserved, reserved).
    pub slots: Vec<[f64; 8]>,
}

/// One telemetry parameter.
#[derive(Debug, Serialize)]
pub(crate) struct Telemetry {
    pub name: &'static str,
    pub value: serde_json::Value,
}

fn xy(p: Point2<f64>) -> [f64; 2] {
    [p.x, p.y]
}

fn v2(v: Vector2<f64>) -> [f64; 2] {
    [v.x, v.y]
}

fn pieces(p: Pieces) -> &'static str {
    match p {
        Pieces::All => "all",
        Pieces::Shift => "shift",
        Pieces::Rotation => "rotation",
        Pieces::Scale => "scale",
    }
}

/// RMS length of `residuals` (0 for none).
fn rms(residuals: &[Vector2<f64>]) -> f64 {
    #[allow(clippy::cast_precision_loss)] // a handful of marks
    let n = residuals.len().max(1) as f64;
    (residuals.iter().map(Vector2::norm_squared).sum::<f64>() / n).sqrt()
}

/// The steps of one program's records, with the cut error of every fit.
pub(crate) fn steps(records: &[Record], sim: &Sim, machine: &SimMachine) -> Vec<Step> {
    let mut run_marks: Vec<(Point2<f64>, LengthUnit)> = Vec::new();
    let mut out = Vec::with_capacity(records.len());
    for r in records {
        let line = r.line;
        let step = match &r.result {
            Err(e) => Step::Refused { line, mcode: r.mcode, message: e.to_string() },
            Ok(Outcome::Begin(reply)) => {
                run_marks.clear();
                Step::Begin { line, mode: reply.report.name() }
            }
            Ok(Outcome::Capture(reply)) => {
                let c = &reply.report;
                if c.dot_index.is_some() {
                    run_marks.push((c.commanded, c.unit));
                }
                Step::Capture {
                    line,
                    unit: c.unit.short_name(),
                    commanded: xy(c.commanded),
                    pixels: v2(c.centred_px),
                    observed: xy(c.observed),
                    offset: v2(c.offset),
                    width: c.width,
                    height: c.height,
                    angle_deg: c.angle_deg,
                    score: c.score,
                    judgment: c.judgment.label(),
                    dot: c.dot_index,
                    slot: c.slot,
                    warning: c.warning.clone(),
                }
            }
            Ok(Outcome::Apply(reply)) => {
                let a = &reply.report;
                Step::Fit {
                    line,
                    unit: a.unit.short_name(),
                    model: a.mode.name(),
                    pieces: pieces(a.pieces),
                    marks: a.fit.len,
                    theta_deg: a.chain.rotation_deg,
                    scale: v2(a.chain.scale),
                    shift: v2(a.chain.shift),
                    center: xy(a.chain.center),
                    residuals: a.residuals.iter().map(|r| v2(*r)).collect(),
                    rms: rms(&a.residuals),
                    max_residual: a.max_residual,
                    gcode: reply.gcode.clone(),
                    cut_error: cut_error(sim, machine, &reply.gcode, &run_marks),
                }
            }
            Ok(Outcome::Calibrate(reply)) => match &reply.report {
                CalReport::Sheet(s) => Step::SheetCalibration {
                    line,
                    unit: s.unit.short_name(),
                    sheet: s.sheet,
                    swap_xy: s.axis.remap.swap_xy,
                    invert_x: s.axis.remap.invert_x,
                    invert_y: s.axis.remap.invert_y,
                    k: [[s.k[(0, 0)], s.k[(0, 1)]], [s.k[(1, 0)], s.k[(1, 1)]]],
                    scale: v2(s.scale),
                    camera_rotation_deg: s.camera_rotation_deg,
                    sheet_rotation_deg: s.sheet_rotation_deg,
                    sheet_scale: v2(s.sheet_scale),
                    walk_rms: s.walk_rms,
                    tool: s.tool,
                    offset_before: v2(s.offset_before),
                    offset_written: v2(s.offset_written),
                    verify: s
                        .verify
                        .iter()
                        .map(|v| VerifyDot { dot: v.dot, nominal: xy(v.nominal), residual: v2(v.residual) })
                        .collect(),
                    verify_rms: s.verify_rms,
                    verify_max: s.verify_max,
                    triggers: s.triggers,
                    date: s.date.clone(),
                },
                CalReport::Quick(q) => Step::QuickCalibration {
                    line,
                    unit: q.unit.short_name(),
                    swap_xy: q.axis.remap.swap_xy,
                    invert_x: q.axis.remap.invert_x,
                    invert_y: q.axis.remap.invert_y,
                    k: [[q.k[(0, 0)], q.k[(0, 1)]], [q.k[(1, 0)], q.k[(1, 1)]]],
                    diameter: q.diameter,
                    size_px: v2(q.size_px),
                    size_error: q.size_error,
                    bump_error: q.bump_error,
                    date: q.date.clone(),
                },
            },
            Ok(Outcome::SelectJob(reply)) => Step::Job { line, job: reply.report.job, switched: reply.report.switched },
        };
        out.push(step);
    }
    out
}

/// Distance within which a commanded point counts as a fixture's nominal mark, world unit.
const SAME_MARK: f64 = 1e-3;
/// Grid points per side over the run's marks.
const GRID: u32 = 5;

/// The cut error of the alignment `gcode` over the run's marks: the fixture that carries every
/// mark of the run (at its nominal position), a 5 × 5 grid over their bounding box, the tool
/// active now. `None` when no present fixture carries the marks (nothing to compare with).
fn cut_error(
    sim: &Sim,
    machine: &SimMachine,
    gcode: &[String],
    marks: &[(Point2<f64>, LengthUnit)],
) -> Option<CutError> {
    let world = sim.world();
    let unit = world.length_unit();
    let points: Vec<Point2<f64>> = marks.iter().map(|(p, u)| p * u.factor_to(unit)).collect();
    let fixture = world.fixtures.iter().filter(|f| f.present).find(|f| {
        let nominal = f.nominal_marks(unit);
        !points.is_empty() && points.iter().all(|p| nominal.iter().any(|n| (n - p).norm() < SAME_MARK))
    })?;
    let (lo, hi) = points.iter().fold((points[0], points[0]), |(lo, hi), p| {
        (Point2::new(lo.x.min(p.x), lo.y.min(p.y)), Point2::new(hi.x.max(p.x), hi.y.max(p.y)))
    });
    let step = (hi - lo) / f64::from(GRID - 1);
    let grid: Vec<Point2<f64>> = (0..GRID)
        .flat_map(|i| (0..GRID).map(move |j| lo + Vector2::new(step.x * f64::from(i), step.y * f64::from(j))))
        .collect();
    let mut max: f64 = 0.0;
    for p in &grid {
        max = max.max(machine.cut_error(gcode, &fixture.name, *p).ok()?);
    }
    Some(CutError { fixture: fixture.name.clone(), tool: machine.active_tool(), points: grid.len(), max })
}

/// The calibration truth now (after a program that calibrated).
pub(crate) fn calibration_truth(sim: &Sim, machine: &SimMachine, params: &Params) -> Option<CalibrationTruth> {
    let unit = machine.units();
    let tool = params.camera_tool().unwrap_or_else(|| machine.active_tool());
    let offset = machine.tool_offset(tool).ok()?;
    let e = sim.calibration_error(params, offset, unit);
    Some(CalibrationTruth {
        k_relative: e.k_relative,
        offset_error: e.offset,
        unit: unit.short_name(),
        remap_matches: e.remap_matches,
    })
}

/// The pound block at `params`' base.
pub(crate) fn pound(machine: &SimMachine, params: &Params) -> PoundReport {
    let base = params.pound_var_base();
    let slots = (0..5u32)
        .map(|s| {
            std::array::from_fn(|f| {
                let at = u32::try_from(base).ok().map(|b| b + 8 * s + u32::try_from(f).unwrap_or(0));
                at.and_then(|a| machine.pound(a).ok()).unwrap_or(0.0)
            })
        })
        .collect();
    PoundReport { base, slots }
}

/// Every telemetry parameter.
pub(crate) fn telemetry(t: &vision_core::Telemetry) -> Vec<Telemetry> {
    vision_core::Telemetry::SPECS
        .iter()
        .filter_map(|s| {
            let value = match t.get(s.name)? {
                ParamValue::Bool(b) => serde_json::Value::from(b),
                ParamValue::Int(i) => serde_json::Value::from(i),
                ParamValue::Float(f) => serde_json::Value::from(f),
                ParamValue::Text(t) => serde_json::Value::from(t),
            };
            Some(Telemetry { name: s.name, value })
        })
        .collect()
}
