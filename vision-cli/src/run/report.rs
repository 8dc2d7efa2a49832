//! What `mach-vision run` reports, built from the Vision handler's records and the simulator's
//! truth. Serialised as-is for `--json`; [`super::text`] renders it for people.

use serde::Serialize;
use vision_core::{
    controller::AppliedBy, AlignReport, CalReport, Capture, JobReport, Params, PoundBlock, PoundReport, QuickReport,
    RunMode, SheetReport, Telemetry,
};
use vision_driver_sim::{Sim, SimMachine};
use vision_gcode::{Event, Rate};
use vision_math::{AlignmentChain, LengthUnit, Point2, Vector2};

use crate::Failure;
use vision_host::Record;
use vision_mcode::Outcome;

/// The whole run.
#[derive(Debug, Serialize)]
pub(crate) struct Report {
    /// The subcommand that ran the programs (`run` or `send`), for the text report's heading.
    #[serde(skip)]
    pub command: &'static str,
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
    /// Every telemetry parameter after the last program, by its manual name.
    pub telemetry: Telemetry,
    /// `send`: how the programs streamed to the controller.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub streaming: Option<crate::send::StreamingReport>,
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
    /// The time from the program's last M280 to the M282 after it, seconds (null without).
    pub alignment_time_s: Option<f64>,
    /// Why there is no alignment time although an M282 followed an M280, if so.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alignment_note: Option<String>,
    /// Every Vision M-code, in order (the first [`vision_host::MAX_RECORDS`]).
    pub steps: Vec<Step>,
    /// Vision M-codes past the first [`vision_host::MAX_RECORDS`]: ran, but not listed.
    #[serde(skip_serializing_if = "is_zero")]
    pub steps_not_listed: u64,
    /// What the simulator knows about the calibration after the program, when it calibrated.
    pub calibration_truth: Option<CalibrationTruth>,
    /// Why the program stopped, if it failed.
    pub error: Option<String>,
    /// The line whose Vision M-code was refused and stopped the program, when that refusal is
    /// the last step listed (the text report then says why once).
    #[serde(skip)]
    pub stopped_by_refusal: Option<u32>,
}

#[expect(clippy::trivially_copy_pass_by_ref, reason = "serde's `skip_serializing_if` passes a reference")]
fn is_zero(n: &u64) -> bool {
    *n == 0
}

/// One Vision M-code: the line, and the core's own report for it (flattened into the step).
#[derive(Debug, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub(crate) enum Step {
    Begin {
        line: u32,
        mode: RunMode,
    },
    Capture {
        line: u32,
        #[serde(flatten)]
        report: Capture,
    },
    Fit {
        line: u32,
        #[serde(flatten)]
        report: AlignReport,
        /// The lines M282 ran.
        gcode: Vec<String>,
        cut_error: Option<CutError>,
    },
    SheetCalibration {
        line: u32,
        #[serde(flatten)]
        report: SheetReport,
    },
    QuickCalibration {
        line: u32,
        #[serde(flatten)]
        report: QuickReport,
    },
    Job {
        line: u32,
        #[serde(flatten)]
        report: JobReport,
    },
    Refused {
        line: u32,
        mcode: u32,
        message: String,
    },
}

/// The simulator's verdict on a fit: how far the cutter lands from the real part.
#[derive(Debug, Serialize)]
pub(crate) struct CutError {
    pub fixture: String,
    /// The tool measured that lands farthest (one of `tools`).
    pub tool: u32,
    /// The tools that cut after the fit, each measured: those that made a feed move after the
    /// fit's line and before the next M280 or M282 (the tool loaded at the end of the program
    /// when none did), in the order they first cut.
    pub tools: Vec<u32>,
    /// Grid points over the run's marks (their bounding box, 5 × 5).
    pub points: usize,
    /// Largest distance over the points and the tools, world unit.
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

/// The most runs of feed moves [`Cutters`] keeps per program (a few kB); the feed moves after
/// them are not told apart.
const MAX_CUTTER_RUNS: usize = 4096;

/// One run of feed moves (G1, G2/G3, canned-cycle feeds) made with one tool, in program order.
#[derive(Debug, Clone, Copy)]
struct FeedRun {
    tool: u32,
    /// The lowest and highest source lines among the run's moves.
    first_line: u32,
    last_line: u32,
}

/// Which tools made the feed moves of a program (the tools that cut), from its events: the
/// loaded tool follows the M6 tool changes; consecutive feed moves with one tool are one run.
#[derive(Debug)]
pub(crate) struct Cutters {
    loaded: u32,
    runs: Vec<FeedRun>,
    /// A feed move came after the runs kept were full.
    overflowed: bool,
}

impl Cutters {
    /// Before a program, with `loaded` the tool loaded then.
    pub(crate) fn new(loaded: u32) -> Cutters {
        Cutters { loaded, runs: Vec::new(), overflowed: false }
    }

