//! `mach-vision send`: a program run in the host's interpreter and streamed to a Grbl-family
//! controller, with the Vision M-codes run by the host and M282's alignment applied to the moves
//! sent ([`vision_core::controller::Grbl`]).
//!
//! The firmware's work offset is left as it was found: the host mirrors the controller's G54–G59,
//! G92 and G28/G30 into its interpreter, runs the program there (work systems, G92 and tool
//! offsets included) and sends every move as absolute coordinates of the work system that was
//! active, so nothing is written to EEPROM for a job.

mod interrupt;
mod link;
mod mirror;

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use clap::Args;
use serde::Serialize;
use vision_grbl::stream::{Sender, SenderOptions};

use crate::run::{read_programs, report_session, RunArgs, Runner};
use crate::terminal::Progress;
use crate::trace::DialectArg;
use crate::Failure;
use link::Shared;

/// Arguments of `mach-vision send`.
#[derive(Debug, Args)]
pub(crate) struct SendArgs {
    /// G-code programs, run in order (as `run` runs them) and streamed to the controller; `-`
    /// reads one from standard input.
    #[arg(required = true, value_name = "PROGRAM.nc")]
    programs: Vec<PathBuf>,
    /// The controller: a serial device (`/dev/ttyACM0`, `COM3`) or `tcp://HOST:PORT`.
    #[arg(long, value_name = "DEVICE|tcp://HOST:PORT")]
    port: String,
    /// Serial baud rate.
    #[arg(long, default_value_t = 115_200)]
    baud: u32,
    /// The camera, as in `run` (`sim`, `simimage`: the simulated world's camera, looking where the
    /// controller reports the machine; `keyence`; `camera` with `--source`).
    #[arg(long, default_value = "sim", value_name = "NAME")]
    camera: String,
    /// Keyence camera address (with `--camera keyence`).
    #[arg(long)]
    ip: Option<String>,
    /// Keyence camera port (with `--camera keyence --ip`).
    #[arg(long, default_value_t = 8500)]
    camera_port: u16,
    /// Frame source for `--camera camera`, as in `run`.
    #[arg(long, value_name = "DEVICE|URL|PATH")]
    source: Option<String>,
    /// The simulated world (TOML): the simulated camera's, and the host's tool table; default:
    /// the built-in world.
    #[arg(long, value_name = "W.toml")]
    world: Option<PathBuf>,
    /// The Vision profile, as in `run` (its tool table is kept beside it).
    #[arg(long, value_name = "P.toml")]
    profile: Option<PathBuf>,
    /// Print the report as one JSON object.
    #[arg(long)]
    json: bool,
    /// No progress on standard error.
    #[arg(long, short)]
    quiet: bool,
    /// Also write one SVG picture per fit and sheet calibration into this folder.
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
    /// Run as if the clock read this many seconds after 1970-01-01 00:00 UTC, as in `run`.
    #[arg(long, value_name = "UNIX_SECONDS")]
    clock: Option<u64>,
}

impl SendArgs {
    /// The same session `run` would set up, with a Grbl controller.
    fn run_args(&self) -> RunArgs {
        RunArgs {
            programs: self.programs.clone(),
            world: self.world.clone(),
            profile: self.profile.clone(),
            camera: self.camera.clone(),
            ip: self.ip.clone(),
            port: self.camera_port,
            source: self.source.clone(),
            json: self.json,
            quiet: self.quiet,
            report: self.report.clone(),
            dialect: Some(DialectArg(&vision_core::controller::Grbl)),
            clock: self.clock,
            panel: None,
            panel_token: None,
        }
    }
}

/// How the programs streamed (the report's `streaming`).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub(crate) struct StreamingReport {
    /// The controller's port as given.
    pub port: String,
    /// `Grbl` or `grblHAL`.
    pub firmware: &'static str,
    /// The receive buffer the lines were counted into (bytes).
    pub rx_buffer: usize,
    /// Planner blocks, as `$I` reported them.
    pub planner_blocks: Option<u32>,
    /// Lines sent.
    pub lines_sent: usize,
    /// Bytes sent, line ends included.
    pub bytes_sent: usize,
    /// The longest a line waited for room in the receive buffer, milliseconds.
    pub longest_wait_ms: f64,
    /// How often the planner ran dry while lines were still to come.
    pub planner_dry: usize,
    /// Status reports read.
    pub status_reports: usize,
    /// From connecting to the last line answered, seconds.
    pub elapsed_s: f64,
}

impl StreamingReport {
    fn new(port: &str, sender: &Sender, elapsed: Duration) -> StreamingReport {
        let figures = sender.report();
        StreamingReport {
            port: port.to_string(),
            firmware: if sender.is_grblhal() { "grblHAL" } else { "Grbl" },
            rx_buffer: sender.rx_buffer(),
            planner_blocks: sender.planner_blocks(),
            lines_sent: figures.lines_sent,
            bytes_sent: figures.bytes_sent,
            longest_wait_ms: figures.longest_wait.as_secs_f64() * 1000.0,
            planner_dry: figures.planner_dry,
            status_reports: figures.status_reports,
            elapsed_s: elapsed.as_secs_f64(),
        }
    }
}

/// Runs `mach-vision send`.
pub(crate) fn run(args: &SendArgs) -> Result<String, Failure> {
    let run_args = args.run_args();
    let texts = read_programs(&run_args)?;
    let progress = Progress::new(args.quiet);
    let shared = Shared(Arc::new(Mutex::new(None)));
    let wrap_link = shared.clone();
    let wrap: crate::run::CameraWrap = Box::new(move |driver| {
        let link = wrap_link.clone();
        Box::new(crate::hooked::Hooked::before(driver, Box::new(move || link.before_trigger())))
    });
    let mut session = Runner::new(&run_args, progress, Some(wrap))?;
    let options = SenderOptions { baud: Some(args.baud), ..SenderOptions::default() };
    let sender = Sender::connect(&args.port, &options).map_err(|e| Failure::Input(e.to_string()))?;
    let interrupted = Arc::new(AtomicBool::new(false));
    interrupt::install(sender.control(), Arc::clone(&interrupted))?;
    let link = mirror::connect(sender, &args.port, &mut session, interrupted)?;
    progress.line(&format!("== connected to {} ({})", args.port, link.figures().firmware));
    *shared.0.lock().unwrap_or_else(std::sync::PoisonError::into_inner) = Some(link);
    let mut drive = shared.clone();
    report_session(&run_args, &mut session, &texts, &mut drive, progress)
}
