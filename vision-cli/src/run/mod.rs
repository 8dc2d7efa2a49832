//! `mach-vision run`: G-code programs on the simulated machine, with the Vision module as the
//! M280–M284 handler, and a report of everything it did — and, because the simulator knows the
//! truth, how far the result is from it.

mod kept;
mod panel;
mod pictures;
mod report;
mod setup;
mod text;
mod timing;

use std::path::{Path, PathBuf};

use clap::Args;
use vision_driver_camera::server::SnapshotServer;
use vision_driver_keyence::emulator::EmulatorHandle;
use vision_driver_sim::{Sim, SimMachine};
use vision_gcode::{Event, RunOutcome};
use vision_host::ProgramHandler;

use crate::terminal::{is_terminal, Progress, Stream};
use crate::trace::{read_program, DialectArg};
use crate::{read_text, Failure};
use report::{calibration_truth, pound, steps, Cutters, ProgramReport, Report, Step};
pub(crate) use setup::camera_name;
use timing::{alignment_time, KeptItems, StreamedPlan};

/// The Keyence driver's registry name: the one camera `--ip`/`--port` address, and the one the
/// CLI can emulate on loopback.
const KEYENCE: &str = vision_driver_keyence::DRIVER_NAME;

/// The camera driver's registry name: any camera whose frames mach-vision searches itself;
/// `--source` gives its frames, or the CLI serves the simulated camera's rendered frames over
/// loopback HTTP.
const CAMERA: &str = vision_driver_camera::DRIVER_NAME;

/// Arguments of `mach-vision run`.
#[derive(Debug, Args)]
pub(crate) struct RunArgs {
    /// G-code programs, run in order on the same machine (tool table, profile and pound
    /// variables carry over from one to the next); `-` reads one from standard input.
    #[arg(required = true, value_name = "PROGRAM.nc")]
    pub(crate) programs: Vec<PathBuf>,
    /// The simulated world (TOML); default: the built-in world.
    #[arg(long, value_name = "W.toml")]
    pub(crate) world: Option<PathBuf>,
    /// The Vision profile to load, and to save calibration (M283) and job changes (M284) to.
    /// A missing file starts a fresh, uncalibrated profile. Default: the profile a perfect
    /// calibration of the world would leave, not saved.
    #[arg(long, value_name = "P.toml")]
    pub(crate) profile: Option<PathBuf>,
    /// The camera: any registered driver's name, in any case (`sim`: the world's simulated
    /// camera, called directly; `simimage`: the frames that camera sees, rendered and searched
    /// with vision-locate; `keyence`: a Keyence VS camera over TCP, at `--ip`/`--port`, or
    /// without `--ip` an emulated VS camera on loopback backed by the world's simulated camera;
    /// `camera`: a USB, network or file camera at `--source`, or without `--source` the
    /// simulated camera's rendered frames served as HTTP snapshots on loopback).
    #[arg(long, default_value = "sim", value_name = "NAME")]
    pub(crate) camera: String,
    /// Keyence camera address (with `--camera keyence`).
    #[arg(long)]
    pub(crate) ip: Option<String>,
    /// Keyence camera port (with `--camera keyence --ip`).
    #[arg(long, default_value_t = 8500, allow_negative_numbers = true)]
    pub(crate) port: u16,
    /// Frame source for `--camera camera`: a V4L2 device, an `http://` snapshot URL, or an
    /// image file or folder (the profile's `VisionCameraSource` when absent is replaced, for
    /// the session only, by the loopback snapshots of the simulated camera).
    #[arg(long, value_name = "DEVICE|URL|PATH")]
    pub(crate) source: Option<String>,
    /// Print the report as one JSON object.
    #[arg(long)]
    pub(crate) json: bool,
    /// Show no progress and no list of the files `--report` wrote; errors and warnings still
    /// go to standard error. (Progress — each Vision M-code as it runs, M283's walk dot by
    /// dot — is shown on standard error when it is a terminal, or when the environment sets
    /// MACH_VISION_TERMINAL=always; never on standard output.)
    #[arg(long, short)]
    pub(crate) quiet: bool,
    /// Also write one SVG picture per fit and per sheet calibration into this folder
    /// (created if missing).
    #[arg(long, value_name = "DIR")]
    pub(crate) report: Option<PathBuf>,
    /// The controller the simulated machine is: its G-code dialect and its rules for the Vision
    /// M-codes; default: the world's `machine.dialect`, which is mach4 (the manual's
    /// controller, as in `trace` and `plan`) unless the world says otherwise.
    #[arg(long, value_parser = DialectArg::parser(), ignore_case = true)]
    pub(crate) dialect: Option<DialectArg>,
    /// Run as if the clock read this many seconds after 1970-01-01 00:00 UTC (the time M283
    /// stamps its calibration with and M281 D1 names images by), so that two runs print the
    /// same report; default: the system clock.
    #[arg(long, value_name = "UNIX_SECONDS", allow_negative_numbers = true, value_parser = unix_seconds)]
    pub(crate) clock: Option<u64>,
    /// Serve the operator panel at this address while the run goes on (`127.0.0.1:0`: any
    /// free port; the address is printed on standard error as `panel at http://…`): each
    /// capture's frame and mark, each fit's picture and G-code, the calibration and telemetry,
    /// read-only. An address other than loopback needs `--panel-token`. The panel ends with
    /// the run.
    #[arg(long, value_name = "ADDRESS:PORT")]
    pub(crate) panel: Option<std::net::SocketAddr>,
    /// A secret every panel request must give (`?token=…`): 1 to 256 of A-Z a-z 0-9 - . _ ~.
    #[arg(long, value_name = "TOKEN")]
    pub(crate) panel_token: Option<String>,
}

