//! `mach-vision trace`: run a G-code program on the interpreter with no vision handler attached
//! and print what the machine would do, event by event, in machine coordinates.
//!
//! User M-codes (M280–M284 and the rest of the user range) are reported, not executed. Output
//! streams as the program runs and events are not kept: memory is the program text (read
//! whole) plus a constant.

use std::fmt::Write as _;
use std::io::{BufWriter, Read as _, Write};
use std::path::PathBuf;

use clap::{Args, ValueEnum};
use serde_json::{json, Value};
use vision_core::text::{printable_line, MAX_MESSAGE_CHARS};
use vision_core::Controller;
use vision_driver_sim::interpreter_dialect;
use vision_gcode::{
    ArcDirection, Dialect, Event, GcodeError, Interpreter, InterpreterConfig, PathMode, Rate, RunOutcome, Xyz,
};
use vision_math::LengthUnit;

use crate::Failure;

/// Arguments of `mach-vision trace`.
#[derive(Debug, Args)]
pub(crate) struct TraceArgs {
    /// Print one JSON object per line (one per event, then a summary) instead of text.
    #[arg(long)]
    json: bool,
    /// The machine's coordinate unit (events are in it); the program's G20/G21 are converted.
    #[arg(long, value_enum, default_value_t = UnitArg::In)]
    machine_units: UnitArg,
    /// Turn the block-delete switch on: lines starting with `/` are skipped (off by default, as
    /// on the controllers: the `/` is ignored).
    #[arg(long)]
    block_delete: bool,
    /// Whose G-code rules apply where the controllers differ; the default is Mach4, the
    /// manual's controller, as in `plan` and `run`.
    #[arg(long, value_parser = DialectArg::parser(), ignore_case = true, default_value_t = DialectArg::DEFAULT)]
    dialect: DialectArg,
    /// Folders searched for `name.ngc` when `o<name> call` names a subroutine the program does
    /// not define (LinuxCNC's SUBROUTINE_PATH); colon-separated, or repeat the option.
    #[arg(long, value_delimiter = ':')]
    subroutine_path: Vec<PathBuf>,
    /// The G-code program; standard input when `-`.
    program: PathBuf,
}

/// `--dialect NAME`: the controller whose G-code rules apply where the controllers differ
/// (shared with `plan` and `run`): `mach4` (G92 keeps unnamed axes, G43 applies tool length
/// offsets, flat comments), `linuxcnc` (2.9: as Mach4 without G68/G51; its tool table is added)
/// or `machinemotion` (seed 002: G92 zeroes unnamed axes, M6 applies tool offsets, nested
/// comments). Any name in `vision_core::CONTROLLERS`, in any case; `--help` lists them.
#[derive(Debug, Clone, Copy)]
pub(crate) struct DialectArg(pub(crate) &'static dyn Controller);

impl DialectArg {
    /// Mach4, every subcommand's default. Decision: the controller a user most likely has — the
    /// manual's (SPEC), the one the Windows package installs into — so that `trace`, `plan` and
    /// `run` read a program alike when no `--dialect` is given (`run` takes the world's
    /// `machine.dialect`, whose default is the same Mach4).
    pub(crate) const DEFAULT: DialectArg = DialectArg(&vision_core::controller::Mach4);

    /// Parses a controller's name (case-insensitive).
    pub(crate) fn parse(name: &str) -> Result<DialectArg, String> {
        vision_core::controller::by_name(name).map(DialectArg).map_err(|e| e.to_string())
    }

    /// The option's parser: the controllers' names as clap's possible values (so `--help` lists
    /// them; the option sets `ignore_case`).
    pub(crate) fn parser() -> impl clap::builder::TypedValueParser<Value = DialectArg> {
        use clap::builder::TypedValueParser as _;
        clap::builder::PossibleValuesParser::new(vision_core::controller::names())
            .try_map(|name| DialectArg::parse(&name))
    }

    /// The interpreter's dialect.
    pub(crate) fn dialect(self) -> Dialect {
        interpreter_dialect(self.0)
    }
}

impl std::fmt::Display for DialectArg {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0.name())
    }
}

