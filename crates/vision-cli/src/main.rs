//! `mach-vision`: camera alignment for CNC machines, from the command line.
//!
//! Every subcommand lives in its own module; this file only parses the command line and maps
//! outcomes to exit codes (0 success, 1 a run that failed, 2 bad input).

mod fit;
mod plan;
mod trace;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Camera alignment for CNC machines.
#[derive(Debug, Parser)]
#[command(name = "mach-vision", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Fit a transform from commanded to observed mark positions (JSON from FILE or stdin).
    Fit(fit::FitArgs),
    /// Run a G-code program with no vision handler and print the machine events it produces.
    Trace(trace::TraceArgs),
    /// Plan a G-code program's motion (interpreter + path planner): the cycle time, and every
    /// setpoint as CSV with --csv.
    Plan(plan::PlanArgs),
}

/// A failure with the exit code it maps to.
#[derive(Debug)]
pub(crate) enum Failure {
    /// Bad input (exit 2): unreadable file, malformed JSON, degenerate geometry.
    Input(String),
    /// A run that failed (exit 1): a program that stopped at a line.
    Run(String),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let outcome = match cli.command {
        Command::Fit(args) => fit::run(&args),
        Command::Trace(args) => trace::run(&args),
        Command::Plan(args) => plan::run(&args),
    };
    match outcome {
        Ok(text) => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        Err(Failure::Input(message)) => {
            eprintln!("mach-vision: {message}");
            ExitCode::from(2)
        }
        Err(Failure::Run(message)) => {
            eprintln!("mach-vision: {message}");
            ExitCode::from(1)
        }
    }
}