/// `--clock`'s value: whole seconds since 1970-01-01 00:00 UTC, not before it.
fn unix_seconds(text: &str) -> Result<u64, String> {
    match text.trim().parse::<i128>() {
        Ok(s) if s < 0 => Err(format!("{s} is before 1970-01-01 00:00 UTC: give 0 or more seconds")),
        Ok(s) => u64::try_from(s).map_err(|_| format!("{s} is past the largest time, {} seconds", u64::MAX)),
        Err(_) => Err("not a whole number of seconds".to_string()),
    }
}

/// Passes the camera driver a run builds through a host's wrapper (`send`'s: the camera triggers
/// only once the controller has stopped).
pub(crate) type CameraWrap =
    Box<dyn Fn(Box<dyn vision_core::CameraDriver>) -> Box<dyn vision_core::CameraDriver> + Send + Sync>;

/// Everything a run needs, set up: the simulated machine and camera, and the Vision session
/// that runs M280–M284 on it (the path every bridge runs).
pub(crate) struct Runner {
    pub(crate) sim: Sim,
    pub(crate) machine: SimMachine,
    handler: ProgramHandler,
    camera: String,
    /// Keeps the loopback emulator alive for the session.
    _emulator: Option<EmulatorHandle>,
    /// Keeps the loopback snapshot server alive for the session.
    _snapshots: Option<SnapshotServer>,
    /// The operator panel (`--panel`).
    panel: Option<panel::RunPanel>,
}

impl Runner {
    /// The Vision module.
    fn module(&self) -> &vision_core::VisionModule {
        self.handler.session().module()
    }

