//! `mach-vision run`: G-code programs on the simulated machine, with the Vision module as the
//! M280–M284 handler, and a report of everything it did — and, because the simulator knows the
//! truth, how far the result is from it.

mod kept;
mod pictures;
mod report;
mod text;

use std::path::{Path, PathBuf};

use clap::Args;
use vision_core::{DriverRegistry, Params, ProfileStore, VisionModule};
use vision_driver_camera::server::{Encoding, SnapshotServer};
use vision_driver_camera::FrameSource;
use vision_driver_keyence::emulator::EmulatorHandle;
use vision_driver_sim::{ControllerName, Sim, SimMachine};
use vision_gcode::{Event, RunOutcome};
use vision_host::{fixed_clock, system_clock};
use vision_host::{ProgramHandler, Session, SimFrames};
use vision_path::{Limits, PlanConfig, Setpoints};

use crate::terminal::{is_terminal, Progress, Stream};
use crate::trace::{read_program, DialectArg};
use crate::{read_text, world, Failure};
use report::{calibration_truth, pound, steps, Cutters, ProgramReport, Report, Step};

/// Setpoint period of the cycle-time planning, seconds.
const CYCLE_PERIOD_S: f64 = 0.001;

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
    programs: Vec<PathBuf>,
    /// The simulated world (TOML); default: the built-in world.
    #[arg(long, value_name = "W.toml")]
    world: Option<PathBuf>,
    /// The Vision profile to load, and to save calibration (M283) and job changes (M284) to.
    /// A missing file starts a fresh, uncalibrated profile. Default: the profile a perfect
    /// calibration of the world would leave, not saved.
    #[arg(long, value_name = "P.toml")]
    profile: Option<PathBuf>,
    /// The camera: any registered driver's name, in any case (`sim`: the world's simulated
    /// camera, called directly; `simimage`: the frames that camera sees, rendered and searched
    /// with vision-locate; `keyence`: a Keyence VS camera over TCP, at `--ip`/`--port`, or
    /// without `--ip` an emulated VS camera on loopback backed by the world's simulated camera;
    /// `camera`: a USB, network or file camera at `--source`, or without `--source` the
    /// simulated camera's rendered frames served as HTTP snapshots on loopback).
    #[arg(long, default_value = "sim", value_name = "NAME")]
    camera: String,
    /// Keyence camera address (with `--camera keyence`).
    #[arg(long)]
    ip: Option<String>,
    /// Keyence camera port (with `--camera keyence --ip`).
    #[arg(long, default_value_t = 8500, allow_negative_numbers = true)]
    port: u16,
    /// Frame source for `--camera camera`: a V4L2 device, an `http://` snapshot URL, or an
    /// image file or folder (the profile's `VisionCameraSource` when absent is replaced, for
    /// the session only, by the loopback snapshots of the simulated camera).
    #[arg(long, value_name = "DEVICE|URL|PATH")]
    source: Option<String>,
    /// Print the report as one JSON object.
    #[arg(long)]
    json: bool,
    /// Show no progress and no list of the files `--report` wrote; errors and warnings still
    /// go to standard error. (Progress — each Vision M-code as it runs, M283's walk dot by
    /// dot — is shown on standard error when it is a terminal, or when the environment sets
    /// MACH_VISION_TERMINAL=always; never on standard output.)
    #[arg(long, short)]
    quiet: bool,
    /// Also write one SVG picture per fit and per sheet calibration into this folder
    /// (created if missing).
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
    /// The controller the simulated machine is: its G-code dialect and its rules for the Vision
    /// M-codes; default: the world's `machine.dialect`, which is mach4 (the manual's
    /// controller, as in `trace` and `plan`) unless the world says otherwise.
    #[arg(long, value_parser = DialectArg::parser(), ignore_case = true)]
    dialect: Option<DialectArg>,
    /// Run as if the clock read this many seconds after 1970-01-01 00:00 UTC (the time M283
    /// stamps its calibration with and M281 D1 names images by), so that two runs print the
    /// same report; default: the system clock.
    #[arg(long, value_name = "UNIX_SECONDS", allow_negative_numbers = true, value_parser = unix_seconds)]
    clock: Option<u64>,
}