    /// Follows one event of the program.
    pub(crate) fn push(&mut self, event: &Event) {
        let line = match event {
            Event::ToolChange { tool, .. } => {
                self.loaded = *tool;
                return;
            }
            Event::Linear(m) if matches!(m.rate, Rate::Feed(_)) => m.line,
            Event::Arc(m) => m.line,
            _ => return,
        };
        let full = self.runs.len() >= MAX_CUTTER_RUNS;
        match self.runs.last_mut() {
            Some(run) if run.tool == self.loaded && !self.overflowed => {
                run.first_line = run.first_line.min(line);
                run.last_line = run.last_line.max(line);
            }
            _ if !full => self.runs.push(FeedRun { tool: self.loaded, first_line: line, last_line: line }),
            _ => self.overflowed = true,
        }
    }

    /// The tools of the feed moves kept after line `after` and before line `before`, each once,
    /// in the order they first cut.
    fn between(&self, after: u32, before: u32) -> Vec<u32> {
        let mut tools = Vec::new();
        for r in self.runs.iter().filter(|r| r.last_line > after && r.first_line < before) {
            if !tools.contains(&r.tool) {
                tools.push(r.tool);
            }
        }
        tools
    }
}

/// The steps of one program's records, with the cut error of every fit measured for the tools
/// that cut after it (`cutters`, from the program's events).
pub(crate) fn steps(records: &[Record], sim: &Sim, machine: &SimMachine, cutters: &Cutters) -> Vec<Step> {
    let mut run_marks: Vec<(Point2<f64>, LengthUnit)> = Vec::new();
    let mut out = Vec::with_capacity(records.len());
    for (i, r) in records.iter().enumerate() {
        let mut cut = None;
        match &r.result {
            Ok(Outcome::Begin(_)) => run_marks.clear(),
            Ok(Outcome::Capture(reply)) => {
                let c = &reply.report;
                if c.dot_index.is_some() {
                    run_marks.push((c.commanded, c.unit));
                }
            }
            Ok(Outcome::Apply(reply)) => {
                // The alignment holds until the next M280 cancels it or M282 replaces it.
                let until = records[i + 1..]
                    .iter()
                    .find(|n| matches!(n.result, Ok(Outcome::Begin(_) | Outcome::Apply(_))))
                    .map_or(u32::MAX, |n| n.line);
                let mut tools = cutters.between(r.line, until);
                if tools.is_empty() {
                    tools.push(machine.interpreter().active_tool());
                }
                let host = (reply.report.how.by == AppliedBy::Host).then_some(reply.report.chain);
                cut = cut_error(sim, machine, &reply.gcode, host, &run_marks, tools);
            }
            _ => {}
        }
        out.push(step(r, cut));
    }
    out
}

/// The step of record `r`; `cut_error` is the simulator's verdict on an M282 (known only once
/// the program has run: `None` while it streams).
pub(crate) fn step(r: &Record, cut_error: Option<CutError>) -> Step {
    let line = r.line;
    match &r.result {
        Err(e) => Step::Refused { line, mcode: r.mcode, message: e.to_string() },
        Ok(Outcome::Begin(reply)) => Step::Begin { line, mode: reply.report },
        Ok(Outcome::Capture(reply)) => Step::Capture { line, report: reply.report.clone() },
        Ok(Outcome::Apply(reply)) => {
            Step::Fit { line, report: reply.report.clone(), gcode: reply.gcode.clone(), cut_error }
        }
        Ok(Outcome::Calibrate(reply)) => match &reply.report {
            CalReport::Sheet(s) => Step::SheetCalibration { line, report: s.clone() },
            CalReport::Quick(q) => Step::QuickCalibration { line, report: q.clone() },
        },
        Ok(Outcome::SelectJob(reply)) => Step::Job { line, report: reply.report },
    }
}

/// Distance within which a commanded point counts as a fixture's nominal mark, world unit.
const SAME_MARK: f64 = 1e-3;
/// Grid points per side over the run's marks.
const GRID: u32 = 5;

/// The cut error of the alignment `gcode` (and `host`, the chain a host applies to the moves)
/// over the run's marks: the fixture that carries every
/// mark of the run (at its nominal position), a 5 × 5 grid over their bounding box, the tool
/// `tool`. `None` when no present fixture carries the marks (nothing to compare with).
fn cut_error(
    sim: &Sim,
    machine: &SimMachine,
    gcode: &[String],
    host: Option<AlignmentChain>,
    marks: &[(Point2<f64>, LengthUnit)],
    tools: Vec<u32>,
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
    let (mut worst, mut max) = (*tools.first()?, 0.0);
    for &tool in &tools {
        for p in &grid {
            let e = machine.aligned_cut_error(gcode, host, tool, &fixture.name, *p).ok()?;
            if e > max {
                (worst, max) = (tool, e);
            }
        }
    }
    Some(CutError { fixture: fixture.name.clone(), tool: worst, tools, points: grid.len(), max })
}

/// The calibration truth now (after a program that calibrated), the camera tool's table
/// offset read in `controller`'s sign (LinuxCNC's table holds the negation).
pub(crate) fn calibration_truth(
    sim: &Sim,
    machine: &SimMachine,
    params: &Params,
    controller: &dyn vision_host::Controller,
) -> Option<CalibrationTruth> {
    let interp = machine.interpreter();
    let unit = interp.units();
    let tool = params.camera_tool().unwrap_or_else(|| interp.active_tool());
    let offset = interp.tool_offset(tool)?.xy().coords * controller.tool_table_sign();
    let e = sim.calibration_error(params, offset, unit);
    Some(CalibrationTruth {
        k_relative: e.k_relative,
        offset_error: e.offset,
        unit: unit.short_name(),
        remap_matches: e.remap_matches,
    })
}

/// The pound block at `params`' base (validated when the profile was loaded).
pub(crate) fn pound(machine: &SimMachine, params: &Params) -> Result<PoundReport, Failure> {
    let block = PoundBlock::new(params.pound_var_base()).map_err(|e| Failure::Input(e.to_string()))?;
    let interp = machine.interpreter();
    Ok(block.report(|a| Some(interp.param(a))))
}

#[cfg(test)]
#[expect(clippy::cast_possible_truncation, reason = "test values are small and whole")]
mod tests {
    use super::*;
    use vision_gcode::{LinearMove, PathMode, Xyz};

