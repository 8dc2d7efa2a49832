//! `mach-vision plan`: run a G-code program through the interpreter and the path planner and
//! report its cycle time; optionally write every setpoint (and event) as CSV.
//!
//! Streams: the setpoints are never collected, so memory stays bounded however long the
//! program is (the program text itself is read whole, as `trace` does).

use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;

use clap::Args;
use vision_gcode::{Interpreter, InterpreterConfig};
use vision_math::show::number;
use vision_math::{LengthUnit, MM_PER_INCH};
use vision_path::{Event, GcodeItems, Limits, OutputCommand, PathError, PlanConfig, Setpoints, Step};

use crate::trace::{read_program, DialectArg, UnitArg};
use crate::Failure;

/// Arguments of `mach-vision plan`.
#[derive(Debug, Args)]
pub(crate) struct PlanArgs {
    /// Maximum path acceleration, machine units/s² (the seed's `maxPathAcceleration`).
    #[arg(long, allow_negative_numbers = true)]
    accel: f64,
    /// Setpoint period, milliseconds.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    period: f64,
    /// Write every setpoint (time, line, position, velocity) and event to this CSV file.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Every axis's maximum speed, machine units/s [default: 500 mm/s in the machine unit].
    #[arg(long, allow_negative_numbers = true)]
    max_speed: Option<f64>,
    /// Every axis's maximum acceleration, machine units/s² [default: --accel].
    #[arg(long, allow_negative_numbers = true)]
    axis_accel: Option<f64>,
    /// Feed (machine units/min) for feed moves before any F [default: none, such a move is an
    /// error].
    #[arg(long, allow_negative_numbers = true)]
    default_feed: Option<f64>,
    /// The machine's coordinate unit; the program's G20/G21 are converted.
    #[arg(long, value_enum, default_value_t = UnitArg::In)]
    machine_units: UnitArg,
    /// Whose G-code rules apply where the controllers differ; the default is Mach4, the
    /// manual's controller, as in `trace` and `run`.
    #[arg(long, value_parser = DialectArg::parser(), ignore_case = true, default_value_t = DialectArg::DEFAULT)]
    dialect: DialectArg,
    /// Print the report as one JSON object (as `run`, `trace` and `fit` do).
    #[arg(long)]
    json: bool,
    /// The G-code program; standard input when `-`.
    program: PathBuf,
}

/// The JSON report: the planner's settings and what it planned (lengths in the machine unit).
#[derive(Debug, serde::Serialize)]
struct Report {
    program: String,
    /// The machine unit (`in` or `mm`) of every length below.
    unit: &'static str,
    period_ms: f64,
    /// Units/s².
    path_accel: f64,
    /// Every axis's maximum speed, units/s.
    axis_max_speed: f64,
    /// Every axis's maximum acceleration, units/s².
    axis_max_accel: f64,
    /// Seconds; null for a program without motion.
    cycle_time_s: Option<f64>,
    setpoints: u64,
    events: u64,
    /// The last setpoint's position and line; null for a program without motion.
    end: Option<End>,
}

/// Where the plan ends.
#[derive(Debug, serde::Serialize)]
struct End {
    x: f64,
    y: f64,
    z: f64,
    line: usize,
}

/// Runs the subcommand; returns the report.
pub(crate) fn run(args: &PlanArgs) -> Result<String, Failure> {
    let unit = args.machine_units.unit();
    let max_speed = args.max_speed.unwrap_or(match unit {
        LengthUnit::Millimetre => 500.0,
        LengthUnit::Inch => 500.0 / MM_PER_INCH,
    });
    let limits = Limits::uniform(args.accel, max_speed, args.axis_accel.unwrap_or(args.accel));
    if let Some(f) = args.default_feed {
        // An option, not the program: refused as bad input before anything runs.
        let range = &Limits::SPEED_RANGE;
        if !range.contains(&(f / 60.0)) {
            return Err(Failure::Input(format!(
                "--default-feed {f} is invalid: must be a feed between {} and {} units/min",
                range.start() * 60.0,
                range.end() * 60.0
            )));
        }
    }
    let text = read_program(&args.program)?;
    let mut config = InterpreterConfig::new(unit);
    config.default_feed = args.default_feed;
    config.dialect = args.dialect.dialect();
    let items = GcodeItems::new(Interpreter::new(config), text.as_str());
    let plan = PlanConfig::new(limits, args.period / 1000.0, items.start_position());
    let stream = Setpoints::new(&plan, items).map_err(|e| Failure::Input(e.to_string()))?;
    let mut csv = match &args.csv {
        Some(path) => Some(Csv::create(path)?),
        None => None,
    };
    let name = args.program.display();
    let (mut setpoints, mut events) = (0u64, 0u64);
    let mut last = None;
    for step in stream {
        let step = step.map_err(|e| failure(&name.to_string(), &e))?;
        if let Some(csv) = &mut csv {
            csv.step(&step)?;
        }
        match step {
            Step::Setpoint(s) => {
                setpoints += 1;
                last = Some(s);
            }
            Step::Event(_) => events += 1,
        }
    }
    if let Some(csv) = csv {
        csv.finish()?;
    }
    let u = unit.short_name();
    if args.json {
        let report = Report {
            program: name.to_string(),
            unit: u,
            period_ms: args.period,
            path_accel: limits.max_path_accel,
            axis_max_speed: limits.axes[0].max_speed,
            axis_max_accel: limits.axes[0].max_accel,
            cycle_time_s: last.as_ref().map(|s| s.time),
            setpoints,
            events,
            end: last.map(|s| End { x: s.position.x, y: s.position.y, z: s.position.z, line: s.line }),
        };
        let mut json = serde_json::to_string_pretty(&report).map_err(|e| Failure::Input(e.to_string()))?;
        json.push('\n');
        return Ok(json);
    }
    let mut report = String::new();
    // Writing to a String cannot fail. The settings as messages show numbers (10 significant
    // digits at most), not a float's every digit.
    let _ = writeln!(
        report,
        "# {name}: {} ms setpoints, path acceleration {} {u}/s², axes {} {u}/s and {} {u}/s²",
        number(args.period),
        number(limits.max_path_accel),
        number(limits.axes[0].max_speed),
        number(limits.axes[0].max_accel)
    );
    if let Some(s) = last {
        let p = s.position;
        let _ = writeln!(report, "cycle time  {:.3} s", s.time);
        let _ = writeln!(report, "setpoints   {setpoints}");
        let _ = writeln!(report, "events      {events}");
        let _ = writeln!(report, "end         X{:.4} Y{:.4} Z{:.4} (line {})", p.x, p.y, p.z, s.line);
    }
    Ok(report)
}