/// `--clock`'s value: whole seconds since 1970-01-01 00:00 UTC, not before it.
fn unix_seconds(text: &str) -> Result<u64, String> {
    match text.trim().parse::<i128>() {
        Ok(s) if s < 0 => Err(format!("{s} is before 1970-01-01 00:00 UTC: give 0 or more seconds")),
        Ok(s) => u64::try_from(s).map_err(|_| format!("{s} is past the largest time, {} seconds", u64::MAX)),
        Err(_) => Err("not a whole number of seconds".to_string()),
    }
}

/// Everything a run needs, set up: the simulated machine and camera, and the Vision session
/// that runs M280–M284 on it (the path every bridge runs).
struct Runner {
    sim: Sim,
    machine: SimMachine,
    handler: ProgramHandler,
    camera: String,
    /// Keeps the loopback emulator alive for the session.
    _emulator: Option<EmulatorHandle>,
    /// Keeps the loopback snapshot server alive for the session.
    _snapshots: Option<SnapshotServer>,
}

fn set(params: &mut Params, name: &str, value: impl Into<vision_core::ParamValue>) -> Result<(), Failure> {
    params.set(name, value).map_err(|e| Failure::Input(e.to_string()))
}

impl Runner {
    fn new(args: &RunArgs, progress: Progress) -> Result<Runner, Failure> {
        let mut world = world::load(args.world.as_deref())?;
        if let Some(dialect) = args.dialect {
            world.machine.controller = ControllerName(dialect.0);
        }
        let sim = Sim::new(world).map_err(|e| Failure::Input(e.to_string()))?;
        let camera_tool = i64::from(sim.world().machine.camera_tool);
        let registry = vision_host::cameras(Some(&sim));
        let driver = camera_name(&registry, &args.camera)?;

        let mut params = match &args.profile {
            Some(path) if path.exists() => ProfileStore::new(path)
                .with_defaults(registry.params())
                .load()
                .map_err(|e| Failure::Input(e.to_string()))?,
            Some(_) => {
                let mut p = registry.params();
                set(&mut p, "VisionEnabled", true)?;
                set(&mut p, "VisionCameraToolNumber", camera_tool)?;
                p
            }
            None => sim.calibrated_params(&registry.params()).map_err(|e| Failure::Input(e.to_string()))?,
        };

        let profile_camera = match &args.profile {
            Some(path) if path.exists() => Some(ProfileCamera::of(&params)?),
            _ => None,
        };

        // The camera choices below are for this session: the profile keeps the file's (or,
        // for a new profile, the defaults), as do the settings of the CLI's own loopback
        // snapshot server.
        let mut session_only = vec!["VisionDriver", "VisionIP", "VisionPort"];
        if driver == CAMERA && args.source.is_none() {
            session_only.extend(LOOPBACK_CAMERA_SETTINGS);
        }
        let file_values = session_only
            .into_iter()
            .map(|name| params.get(name).map(|v| (name, v)).map_err(|e| Failure::Input(e.to_string())))
            .collect::<Result<Vec<_>, _>>()?;
        let mut snapshots = None;
        let (camera, emulator) = match (driver.as_str(), &args.ip) {
            ("Sim", _) => {
                set(&mut params, "VisionDriver", "Sim")?;
                ("simulated camera".to_string(), None)
            }
            (CAMERA, _) => {
                set(&mut params, "VisionDriver", CAMERA)?;
                match &args.source {
                    Some(source) => {
                        set(&mut params, "VisionCameraSource", source.as_str())?;
                        (format!("Camera driver -> {}", vision_core::text::printable_line(source, 120)), None)
                    }
                    None => {
                        let server = serve_frames(&sim, &mut params)?;
                        let text = format!(
                            "Camera driver -> HTTP snapshots at {} (the simulated camera's rendered frames)",
                            server.url("/snapshot")
                        );
                        snapshots = Some(server);
                        (text, None)
                    }
                }
            }
            (KEYENCE, Some(ip)) => {
                set(&mut params, "VisionDriver", "Keyence")?;
                set(&mut params, "VisionIP", ip.as_str())?;
                set(&mut params, "VisionPort", i64::from(args.port))?;
                (format!("Keyence VS at {ip}:{}", args.port), None)
            }
            (KEYENCE, None) => {
                let emulator = world::serve_camera(&sim, "127.0.0.1:0")
                    .map_err(|e| Failure::Input(format!("cannot start the loopback camera emulator: {e}")))?;
                set(&mut params, "VisionDriver", "Keyence")?;
                set(&mut params, "VisionIP", "127.0.0.1")?;
                set(&mut params, "VisionPort", i64::from(emulator.addr().port()))?;
                (
                    format!("Keyence driver -> emulated VS camera at {} (the simulated camera)", emulator.addr()),
                    Some(emulator),
                )
            }
            (other, _) => {
                set(&mut params, "VisionDriver", other)?;
                (format!("{other} camera"), None)
            }
        };

        // Another driver, or the profile's driver pointed at the CLI's own loopback camera.
        let other_camera = |f: &ProfileCamera| {
            !f.driver.eq_ignore_ascii_case(&driver)
                || (driver == KEYENCE && args.ip.is_none())
                || (driver == CAMERA && args.source.is_none())
        };
        if let Some(file) = profile_camera.filter(other_camera) {
            crate::terminal::show(&file.note(&camera, &args.camera));
        }

        let mut module = VisionModule::from_registry(params, &registry).map_err(|e| Failure::Input(e.to_string()))?;
        if progress.on() {
            module.set_progress_sink(Some(Box::new(|p| crate::terminal::show(&format!("              {p}")))));
        }
        if let Some(path) = &args.profile {
            let mut store = ProfileStore::new(path).with_defaults(registry.params());
            for (name, value) in file_values {
                store = store.keep(name, value);
            }
            // Found before any motion, not when M283/M284 saves after it.
            store.check_writable().map_err(|e| Failure::Input(e.to_string()))?;
            module = module.with_profile(store);
        }
        let mut machine = SimMachine::new(&sim).map_err(|e| Failure::Input(e.to_string()))?;
        if let Some(path) = &args.profile {
            kept::restore(path, &mut machine)?;
        }
        let clock = args.clock.map_or_else(system_clock, |s| fixed_clock(vision_core::Timestamp::from_unix(s, 0)));
        let handler = ProgramHandler::new(Session::new(module), sim.world().machine.controller(), clock);
        Ok(Runner { sim, machine, handler, camera, _emulator: emulator, _snapshots: snapshots })
    }

