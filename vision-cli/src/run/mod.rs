//! `mach-vision run`: G-code programs on the simulated machine, with the Vision module as the
//! M280–M284 handler, and a report of everything it did — and, because the simulator knows the
//! truth, how far the result is from it.

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
use vision_host::{ProgramHandler, Session, SimFrames};
use vision_mcode::system_clock;
use vision_path::{Limits, PlanConfig, Setpoints};

use crate::trace::DialectArg;
use crate::{read_text, world, Failure};
use report::{calibration_truth, pound, steps, ProgramReport, Report, Step};

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
    /// variables carry over from one to the next).
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
    #[arg(long, default_value_t = 8500)]
    port: u16,
    /// Frame source for `--camera camera`: a V4L2 device, an `http://` snapshot URL, or an
    /// image file or folder (the profile's `VisionCameraSource` when absent is replaced by the
    /// loopback snapshots of the simulated camera).
    #[arg(long, value_name = "DEVICE|URL|PATH")]
    source: Option<String>,
    /// Print the report as one JSON object.
    #[arg(long)]
    json: bool,
    /// Also write one SVG picture per fit and per sheet calibration into this folder
    /// (created if missing).
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
    /// The controller the simulated machine is (`mach4`, `linuxcnc`, `machinemotion`): its
    /// G-code dialect and its rules for the Vision M-codes; default: the world's
    /// `machine.dialect` (`mach4` unless the world says otherwise).
    #[arg(long, value_parser = DialectArg::parse)]
    dialect: Option<DialectArg>,
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
    fn new(args: &RunArgs) -> Result<Runner, Failure> {
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

        // The camera choices below are for this session: the profile keeps the file's.
        let file_connection = ["VisionDriver", "VisionIP", "VisionPort"]
            .map(|name| params.get(name).map(|v| (name, v)).map_err(|e| Failure::Input(e.to_string())));
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

        let mut module = VisionModule::from_registry(params, &registry).map_err(|e| Failure::Input(e.to_string()))?;
        if let Some(path) = &args.profile {
            let mut store = ProfileStore::new(path).with_defaults(registry.params());
            for kept in file_connection {
                let (name, value) = kept?;
                store = store.keep(name, value);
            }
            // Found before any motion, not when M283/M284 saves after it.
            store.check_writable().map_err(|e| Failure::Input(e.to_string()))?;
            module = module.with_profile(store);
        }
        let machine = SimMachine::new(&sim).map_err(|e| Failure::Input(e.to_string()))?;
        let handler = ProgramHandler::new(Session::new(module), sim.world().machine.controller(), system_clock());
        Ok(Runner { sim, machine, handler, camera, _emulator: emulator, _snapshots: snapshots })
    }

    /// The Vision module.
    fn module(&self) -> &vision_core::VisionModule {
        self.handler.session().module()
    }

    /// Runs one program (its text already read) and reports it.
    fn run(&mut self, path: &Path, text: &str) -> ProgramReport {
        let start = self.machine.interpreter().machine_position();
        let mut moves = 0u64;
        let mut items = Vec::new();
        let mut collect = |e: &Event| {
            if matches!(e, Event::Linear(_) | Event::Arc(_)) {
                moves += 1;
            }
            items.push(vision_path::item(e, usize::try_from(e.line()).unwrap_or(usize::MAX)));
        };
        let result = self.machine.run_program(text, Some(&mut self.handler), &mut collect);
        let steps_not_listed = self.handler.records_dropped();
        let records = self.handler.take_records();
        let steps = steps(&records, &self.sim, &self.machine);
        let alignment_time_s = self.alignment_time(&items, &steps, start);
        let cycle = self.cycle_time(items, start);
        let calibrated =
            steps.iter().any(|s| matches!(s, Step::SheetCalibration { .. } | Step::QuickCalibration { .. }));
        let calibration_truth =
            if calibrated { calibration_truth(&self.sim, &self.machine, self.module().params()) } else { None };
        let (outcome, error) = match result {
            Ok(RunOutcome::Completed { .. }) => ("completed".to_string(), None),
            Ok(RunOutcome::Ended { line, code }) => (format!("ended by M{code} at line {line}"), None),
            Err(e) => (format!("failed at line {}", e.line()), Some(e.to_string())),
        };
        ProgramReport {
            program: path.display().to_string(),
            outcome,
            moves,
            cycle_time_s: cycle.as_ref().ok().copied(),
            cycle_note: cycle.err(),
            alignment_time_s,
            steps,
            steps_not_listed,
            calibration_truth,
            error,
        }
    }

    /// The time from the last M280 that an M282 follows to that M282 (the motion, settles and re-centring
    /// of the alignment), seconds: the plan up to the M282's line minus the plan before the
    /// M280's. `None` without such a pair or when the motion cannot be planned.
    fn alignment_time(&self, items: &[vision_path::Item], steps: &[Step], start: vision_path::Xyz) -> Option<f64> {
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
        let (begin, fit) = pair?;
        let until = |last: u32| {
            let prefix: Vec<vision_path::Item> = items.iter().filter(|i| i.line() <= last as usize).cloned().collect();
            self.cycle_time(prefix, start).ok()
        };
        Some(until(fit)? - until(begin.saturating_sub(1))?)
    }

    /// The time the motion (moves, dwells, calibration settles) takes on the world's machine:
    /// the path planner at a 1 ms period within `machine.max_speed` / `max_accel`.
    fn cycle_time(&self, items: Vec<vision_path::Item>, start: vision_path::Xyz) -> Result<f64, String> {
        let world = self.sim.world();
        let (speed, accel) = world.machine.motion_limits(world.unit);
        let config = PlanConfig::new(Limits::uniform(accel, speed, accel), CYCLE_PERIOD_S, start);
        let stream = Setpoints::from_items(&config, items).map_err(|e| e.to_string())?;
        stream.run_to_end().map(|s| s.cycle_time).map_err(|e| e.to_string())
    }
}

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

/// Runs `mach-vision run`.
pub(crate) fn run(args: &RunArgs) -> Result<String, Failure> {
    if args.ip.is_some() && !args.camera.eq_ignore_ascii_case(KEYENCE) {
        return Err(Failure::Input("--ip needs --camera keyence".into()));
    }
    if args.source.is_some() && !args.camera.eq_ignore_ascii_case(CAMERA) {
        return Err(Failure::Input("--source needs --camera camera".into()));
    }
    // Every program is read before anything runs: an unreadable file is bad input, not a
    // session cut off halfway with its report lost.
    let texts = args.programs.iter().map(|p| read_text(p, "program")).collect::<Result<Vec<_>, _>>()?;
    let mut session = Runner::new(args)?;
    let mut programs = Vec::with_capacity(args.programs.len());
    let mut failure = None;
    for (path, text) in args.programs.iter().zip(&texts) {
        let report = session.run(path, text);
        if let Some(e) = &report.error {
            failure = Some(format!("{}: {e}", report.program));
        }
        programs.push(report);
        if failure.is_some() {
            break;
        }
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
        pictures::write(&report, dir)?;
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