    fn linear(line: u32, rate: Rate) -> Event {
        let path = PathMode::ExactStop;
        Event::Linear(LinearMove { line, start: Xyz::ZERO, end: Xyz::ZERO, rate, path })
    }

    fn tool_change(line: u32, tool: u32) -> Event {
        Event::ToolChange { line, tool, offset: Xyz::ZERO }
    }

    #[test]
    fn the_cutters_are_the_tools_of_the_feed_moves_between_the_lines() {
        let mut c = Cutters::new(1);
        for e in [
            tool_change(9, 98),
            linear(10, Rate::Feed(10.0)), // a feed with the camera, before the fit
            linear(18, Rate::Rapid),
            tool_change(20, 1),
            linear(24, Rate::Rapid),
            linear(26, Rate::Feed(20.0)),
            linear(27, Rate::Feed(60.0)),
            tool_change(28, 2),
            linear(29, Rate::Feed(20.0)),
            linear(45, Rate::Feed(20.0)), // a subprogram's line, after the main program's end
            tool_change(34, 98),          // loaded again for the closing M280: no feed follows
            linear(35, Rate::Rapid),
        ] {
            c.push(&e);
        }
        assert_eq!(c.between(19, u32::MAX), vec![1, 2], "the fit at line 19 is cut with T1 and T2");
        assert_eq!(c.between(19, 28), vec![1], "an M280 at line 28 ends the alignment");
        assert_eq!(c.between(5, 15), vec![98]);
        assert_eq!(c.between(45, u32::MAX), Vec::<u32>::new(), "no feed after line 45");
    }

    #[test]
    fn the_runs_kept_are_bounded() {
        let mut c = Cutters::new(1);
        for i in 0..(2 * MAX_CUTTER_RUNS as u32) {
            c.push(&tool_change(2 * i, i % 2 + 1));
            c.push(&linear(2 * i + 1, Rate::Feed(1.0)));
        }
        assert_eq!(c.runs.len(), MAX_CUTTER_RUNS);
        assert!(c.overflowed);
        assert_eq!(c.between(0, u32::MAX), vec![1, 2]);
        assert_eq!(c.between(u32::MAX - 1, u32::MAX), Vec::<u32>::new());
    }
}
