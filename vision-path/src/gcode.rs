//! The adapter from the G-code interpreter (`vision-gcode`) to the planner: program text in,
//! [`Item`]s out, one line at a time, so memory stays bounded by one line's events. From the
//! first line that needs control flow (an o-word, M98, M99: [`vision_gcode::needs_program`])
//! the rest of the text is indexed once and still runs a line at a time
//! ([`Interpreter::step_flow`]), so a loop of any length streams too.
//!
//! | interpreter event | planner item |
//! | --- | --- |
//! | `Linear` (G0, G1, G28 legs, arc polylines) | a line [`Segment`]: its rate and G61/G64 as they are |
//! | `Arc` | an arc [`Segment`]: centre, plane normal (+Z G17, +Y G18, +X G19), the interpreter's swept angle signed by the direction |
//! | `Dwell` (G4) | [`Item::Dwell`] |
//! | `ToolChange` (M6) | [`Event::ToolChange`] |
//! | `Output` (M3/M4/M5) | [`Event::Output`]: the tool (or the explicit port) and the M-code |
//! | `Stop` (M0/M1), `UserMCode` (reported, not executed), `Spindle` (M3/M4/M5 without a tool), `Coolant` (M7/M8/M9) | a zero-second dwell: an exact stop there |
//! | `ProgramEnd` (M2/M30) | [`Item::End`] |
//! | an error at a line | `Err(PathError::Program { line, .. })` |
//!
//! The interpreter resolves M3/M4/M5 to writes with its own tool table; the planner keeps only
//! the tool number and the M-code, and the [`crate::PathFollower`]'s [`crate::ToolTable`]
//! resolves them (by the same rule, [`vision_gcode::ToolOutputs::writes`]), so segments and
//! G-code drive tools the same way.

use std::collections::VecDeque;

use vision_gcode::{
    needs_program, Event as GEvent, FlowRun, GcodeError, Interpreter, InterpreterConfig, Piece, Plane, ProgramStream,
    Rate, RunOutcome, Xyz,
};

use crate::follower::check_axes;
use crate::input::{ArcShape, Event, Item, OutputCommand, Segment, Shape};
use crate::{MotionSink, Pace, PathError, PathFollower};

/// A G-code program as a stream of planner items (see the module docs). `T` holds the text
/// (`String` to own it, `&str` to borrow it).
///
/// User M-codes are reported by the interpreter, not executed, and become exact stops: the
/// planner reads ahead of the machine, so a handler would run when the look-ahead reaches its
/// line, up to a braking distance before the machine does. To expand M-codes into G-code, run
/// the interpreter with the handler yourself and turn its events into items with [`item`].
pub struct GcodeItems<T = String> {
    interp: Interpreter,
    /// Where the program stands between lines (begun, opened by `%`).
    program: ProgramStream,
    text: T,
    /// Byte offset of the next line in `text`.
    next: Option<usize>,
    /// Number of the last line run.
    line: u32,
    queue: VecDeque<Result<Item, PathError>>,
    done: bool,
    /// From the first control-flow line on: the run, and the line before it (its lines count
    /// from there).
    flow: Option<(FlowRun, u32)>,
    /// How the last line's events are numbered: `(true, base)` under control flow (`base` plus
    /// the line in the rest of the text), `(false, line)` for a plain line.
    tags: (bool, u32),
    /// The last line's outcome, handled once its held events are queued.
    outcome: Option<Result<Option<Piece>, GcodeError>>,
}

impl<T: AsRef<str>> GcodeItems<T> {
    /// Run `text` on `interp` (in its current state and machine position), lazily.
    pub fn new(mut interp: Interpreter, text: T) -> GcodeItems<T> {
        // A line's events reach the queue a chunk at a time (a canned cycle of a million
        // moves is one line).
        interp.set_chunked_events(true);
        GcodeItems {
            interp,
            program: ProgramStream::default(),
            text,
            next: Some(0),
            line: 0,
            queue: VecDeque::new(),
            done: false,
            flow: None,
            tags: (false, 0),
            outcome: None,
        }
    }