    /// Runs one program (its text already read) and reports it. The moves stream into the
    /// cycle-time planner as the program makes them; only the first
    /// [`timing::MAX_KEPT_ITEMS`] are kept, for the alignment time, so memory does not grow
    /// with the program.
    fn run(&mut self, program: &str, text: &str, progress: Progress, drive: &mut dyn Drive) -> ProgramReport {
        progress.line(&format!("== {program}: running"));
        let start = self.machine.interpreter().machine_position();
        let config = self.plan_config(start);
        let mut planner = StreamedPlan::start(config);
        let mut kept = KeptItems::default();
        let mut moves = 0u64;
        let mut cutters = Cutters::new(self.machine.interpreter().active_tool());
        let mut collect = |e: &Event| {
            cutters.push(e);
            if matches!(e, Event::Linear(_) | Event::Arc(_)) {
                moves += 1;
            }
            let item = vision_path::item(e, usize::try_from(e.line()).unwrap_or(usize::MAX));
            kept.push(&item);
            planner.push(item);
            drive.event(e);
        };
        let world_unit = self.sim.unit().short_name();
        let panel = self.panel.as_ref();
        let mut streamed = Streamed { handler: &mut self.handler, progress, world_unit, panel, program };
        let result = self.machine.run_program(text, Some(&mut streamed), &mut collect);
        let stopped = drive.finish();
        let cycle = planner.finish();
        let steps_not_listed = self.handler.records_dropped();
        let records = self.handler.take_records();
        let steps = steps(&records, &self.sim, &self.machine, &cutters);
        let alignment = alignment_time(&config, &kept, &steps);
        let calibrated =
            steps.iter().any(|s| matches!(s, Step::SheetCalibration { .. } | Step::QuickCalibration { .. }));
        let calibration_truth = if calibrated {
            calibration_truth(&self.sim, &self.machine, self.module().params(), self.handler.controller())
        } else {
            None
        };
        let stopped_by_refusal = match (&result, records.last(), &stopped) {
            (Err(e), Some(r), None) if steps_not_listed == 0 && r.result.is_err() && r.line == e.line() => Some(r.line),
            _ => None,
        };
        let (outcome, error) = match (result, stopped) {
            // The machine stopped first: what the interpreter did after that never reached it.
            (_, Some(stop)) => (format!("failed at line {}", stop.line), Some(stop.message)),
            (Ok(RunOutcome::Completed { .. }), None) => ("completed".to_string(), None),
            (Ok(RunOutcome::Ended { line, code }), None) => (format!("ended by M{code} at line {line}"), None),
            (Err(e), None) => (format!("failed at line {}", e.line()), Some(e.to_string())),
        };
        ProgramReport {
            program: program.to_string(),
            outcome,
            moves,
            cycle_time_s: cycle.as_ref().ok().copied(),
            cycle_note: cycle.err(),
            alignment_time_s: alignment.as_ref().ok().copied().flatten(),
            alignment_note: alignment.err(),
            steps,
            steps_not_listed,
            calibration_truth,
            error,
            stopped_by_refusal,
        }
    }
}

/// What a program's events drive besides the cycle-time planner: nothing for `run` (the
/// simulated machine is the interpreter itself), a real controller for `send`.
pub(crate) trait Drive {
    /// One event of the program, in program order, as the interpreter makes it.
    fn event(&mut self, event: &vision_gcode::Event);

    /// After the program: waits for the machine to finish what it was given. The stop, when the
    /// machine stopped the program before its end (the interpreter ran on, but nothing after
    /// the stop reached the machine).
    fn finish(&mut self) -> Option<DriveStop>;

    /// The figures the report adds (`send`'s streaming).
    fn figures(&self) -> Option<crate::send::StreamingReport> {
        None
    }
}

/// Why the machine stopped a program.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct DriveStop {
    /// The program line the machine stopped at.
    pub line: u32,
    /// Why, for the report and the error line.
    pub message: String,
}

/// `run`'s drive: the interpreter is the machine.
struct Simulated;

impl Drive for Simulated {
    fn event(&mut self, _event: &vision_gcode::Event) {}

    fn finish(&mut self) -> Option<DriveStop> {
        None
    }
}

/// The handler a program runs with: the session's, and each Vision M-code's line of the report
/// shown as progress the moment it has run (its cut error is known only after the program).
struct Streamed<'a> {
    handler: &'a mut ProgramHandler,
    progress: Progress,
    world_unit: &'static str,
    panel: Option<&'a panel::RunPanel>,
    program: &'a str,
}

impl vision_gcode::MCodeHandler for Streamed<'_> {
    fn call(
        &mut self,
        call: &vision_gcode::UserMCode<'_>,
        ctx: &mut vision_gcode::Context<'_>,
    ) -> Result<Vec<String>, vision_gcode::HandlerError> {
        let before = self.handler.records().len();
        let result = self.handler.call(call, ctx);
        if self.progress.on() && self.handler.records().len() > before {
            if let Some(record) = self.handler.records().last() {
                self.progress.line(&text::progress_line(&report::step(record, None), self.world_unit));
            }
        }
        if let Some(panel) = self.panel {
            let module = self.handler.session().module();
            let records = self.handler.records();
            let records = if records.len() > before { records } else { &[] };
            panel.after_mcode(self.program, records, module.params(), module.telemetry(), self.world_unit);
        }
        result
    }
}