/// The machine unit on the command line (shared with `plan`).
#[derive(Debug, Clone, Copy, ValueEnum)]
pub(crate) enum UnitArg {
    /// Inches (the manual's router).
    In,
    /// Millimetres.
    Mm,
}

impl UnitArg {
    pub(crate) fn unit(self) -> LengthUnit {
        match self {
            UnitArg::In => LengthUnit::Inch,
            UnitArg::Mm => LengthUnit::Millimetre,
        }
    }
}

/// Runs the subcommand, printing as it goes; returns nothing more to print.
pub(crate) fn run(args: &TraceArgs) -> Result<String, Failure> {
    let text = read_program(&args.program)?;
    let unit = args.machine_units.unit();
    let config = InterpreterConfig {
        block_delete: args.block_delete,
        dialect: args.dialect.dialect(),
        subroutine_path: args.subroutine_path.clone(),
        ..InterpreterConfig::new(unit)
    };
    let mut interp = Interpreter::new(config);
    let stdout = std::io::stdout();
    let mut out = Output { writer: BufWriter::new(stdout.lock()), json: args.json, broken: false };
    if !args.json {
        out.line(&format!("# {}: machine coordinates (spindle) in {}", args.program.display(), unit.short_name()));
    }
    let result = interp.run(&text, None, &mut |e: &Event| out.event(e));
    match result {
        Ok(outcome) => {
            out.summary(&interp, outcome);
            out.flush();
            Ok(String::new())
        }
        Err(e) => {
            out.failure(&e);
            out.flush();
            Err(Failure::Run(format!("{}: {e}", args.program.display())))
        }
    }
}

pub(crate) fn read_program(path: &PathBuf) -> Result<String, Failure> {
    let bytes = if path.as_os_str() == "-" {
        let mut b = Vec::new();
        std::io::stdin().read_to_end(&mut b).map_err(|e| Failure::Input(format!("cannot read standard input: {e}")))?;
        b
    } else {
        std::fs::read(path).map_err(|e| Failure::Input(format!("cannot read {}: {e}", path.display())))?
    };
    // Controllers read programs as bytes; a comment written in Latin-1 (`(Ø 6 mm)`) is common.
    Ok(String::from_utf8(bytes).unwrap_or_else(|e| e.into_bytes().iter().map(|&b| char::from(b)).collect()))
}

/// The output stream: text or JSON lines. A closed pipe (`| head`) stops the printing quietly.
struct Output<W: Write> {
    writer: W,
    json: bool,
    broken: bool,
}

impl<W: Write> Output<W> {
    fn line(&mut self, s: &str) {
        // Text lines quote program comments and file names: shown escaped and cut (JSON
        // escapes them itself).
        let printable;
        let s = if self.json {
            s
        } else {
            printable = printable_line(s, MAX_MESSAGE_CHARS);
            printable.as_str()
        };
        if !self.broken && writeln!(self.writer, "{s}").is_err() {
            self.broken = true;
        }
    }

    fn flush(&mut self) {
        if !self.broken {
            let _ = self.writer.flush();
        }
    }

    fn event(&mut self, e: &Event) {
        let s = if self.json { event_json(e).to_string() } else { event_text(e) };
        self.line(&s);
    }

    fn summary(&mut self, interp: &Interpreter, outcome: RunOutcome) {
        let m = interp.machine_position();
        let (what, line, code) = match outcome {
            RunOutcome::Completed { lines } => ("completed", lines, None),
            RunOutcome::Ended { line, code } => ("ended", line, Some(code)),
        };
        if self.json {
            let summary = json!({
                "type": "summary",
                "outcome": what,
                "line": line,
                "code": code,
                "machine_unit": interp.machine_unit().short_name(),
                "machine": m.to_array(),
                "program": interp.program_position().to_array(),
                "program_unit": interp.units().short_name(),
            });
            self.line(&summary.to_string());
        } else {
            let end = match code {
                Some(c) => format!("ended by M{c} at line {line}"),
                None => format!("ran all {line} lines"),
            };
            self.line(&format!("# {end}; machine at {}", pos(m)));
        }
    }