    /// Where the machine is before the program runs (the planner's start), machine units.
    pub fn start_position(&self) -> Xyz {
        self.interp.machine_position()
    }

    /// Queue the next chunk of the last line's items, or its outcome, or run the next line.
    fn step(&mut self) {
        let tags = self.tags;
        if self.interp.emit_held(&mut queue_into(&mut self.queue, tags)) {
            return;
        }
        if let Some(outcome) = self.outcome.take() {
            return self.after(outcome, tags.0, |n| tag(tags, n));
        }
        if let Some((run, base)) = &mut self.flow {
            self.tags = (true, *base);
            let outcome = self.interp.step_flow(run, &mut self.program, &mut queue_into(&mut self.queue, self.tags));
            if let Ok(Some(_)) | Err(_) = outcome {
                self.flow = None;
            }
            self.outcome = Some(outcome);
            return;
        }
        // The end of the text (a final newline does not start another line): the program
        // ended without M2/M30 or a closing `%`, which LinuxCNC refuses.
        let Some(start) = self.next.filter(|&start| start < self.text.as_ref().len()) else {
            self.done = true;
            let end = match self.interp.end_of_text(self.line) {
                Ok(_) => Ok(Item::End { line: self.line as usize }),
                Err(e) => Err(program_error(&e, self.line)),
            };
            self.queue.push_back(end);
            return;
        };
        let rest = &self.text.as_ref()[start..];
        let (raw, next) = match rest.find('\n') {
            Some(i) => (&rest[..i], Some(start + i + 1)),
            None => (rest, None),
        };
        self.next = next;
        self.line = self.line.saturating_add(1);
        let line = self.line;
        if needs_program(raw) {
            // Control flow needs the rest of the text at once (its subroutines may come later):
            // it is indexed now and run a line at a time from here.
            let base = line - 1;
            self.tags = (true, base);
            match self.interp.start_flow(&mut self.program, rest, &mut queue_into(&mut self.queue, self.tags)) {
                Ok(run) => self.flow = Some((run, base)),
                Err(e) => self.outcome = Some(Err(e)),
            }
            return;
        }
        self.tags = (false, line);
        let mut sink = queue_into(&mut self.queue, self.tags);
        self.outcome = Some(self.interp.run_streamed(&mut self.program, raw, None, &mut sink).map(Some));
    }

    /// What a line's `outcome` means for the stream: `whole` when it ran under control flow
    /// (on the rest of the text), `at` gives a line of the piece its number in the text.
    fn after(&mut self, outcome: Result<Option<Piece>, GcodeError>, whole: bool, at: impl Fn(u32) -> u32) {
        match outcome {
            Ok(None) => {}
            Ok(Some(Piece::RanOut { lines })) if whole => {
                // The control flow ran to the end of the text.
                self.next = None;
                self.line = at(lines);
            }
            Ok(Some(Piece::RanOut { .. })) => {}
            // M2/M30 queued its own end.
            Ok(Some(Piece::Over(RunOutcome::Ended { .. }))) => self.done = true,
            // The closing `%`.
            Ok(Some(Piece::Over(RunOutcome::Completed { lines }))) => {
                self.queue.push_back(Ok(Item::End { line: at(lines) as usize }));
                self.done = true;
            }
            Err(e) => {
                self.queue.push_back(Err(program_error(&e, at(e.line()))));
                self.done = true;
            }
        }
    }
}

impl<T: AsRef<str>> Iterator for GcodeItems<T> {
    type Item = Result<Item, PathError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if let Some(item) = self.queue.pop_front() {
                return Some(item);
            }
            if self.done {
                return None;
            }
            self.step();
        }
    }
}

