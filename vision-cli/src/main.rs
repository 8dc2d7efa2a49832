//! `mach-vision`: camera alignment for CNC machines, from the command line.
//!
//! Every subcommand lives in its own module; this file only parses the command line and maps
//! outcomes to exit codes (0 success, 1 a run that failed, 2 bad input).

mod emulate;
mod fit;
mod hooked;
mod image_size;
mod locate;
mod panel;
mod picture;
mod plan;
#[cfg(test)]
mod reference;
mod run;
mod send;
mod sheet;
mod terminal;
mod trace;
mod trigger;
mod world;

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use vision_core::text::{printable_line, printable_lines, MAX_MESSAGE_CHARS};

/// Camera alignment for CNC machines.
#[derive(Debug, Parser)]
#[command(
    name = "mach-vision",
    version,
    about,
    after_help = "Every subcommand that reads G-code (trace, plan, run) defaults to --dialect mach4, the manual's \
                  controller; send always reads Grbl's.\n\nEnvironment: MACH_VISION_TERMINAL=always (or never) treats every standard stream as a \
                  terminal (or as none): run's progress on standard error, fit's note that it reads standard input, \
                  and a refusal printed once. Unset, the operating system says which streams are terminals."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Fit a transform from commanded to observed mark positions (JSON from FILE or stdin).
    Fit(fit::FitArgs),
    /// Run G-code programs on the simulated machine with the Vision M-codes, and report.
    Run(run::RunArgs),
    /// Run G-code programs in the host's interpreter and stream them to a Grbl, grblHAL or
    /// FluidNC controller, with the Vision M-codes run and M282's alignment applied by the host.
    Send(send::SendArgs),
    /// Run a G-code program with no vision handler and print the machine events it produces.
    Trace(trace::TraceArgs),
    /// Plan a G-code program's motion (interpreter + path planner): the cycle time, and every
    /// setpoint as CSV with --csv.
    Plan(plan::PlanArgs),
    /// Serve an emulated Keyence VS camera (the simulated camera; the default) or a Grbl
    /// controller (`emulate grbl`) on 127.0.0.1 until Ctrl-C.
    Emulate(emulate::EmulateArgs),
    /// Trigger a Keyence camera (real or emulated) once and print the decoded reading.
    Trigger(trigger::TriggerArgs),
    /// Find the fiducial mark (dot, ring or cross) in image files: its centre in pixels.
    Locate(locate::LocateArgs),
    /// Draw the calibration sheet M283 walks, to print (SVG or PDF, true size).
    Sheet(sheet::SheetArgs),
    /// Serve a local web page showing what the camera sees and the mark located on it,
    /// until Ctrl-C (read-only: nothing on it moves the machine).
    Panel(panel::PanelArgs),
}

/// The text of file `path`; `what` names it in the error ("program", "world").
pub(crate) fn read_text(path: &std::path::Path, what: &str) -> Result<String, Failure> {
    std::fs::read_to_string(path).map_err(|e| Failure::Input(format!("cannot read {what} {}: {e}", path.display())))
}

/// A failure with the exit code it maps to.
#[derive(Debug)]
pub(crate) enum Failure {
    /// Bad input (exit 2): unreadable file, malformed JSON, degenerate geometry.
    Input(String),
    /// A run that failed (exit 1): a program that stopped at a line.
    Run(String),
    /// A run that failed (exit 1) after producing a report worth printing.
    RunWithReport {
        /// The report, to standard output.
        output: String,
        /// The failure, to standard error.
        message: String,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let outcome = match cli.command {
        Command::Fit(args) => fit::run(&args),
        Command::Run(args) => run::run(&args),
        Command::Send(args) => send::run(&args),
        Command::Trace(args) => trace::run(&args),
        Command::Plan(args) => plan::run(&args),
        Command::Emulate(args) => emulate::run(&args),
        Command::Trigger(args) => trigger::run(&args),
        Command::Locate(args) => locate::run(&args),
        Command::Sheet(args) => sheet::run(&args),
        Command::Panel(args) => panel::run(&args),
    };
    // Every text a person reads goes through `vision_core::text`: reports and messages quote
    // program comments, file contents and camera replies, which may hold escape sequences or
    // megabytes (JSON output has no raw control characters, so it passes unchanged).
    match outcome {
        Ok(text) => {
            print!("{}", printable_lines(&text));
            ExitCode::SUCCESS
        }
        Err(Failure::Input(message)) => {
            error_line(&message);
            ExitCode::from(2)
        }
        Err(Failure::Run(message)) => {
            error_line(&message);
            ExitCode::from(1)
        }
        Err(Failure::RunWithReport { output, message }) => {
            print!("{}", printable_lines(&output));
            error_line(&message);
            ExitCode::from(1)
        }
    }
}

/// The one line on standard error that names the problem.
fn error_line(message: &str) {
    eprintln!("mach-vision: {}", printable_line(message, MAX_MESSAGE_CHARS));
}