    /// The Vision module.
    fn module(&self) -> &vision_core::VisionModule {
        self.handler.session().module()
    }

    /// Runs one program (its text already read) and reports it. The moves stream into the
    /// cycle-time planner as the program makes them; only the first [`MAX_KEPT_ITEMS`] are
    /// kept, for the alignment time, so memory does not grow with the program.
    fn run(&mut self, program: &str, text: &str, progress: Progress) -> ProgramReport {
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
        };
        let world_unit = self.sim.unit().short_name();
        let mut streamed = Streamed { handler: &mut self.handler, progress, world_unit };
        let result = self.machine.run_program(text, Some(&mut streamed), &mut collect);
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
        let stopped_by_refusal = match (&result, records.last()) {
            (Err(e), Some(r)) if steps_not_listed == 0 && r.result.is_err() && r.line == e.line() => Some(r.line),
            _ => None,
        };
        let (outcome, error) = match result {
            Ok(RunOutcome::Completed { .. }) => ("completed".to_string(), None),
            Ok(RunOutcome::Ended { line, code }) => (format!("ended by M{code} at line {line}"), None),
            Err(e) => (format!("failed at line {}", e.line()), Some(e.to_string())),
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

    /// The planner's set-up for the world's machine: a 1 ms period within `machine.max_speed` /
    /// `max_accel`, from `start` (machine units).
    fn plan_config(&self, start: vision_path::Xyz) -> PlanConfig {
        let world = self.sim.world();
        let (speed, accel) = world.machine.motion_limits(world.unit);
        PlanConfig::new(Limits::uniform(accel, speed, accel), CYCLE_PERIOD_S, start)
    }
}

/// The handler a program runs with: the session's, and each Vision M-code's line of the report
/// shown as progress the moment it has run (its cut error is known only after the program).
struct Streamed<'a> {
    handler: &'a mut ProgramHandler,
    progress: Progress,
    world_unit: &'static str,
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
        result
    }
}