impl PathFollower {
    /// The seed's `startPath(GCODE_STRING, maxPathAcceleration)`: run `program` on a fresh
    /// interpreter built from `config`, starting where the machine is.
    ///
    /// Refused at once while a path runs. The whole program is then checked, streaming
    /// (interpreter errors, a move of an unmapped axis, a tool missing from the follower's
    /// table): if anything fails, nothing moves and the error comes back here. User M-codes
    /// are exact stops (see [`GcodeItems`]).
    pub fn start_gcode<S: MotionSink + 'static>(
        &mut self,
        config: &InterpreterConfig,
        program: impl Into<String>,
        max_path_accel: f64,
        sink: S,
        pace: Pace,
    ) -> Result<(), PathError> {
        if self.status().running() {
            return Err(PathError::AlreadyRunning);
        }
        let text = program.into();
        let at = self.status().position;
        let fresh = || -> Result<Interpreter, PathError> {
            let mut interp = Interpreter::new(config.clone());
            interp.set_machine_position(at).map_err(|e| program_error(&e, 0))?;
            Ok(interp)
        };
        // The interpreter names the tool of every M3/M4/M5 (`$n` or its active tool), so no
        // selection needs tracking here.
        for item in GcodeItems::new(fresh()?, text.as_str()) {
            if let Item::Event { line, event: Event::Output(command) } = check_axes(&self.config().axes, item?)? {
                crate::tools::resolve(&self.config().tools, line, None, command)?;
            }
        }
        self.start(GcodeItems::new(fresh()?, text), max_path_accel, sink, pace)
    }
}

/// The line of the text an event of line `n` stands for, under `tags` ([`GcodeItems::tags`]).
fn tag((whole, base): (bool, u32), n: u32) -> u32 {
    if whole {
        base.saturating_add(n)
    } else {
        base
    }
}

/// A sink that queues each event as its planner item, numbered by `tags`.
fn queue_into(queue: &mut VecDeque<Result<Item, PathError>>, tags: (bool, u32)) -> impl FnMut(&GEvent) + '_ {
    move |e: &GEvent| queue.push_back(Ok(item(e, tag(tags, e.line()) as usize)))
}

/// The planner item for one interpreter event, tagged with `line`.
pub fn item(event: &GEvent, line: usize) -> Item {
    match event {
        GEvent::Linear(m) => {
            Item::Move(Segment { line, start: m.start, end: m.end, shape: Shape::Line, rate: m.rate, mode: m.path })
        }
        GEvent::Arc(a) => Item::Move(Segment {
            line,
            start: a.start,
            end: a.end,
            shape: Shape::Arc(ArcShape {
                centre: a.center,
                normal: match a.plane {
                    Plane::Xy => Xyz::new(0.0, 0.0, 1.0),
                    Plane::Zx => Xyz::new(0.0, 1.0, 0.0),
                    Plane::Yz => Xyz::new(1.0, 0.0, 0.0),
                },
                sweep: a.direction.sign() * a.angle,
            }),
            rate: Rate::Feed(a.feed),
            mode: a.path,
        }),
        GEvent::Dwell { seconds, .. } => Item::Dwell { line, seconds: *seconds },
        GEvent::ToolChange { tool, .. } => Item::Event { line, event: Event::ToolChange(*tool) },
        GEvent::Output(o) => {
            let command = match (o.tool, o.writes.first()) {
                (None, Some(w)) => OutputCommand::Port { device: w.device, port: w.port, command: o.command },
                (tool, _) => OutputCommand::Tool { tool, command: o.command },
            };
            Item::Event { line, event: Event::Output(command) }
        }
        // A spindle or coolant switch waits for the motion before it (a stop, like M0).
        GEvent::Stop { .. } | GEvent::UserMCode(_) | GEvent::Spindle { .. } | GEvent::Coolant { .. } => {
            Item::Dwell { line, seconds: 0.0 }
        }
        GEvent::ProgramEnd { .. } => Item::End { line },
    }
}

/// The interpreter's error for a line run alone (numbered 1), told at its real `line`.
fn program_error(e: &GcodeError, line: u32) -> PathError {
    let text = e.to_string();
    let own = vision_gcode::error::source_position(u64::from(e.line()), e.column());
    let message = match text.strip_prefix(&own) {
        Some(rest) => rest.trim_start_matches([':', ' ']).to_string(),
        None => text,
    };
    PathError::Program { line: line as usize, column: e.column(), message }
}