    fn failure(&mut self, e: &GcodeError) {
        if self.json {
            self.line(
                &json!({"type": "error", "line": e.line(), "column": e.column(), "message": e.to_string()}).to_string(),
            );
        }
    }
}

fn pos(p: Xyz) -> String {
    format!("X{:.4} Y{:.4} Z{:.4}", p.x, p.y, p.z)
}

fn path_json(path: PathMode) -> Value {
    match path {
        PathMode::ExactStop => json!({"mode": "exact_stop"}),
        PathMode::Blend { tolerance } => json!({"mode": "blend", "tolerance": tolerance}),
    }
}

fn event_json(e: &Event) -> Value {
    match e {
        Event::Linear(m) => {
            let (rate, feed) = match m.rate {
                Rate::Rapid => ("rapid", None),
                Rate::Feed(f) => ("feed", Some(f)),
            };
            json!({"line": m.line, "type": "linear", "rate": rate, "feed": feed, "start": m.start.to_array(),
                   "end": m.end.to_array(), "path": path_json(m.path)})
        }
        Event::Arc(a) => json!({
            "line": a.line, "type": "arc", "start": a.start.to_array(), "end": a.end.to_array(), "center": a.center.to_array(),
            "plane": a.plane.gcode(),
            "direction": if a.direction == ArcDirection::Clockwise { "cw" } else { "ccw" },
            "angle_rad": a.angle, "extra_turns": a.extra_turns(), "feed": a.feed, "path": path_json(a.path),
        }),
        Event::Dwell { line, seconds } => json!({"line": line, "type": "dwell", "seconds": seconds}),
        Event::ToolChange { line, tool, offset } => {
            json!({"line": line, "type": "tool_change", "tool": tool, "offset": offset.to_array()})
        }
        Event::Spindle { line, command, speed } => {
            json!({"line": line, "type": "spindle", "command": command.gcode(), "speed": speed})
        }
        Event::Coolant { line, coolant } => json!({"line": line, "type": "coolant", "command": coolant.gcode()}),
        Event::Output(o) => json!({
            "line": o.line, "type": "output", "command": o.command.gcode(), "tool": o.tool,
            "writes": o.writes.iter().map(|w| json!({"device": w.device, "port": w.port, "high": w.high})).collect::<Vec<_>>(),
        }),
        Event::Stop { line, optional } => json!({"line": line, "type": "stop", "optional": optional}),
        Event::ProgramEnd { line, code } => json!({"line": line, "type": "program_end", "code": code}),
        Event::UserMCode(c) => {
            let words: serde_json::Map<String, Value> =
                c.words.iter().map(|(l, v)| (l.to_string(), json!(v))).collect();
            json!({"line": c.line, "type": "user_mcode", "code": c.code, "words": words, "comments": c.comments,
                   "executed": false})
        }
    }
}