/// The camera a profile file names, to tell the user when `--camera` picked another.
struct ProfileCamera {
    /// `VisionDriver`.
    driver: String,
    /// The options that pick it: `--camera keyence --ip … --port …`, `--camera camera --source …`.
    options: String,
}

impl ProfileCamera {
    fn of(params: &Params) -> Result<ProfileCamera, Failure> {
        let text = |name: &str| -> Result<String, Failure> {
            let value = params.get(name).map_err(|e| Failure::Input(e.to_string()))?;
            Ok(match value {
                vision_core::ParamValue::Text(t) => t,
                other => other.to_string(),
            })
        };
        let driver = text("VisionDriver")?;
        let quoted = |v: &str| {
            let v = vision_core::text::printable_line(v, 200);
            if v.is_empty() || v.contains(char::is_whitespace) {
                format!("'{v}'")
            } else {
                v
            }
        };
        let options = if driver.eq_ignore_ascii_case(KEYENCE) {
            format!("--camera keyence --ip {} --port {}", quoted(&text("VisionIP")?), text("VisionPort")?)
        } else if driver.eq_ignore_ascii_case(CAMERA) {
            format!("--camera camera --source {}", quoted(&text("VisionCameraSource")?))
        } else {
            format!("--camera {}", quoted(&driver.to_ascii_lowercase()))
        };
        Ok(ProfileCamera { driver, options })
    }

    /// The note: which camera the run uses, and how to use the profile's.
    fn note(&self, camera: &str, option: &str) -> String {
        format!(
            "mach-vision: the profile names camera driver {}, but this run uses the {camera} (--camera {}); to use \
             the profile's camera, give {}",
            vision_core::text::printable_line(&self.driver, 64),
            vision_core::text::printable_line(option, 64),
            self.options
        )
    }
}

/// The most planner items `run` keeps per program for the alignment time (about 16 MB); the
/// items past them are planned as they stream, not kept.
const MAX_KEPT_ITEMS: usize = 100_000;

/// The first [`MAX_KEPT_ITEMS`] items of a program, and the lowest line of those not kept.
#[derive(Default)]
struct KeptItems {
    items: Vec<vision_path::Item>,
    /// The lowest source line among the items not kept, if any was not.
    lowest_dropped: Option<usize>,
}

impl KeptItems {
    fn push(&mut self, item: &vision_path::Item) {
        if self.items.len() < MAX_KEPT_ITEMS {
            self.items.push(item.clone());
        } else {
            let line = item.line();
            self.lowest_dropped = Some(self.lowest_dropped.map_or(line, |l| l.min(line)));
        }
    }

    /// Every item of the lines up to `last`, or `None` when some of them were not kept.
    fn through(&self, last: usize) -> Option<Vec<vision_path::Item>> {
        if self.lowest_dropped.is_some_and(|l| l <= last) {
            return None;
        }
        Some(self.items.iter().filter(|i| i.line() <= last).cloned().collect())
    }
}