/// The report's name for the program read from standard input (`-`).
const STDIN_NAME: &str = "stdin";

/// Whether `path` is `-`, standard input.
fn is_stdin(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// Runs `mach-vision run`.
pub(crate) fn run(args: &RunArgs) -> Result<String, Failure> {
    let texts = read_programs(args)?;
    let progress = Progress::new(args.quiet);
    let mut session = Runner::new(args, progress, None)?;
    report_session(args, &mut session, &texts, &mut Simulated, progress)
}

/// Checks `args`' camera options and reads every program before anything runs: an unreadable
/// file is bad input, not a session cut off halfway with its report lost.
pub(crate) fn read_programs(args: &RunArgs) -> Result<Vec<String>, Failure> {
    if args.ip.is_some() && !args.camera.eq_ignore_ascii_case(KEYENCE) {
        return Err(Failure::Input("--ip needs --camera keyence".into()));
    }
    if args.source.is_some() && !args.camera.eq_ignore_ascii_case(CAMERA) {
        return Err(Failure::Input("--source needs --camera camera".into()));
    }
    if args.programs.iter().filter(|p| is_stdin(p)).count() > 1 {
        return Err(Failure::Input("- (standard input) can be given once: it holds one program".into()));
    }
    args.programs.iter().map(|p| if is_stdin(p) { read_program(p) } else { read_text(p, "program") }).collect()
}

/// Runs the programs `texts` (read from `args.programs`) in `session`, their events also
/// driving `drive`, and reports them as `args` ask.
pub(crate) fn report_session(
    args: &RunArgs,
    session: &mut Runner,
    texts: &[String],
    drive: &mut dyn Drive,
    progress: Progress,
) -> Result<String, Failure> {
    // On a terminal the report above the error line already says why a refusal stopped the
    // run: the error line then only says where.
    let report_shows_refusal = !args.json && is_terminal(Stream::Stdout) && is_terminal(Stream::Stderr);
    let mut programs = Vec::with_capacity(args.programs.len());
    let mut failure = None;
    for (path, text) in args.programs.iter().zip(texts) {
        let name = if is_stdin(path) { STDIN_NAME.to_string() } else { path.display().to_string() };
        let report = session.run(&name, text, progress, drive);
        if let Some(e) = &report.error {
            failure = Some(match report.stopped_by_refusal {
                Some(line) if report_shows_refusal => {
                    format!("{}: stopped at line {line} — the refusal above says why", report.program)
                }
                _ => format!("{}: {e}", report.program),
            });
        }
        programs.push(report);
        if failure.is_some() {
            break;
        }
    }
    if let Some(path) = &args.profile {
        kept::save(path, &session.machine)?;
    }
    let params = session.module().params();
    let streaming = drive.figures();
    let report = Report {
        command: if streaming.is_some() { "send" } else { "run" },
        world: args.world.as_ref().map_or_else(|| "built-in".to_string(), |p| p.display().to_string()),
        world_unit: session.sim.unit().short_name(),
        camera: session.camera.clone(),
        profile: args.profile.as_ref().map(|p| p.display().to_string()),
        programs,
        pound: pound(&session.machine, params)?,
        telemetry: session.module().telemetry().clone(),
        streaming,
    };
    if let Some(dir) = &args.report {
        // On standard error: standard output stays the report (and `--json` one object).
        let written = pictures::write(&report, dir)?;
        if written.is_empty() {
            eprintln!("mach-vision: --report {}: the run made no fit or sheet calibration to draw", dir.display());
        }
        for path in written {
            if !args.quiet {
                eprintln!("mach-vision: wrote {}", vision_core::text::printable_line(&path.display().to_string(), 400));
            }
        }
    }
    let output = if args.json {
        let mut s = serde_json::to_string_pretty(&report).map_err(|e| Failure::Input(e.to_string()))?;
        s.push('\n');
        s
    } else {
        text::render(&report)
    };
    match failure {
        None => Ok(output),
        Some(message) => Err(Failure::RunWithReport { output, message }),
    }
}