fn event_text(e: &Event) -> String {
    let mut s = format!("{:>6}  ", e.line());
    // Writing to a String cannot fail.
    let _ = match e {
        Event::Linear(m) => match m.rate {
            Rate::Rapid => write!(s, "rapid  {}", pos(m.end)),
            Rate::Feed(f) => write!(s, "feed   {}  F{f:.4}", pos(m.end)),
        },
        Event::Arc(a) => {
            let dir = if a.direction == ArcDirection::Clockwise { "cw " } else { "ccw" };
            write!(
                s,
                "arc    {}  {} {dir} centre {}  {:.4} deg  F{:.4}",
                pos(a.end),
                a.plane.gcode(),
                pos(a.center),
                a.angle.to_degrees(),
                a.feed
            )
        }
        Event::Dwell { seconds, .. } => write!(s, "dwell  {seconds} s"),
        Event::ToolChange { tool, offset, .. } => write!(s, "tool   T{tool} loaded, offset {}", pos(*offset)),
        Event::Output(o) => {
            let target = o.tool.map_or_else(|| "explicit".to_string(), |t| format!("tool {t}"));
            let writes: Vec<String> = o
                .writes
                .iter()
                .map(|w| format!("device {} port {} {}", w.device, w.port, if w.high { "high" } else { "low" }))
                .collect();
            let writes = if writes.is_empty() { "no outputs wired".to_string() } else { writes.join(", ") };
            write!(s, "{}     {target}: {writes}", o.command.gcode())
        }
        Event::Spindle { command, speed, .. } => match speed {
            Some(rpm) => write!(s, "{}     spindle S{rpm}", command.gcode()),
            None => write!(s, "{}     spindle", command.gcode()),
        },
        Event::Coolant { coolant, .. } => write!(s, "{}     coolant", coolant.gcode()),
        Event::Stop { optional, .. } => {
            write!(s, "{}", if *optional { "M1     optional stop" } else { "M0     program stop" })
        }
        Event::ProgramEnd { code, .. } => write!(s, "M{code}    program end"),
        Event::UserMCode(c) => {
            let words: Vec<String> = c.words.iter().map(|(l, v)| format!("{l}{v}")).collect();
            let comments: Vec<String> = c.comments.iter().map(|t| format!("({t})")).collect();
            let call = [format!("M{}", c.code)].into_iter().chain(words).chain(comments).collect::<Vec<_>>().join(" ");
            write!(s, "user   {call}  -- not executed (no vision handler)")
        }
    };
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trace(program: &str, json: bool) -> (Vec<String>, Result<RunOutcome, GcodeError>) {
        let mut interp = Interpreter::new(InterpreterConfig::default());
        let mut out = Output { writer: Vec::new(), json, broken: false };
        let result = interp.run(program, None, &mut |e: &Event| out.event(e));
        let text = String::from_utf8(out.writer).expect("utf-8");
        (text.lines().map(str::to_string).collect(), result)
    }

    #[test]
    fn text_lines_name_the_line_and_the_machine_position() {
        let (lines, result) =
            trace("G90 G20 F10\nT2 M6\nG0 X1 Y2\nG2 X2 Y1 I1 J0\nG4 P0.5\nM281 D1 (cap)\nM3\nM30", false);
        assert!(result.is_ok());
        assert_eq!(lines[0], "     2  tool   T2 loaded, offset X0.0000 Y0.0000 Z0.0000");
        assert_eq!(lines[1], "     3  rapid  X1.0000 Y2.0000 Z0.0000");
        assert!(lines[2].starts_with("     4  arc    X2.0000 Y1.0000 Z0.0000  G17 cw  centre X2.0000 Y2.0000"));
        assert_eq!(lines[3], "     5  dwell  0.5 s");
        assert_eq!(lines[4], "     6  user   M281 D1 (cap)  -- not executed (no vision handler)");
        assert_eq!(lines[5], "     7  M3     tool 2: no outputs wired");
        assert_eq!(lines[6], "     8  M30    program end");
    }

    #[test]
    fn json_lines_carry_every_field() {
        let (lines, _) = trace("G90 F10\nG64 P0.01\nG1 X1\nM283 C1", true);
        let v: Vec<Value> = lines.iter().map(|l| serde_json::from_str(l).expect("JSON")).collect();
        assert_eq!(v[0]["type"], "linear");
        assert_eq!(v[0]["rate"], "feed");
        assert_eq!(v[0]["feed"], 10.0);
        assert_eq!(v[0]["end"], json!([1.0, 0.0, 0.0]));
        assert_eq!(v[0]["path"], json!({"mode": "blend", "tolerance": 0.01}));
        assert_eq!(v[1]["type"], "user_mcode");
        assert_eq!(v[1]["words"], json!({"C": 1.0}));
        assert_eq!(v[1]["executed"], false);
    }
}