/// The time from the last M280 that an M282 follows to that M282 (the motion, settles and
/// re-centring of the alignment), seconds: the plan up to the M282's line minus the plan before
/// the M280's. `Ok(None)` without such a pair or when the motion cannot be planned; `Err` with
/// the reason when the items before the M282 were too many to keep.
fn alignment_time(config: &PlanConfig, kept: &KeptItems, steps: &[Step]) -> Result<Option<f64>, String> {
    // The last M280 that an M282 follows, and that M282.
    let mut begin = None;
    let mut pair = None;
    for step in steps {
        match step {
            Step::Begin { line, .. } => begin = Some(*line),
            Step::Fit { line, .. } => {
                if let Some(b) = begin.take() {
                    pair = Some((b, *line));
                }
            }
            _ => {}
        }
    }
    let Some((begin, fit)) = pair else { return Ok(None) };
    let until = |last: u32| -> Result<Option<f64>, String> {
        let prefix = kept.through(last as usize).ok_or_else(|| {
            format!("not computed: the program made more than {MAX_KEPT_ITEMS} moves and other motion items, some before line {fit}'s M282")
        })?;
        Ok(plan_time(config, prefix).ok())
    };
    let (Some(to_fit), Some(before)) = (until(fit)?, until(begin.saturating_sub(1))?) else { return Ok(None) };
    Ok(Some(to_fit - before))
}

/// The time the motion (moves, dwells, calibration settles) of `items` takes, seconds.
fn plan_time(config: &PlanConfig, items: impl IntoIterator<Item = vision_path::Item>) -> Result<f64, String> {
    let stream = Setpoints::from_items(config, items).map_err(|e| e.to_string())?;
    stream.run_to_end().map(|s| s.cycle_time).map_err(|e| e.to_string())
}

/// Items sent to the planner together (one channel message).
const PLAN_BATCH: usize = 1024;

/// The cycle-time planner running beside the interpreter: the interpreter pushes events and the
/// planner pulls items, so the two meet at a bounded channel, the planner on a thread of its
/// own (a few batches in flight, never the whole program).
struct StreamedPlan {
    batch: Vec<vision_path::Item>,
    sender: Option<std::sync::mpsc::SyncSender<Vec<vision_path::Item>>>,
    /// The planner's thread, or why it could not start.
    thread: Result<std::thread::JoinHandle<Result<f64, String>>, String>,
}

impl StreamedPlan {
    fn start(config: PlanConfig) -> StreamedPlan {
        let (sender, receiver) = std::sync::mpsc::sync_channel::<Vec<vision_path::Item>>(4);
        let thread = std::thread::Builder::new()
            .name("cycle-time planner".into())
            .spawn(move || plan_time(&config, receiver.into_iter().flatten()))
            .map_err(|e| format!("the path planner could not start: {e}"));
        let sender = thread.is_ok().then_some(sender);
        StreamedPlan { batch: Vec::with_capacity(PLAN_BATCH), sender, thread }
    }

    fn push(&mut self, item: vision_path::Item) {
        self.batch.push(item);
        if self.batch.len() >= PLAN_BATCH {
            self.send();
        }
    }

    fn send(&mut self) {
        let batch = std::mem::replace(&mut self.batch, Vec::with_capacity(PLAN_BATCH));
        // A planner that stopped early (a path it cannot plan) has its answer: the rest is not
        // needed.
        if let Some(sender) = &self.sender {
            if sender.send(batch).is_err() {
                self.sender = None;
            }
        }
    }

    /// The cycle time of everything pushed, seconds, or why there is none.
    fn finish(mut self) -> Result<f64, String> {
        self.send();
        self.sender = None;
        self.thread?.join().unwrap_or_else(|_| Err("the path planner stopped unexpectedly".to_string()))
    }
}

/// The camera driver's settings [`serve_frames`] sets for the loopback snapshot server: its
/// URL (which dies with the run), timeout and flush count, and the mark settings the simulated
/// operator would set. They are the session's: a profile saved by the run keeps the file's
/// values (the defaults for a new profile).
const LOOPBACK_CAMERA_SETTINGS: [&str; 7] = [
    "VisionCameraSource",
    "VisionCameraTimeout",
    "VisionCameraFlushFrames",
    "VisionCameraSearchRadius",
    "VisionCameraMarkDiameterPx",
    "VisionCameraMark",
    "VisionCameraPolarity",
];