/// A program that failed at a line is a failed run (exit 1); anything else is bad input.
fn failure(name: &str, e: &PathError) -> Failure {
    match e.line() {
        Some(_) => Failure::Run(format!("{name}: {e}")),
        None => Failure::Input(format!("{name}: {e}")),
    }
}

/// The CSV writer: `time_s,line,x,y,z,vx,vy,vz,event`; events are rows of their own with the
/// position columns empty.
struct Csv {
    path: PathBuf,
    out: BufWriter<File>,
}

impl Csv {
    fn create(path: &PathBuf) -> Result<Csv, Failure> {
        let file = File::create(path).map_err(|e| Failure::Input(format!("cannot create {}: {e}", path.display())))?;
        let mut csv = Csv { path: path.clone(), out: BufWriter::new(file) };
        csv.write("time_s,line,x,y,z,vx,vy,vz,event\n")?;
        Ok(csv)
    }

    fn write(&mut self, s: &str) -> Result<(), Failure> {
        let written = self.out.write_all(s.as_bytes());
        self.written(written)
    }

    /// One row per step, formatted straight into the buffer (no string per row).
    fn step(&mut self, step: &Step) -> Result<(), Failure> {
        let written = match step {
            Step::Setpoint(s) => {
                let (p, v) = (s.position, s.velocity);
                writeln!(self.out, "{:.6},{},{},{},{},{},{},{},", s.time, s.line, p.x, p.y, p.z, v.x, v.y, v.z)
            }
            Step::Event(e) => writeln!(self.out, "{:.6},{},,,,,,,{}", e.time, e.line, EventText(e.event)),
        };
        self.written(written)
    }

    fn finish(mut self) -> Result<(), Failure> {
        let flushed = self.out.flush();
        self.written(flushed)
    }

    fn written(&self, result: std::io::Result<()>) -> Result<(), Failure> {
        result.map_err(|e| Failure::Input(format!("cannot write {}: {e}", self.path.display())))
    }
}

/// An event as the G-code that caused it (`M6 T2`, `M3 $1`, `M5 A1 P0`).
struct EventText(Event);

impl std::fmt::Display for EventText {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0 {
            Event::ToolChange(t) => write!(f, "M6 T{t}"),
            Event::Output(OutputCommand::Tool { tool: Some(t), command }) => write!(f, "{} ${t}", command.gcode()),
            Event::Output(OutputCommand::Tool { tool: None, command }) => f.write_str(command.gcode()),
            Event::Output(OutputCommand::Port { device, port, command }) => {
                write!(f, "{} A{device} P{port}", command.gcode())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use vision_path::SpindleCommand;

    use super::*;

    #[test]
    fn events_read_back_as_their_own_m_codes() {
        let text = |event| EventText(event).to_string();
        let port = |command| Event::Output(OutputCommand::Port { device: 1, port: 1, command });
        assert_eq!(text(port(SpindleCommand::CounterClockwise)), "M4 A1 P1");
        assert_eq!(text(port(SpindleCommand::Clockwise)), "M3 A1 P1");
        assert_eq!(text(port(SpindleCommand::Stop)), "M5 A1 P1");
        let tool = |tool, command| Event::Output(OutputCommand::Tool { tool, command });
        assert_eq!(text(tool(Some(2), SpindleCommand::CounterClockwise)), "M4 $2");
        assert_eq!(text(tool(None, SpindleCommand::Stop)), "M5");
        assert_eq!(text(Event::ToolChange(3)), "M6 T3");
    }
}