/// Serves the simulated camera's rendered frames as PNG snapshots on a loopback port, and
/// points the camera driver's settings at it with the mark settings the simulated operator
/// would set ([`vision_host::sim_image_config`]); no frame is flushed (each is rendered at the
/// request, so none is stale), and the timeout is 60 s (a frame is rendered at each request).
fn serve_frames(sim: &Sim, params: &mut Params) -> Result<SnapshotServer, Failure> {
    let config = vision_host::sim_image_config(sim, params).map_err(|e| Failure::Input(e.to_string()))?;
    let mark = config.mark;
    if let Some(d) = mark.diameter_px {
        set(params, "VisionCameraMarkDiameterPx", d)?;
    }
    set(params, "VisionCameraSearchRadius", mark.search_radius_pct)?;
    let kind = match mark.kind {
        vision_driver_camera::MarkKind::Dot => "dot",
        vision_driver_camera::MarkKind::Ring => "ring",
        vision_driver_camera::MarkKind::Cross => "cross",
    };
    set(params, "VisionCameraMark", kind)?;
    let polarity = if mark.polarity == vision_driver_camera::Polarity::Dark { "dark" } else { "light" };
    set(params, "VisionCameraPolarity", polarity)?;
    set(params, "VisionCameraFlushFrames", 0_i64)?;
    // Rendering a frame takes a fraction of a second in a release build, seconds in a debug one.
    set(params, "VisionCameraTimeout", 60.0)?;
    let mut frames = SimFrames(sim.clone());
    let server = SnapshotServer::bind("127.0.0.1:0", Encoding::Png, move || frames.frame().map_err(|e| e.to_string()))
        .map_err(|e| Failure::Input(format!("cannot start the loopback snapshot server: {e}")))?;
    set(params, "VisionCameraSource", server.url("/snapshot").as_str())?;
    Ok(server)
}

/// The registered name `--camera` gives (any case).
///
/// # Errors
/// [`Failure::Input`] naming the cameras there are, for a name none is registered under.
fn camera_name(registry: &DriverRegistry, camera: &str) -> Result<String, Failure> {
    registry.name(camera).map(str::to_string).ok_or_else(|| {
        Failure::Input(format!(
            "--camera {}: no such camera — the cameras are {} (any case)",
            vision_core::text::printable_line(camera, 64),
            registry.names().join(", ").to_ascii_lowercase()
        ))
    })
}

/// The report's name for the program read from standard input (`-`).
const STDIN_NAME: &str = "stdin";

/// Whether `path` is `-`, standard input.
fn is_stdin(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// Runs `mach-vision run`.
pub(crate) fn run(args: &RunArgs) -> Result<String, Failure> {
    if args.ip.is_some() && !args.camera.eq_ignore_ascii_case(KEYENCE) {
        return Err(Failure::Input("--ip needs --camera keyence".into()));
    }
    if args.source.is_some() && !args.camera.eq_ignore_ascii_case(CAMERA) {
        return Err(Failure::Input("--source needs --camera camera".into()));
    }
    if args.programs.iter().filter(|p| is_stdin(p)).count() > 1 {
        return Err(Failure::Input("- (standard input) can be given once: it holds one program".into()));
    }
    // Every program is read before anything runs: an unreadable file is bad input, not a
    // session cut off halfway with its report lost.
    let texts = args
        .programs
        .iter()
        .map(|p| if is_stdin(p) { read_program(p) } else { read_text(p, "program") })
        .collect::<Result<Vec<_>, _>>()?;
    let progress = Progress::new(args.quiet);
    // On a terminal the report above the error line already says why a refusal stopped the
    // run: the error line then only says where.
    let report_shows_refusal = !args.json && is_terminal(Stream::Stdout) && is_terminal(Stream::Stderr);
    let mut session = Runner::new(args, progress)?;
    let mut programs = Vec::with_capacity(args.programs.len());
    let mut failure = None;
    for (path, text) in args.programs.iter().zip(&texts) {
        let name = if is_stdin(path) { STDIN_NAME.to_string() } else { path.display().to_string() };
        let report = session.run(&name, text, progress);
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
    let report = Report {
        world: args.world.as_ref().map_or_else(|| "built-in".to_string(), |p| p.display().to_string()),
        world_unit: session.sim.unit().short_name(),
        camera: session.camera.clone(),
        profile: args.profile.as_ref().map(|p| p.display().to_string()),
        programs,
        pound: pound(&session.machine, params)?,
        telemetry: session.module().telemetry().clone(),
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

#[cfg(test)]
mod tests {
    use vision_path::{Item, PathMode, Rate, Segment, Shape, Xyz};

    use super::*;

    /// A tiny feed move at `line`, from x0 to x1 (inches).
    fn step(line: usize, x0: f64, x1: f64) -> Item {
        Item::Move(Segment {
            line,
            start: Xyz::new(x0, 0.0, 0.0),
            end: Xyz::new(x1, 0.0, 0.0),
            shape: Shape::Line,
            rate: Rate::Feed(60.0),
            mode: PathMode::ExactStop,
        })
    }

    #[test]
    fn kept_items_stop_at_the_bound_and_know_which_lines_are_whole() {
        let mut kept = KeptItems::default();
        // Line 1 first, then lines 2.. past the bound, then line 3 again (a loop).
        kept.push(&step(1, 0.0, 0.001));
        for i in 0..MAX_KEPT_ITEMS + 10 {
            let line = 2 + i / 1000;
            kept.push(&step(line, 0.0, 0.0));
        }
        kept.push(&step(3, 0.0, 0.0));
        assert_eq!(kept.items.len(), MAX_KEPT_ITEMS, "no more than the bound is held");
        let last_kept_line = kept.items.last().map(Item::line).expect("items");
        assert_eq!(kept.lowest_dropped, Some(3), "the loop's line 3 was dropped");
        assert_eq!(kept.through(2).map(|v| v.len()), Some(1001));
        assert!(kept.through(3).is_none());
        assert!(kept.through(last_kept_line).is_none());
    }

    #[test]
    fn the_loopback_server_sets_only_the_settings_kept_out_of_the_profile() {
        let sim = Sim::new(vision_driver_sim::World::default_world()).expect("world");
        let registry = vision_host::cameras(Some(&sim));
        let before = registry.params();
        let mut after = before.clone();
        let _server = serve_frames(&sim, &mut after).expect("served");
        let changed: Vec<&str> = after
            .config_values()
            .into_iter()
            .filter(|(name, value)| before.get(name).ok().as_ref() != Some(value))
            .map(|(name, _)| name)
            .collect();
        assert!(changed.contains(&"VisionCameraSource"), "{changed:?}");
        for name in changed {
            assert!(LOOPBACK_CAMERA_SETTINGS.contains(&name), "{name} is set for the loopback server but saved");
        }
    }

    #[test]
    fn the_streamed_plan_agrees_with_planning_the_items_whole() {
        let config = PlanConfig::new(Limits::uniform(10.0, 5.0, 10.0), CYCLE_PERIOD_S, Xyz::ZERO);
        // Over two batches, to and fro.
        let items: Vec<Item> = (0..PLAN_BATCH + 7)
            .map(|i| if i % 2 == 0 { step(i + 1, 0.0, 0.01) } else { step(i + 1, 0.01, 0.0) })
            .collect();
        let mut streamed = StreamedPlan::start(config);
        for item in &items {
            streamed.push(item.clone());
        }
        let whole = plan_time(&config, items).expect("plans");
        assert_eq!(streamed.finish(), Ok(whole));
        assert!(whole > 0.0);
    }
}
