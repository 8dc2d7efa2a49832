//! The interpreter: runs text line by line, keeps the modal state, streams events.

mod cycles;
mod flow;
mod frames;
mod host;
mod line;
mod modal;
mod motion;

use std::collections::VecDeque;

use vision_math::{AlignmentChain, LengthUnit, Point2, Vector2};

pub use cycles::MAX_CYCLE_MOVES;
pub use flow::{needs_program, FlowRun};
pub use modal::MotionMode;

use crate::config::InterpreterConfig;
use crate::error::{GcodeError, RunProblem};
use crate::event::{Event, EventSink, PathMode, UserCall};
use crate::geom::{Plane, Xyz};
use crate::handler::{Context, HandlerError, MCodeHandler, UserMCode};
use crate::params::{ParameterTable, ACTIVE_SYSTEM, G92_OFFSET, POSITION, TOOL_NUMBER, TOOL_OFFSET};
use crate::parse::Parser;
use crate::tools::ToolTable;
use crate::watch::{PositionWatch, Publisher};
use crate::words::{evaluate, Target, Words};
use host::affects_frame;
use line::{is_builtin_m, Flow, LineRun, Pending};
use modal::{work_offset_base, Modal};

/// Where a line sits: its number in the text being run, the line its events are tagged with, and
/// whether it is G-code run by a handler.
#[derive(Debug, Clone, Copy)]
struct At {
    line: u32,
    tag: u32,
    nested: bool,
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunOutcome {
    /// Every line ran; `lines` is the number of lines in the text.
    Completed {
        /// Lines in the text.
        lines: u32,
    },
    /// M2 or M30 ended the program at `line`; later lines were not run.
    Ended {
        /// The line of the M2/M30.
        line: u32,
        /// 2 or 30.
        code: u32,
    },
}

/// Where a program fed to [`Interpreter::run_streamed`] in pieces stands between them: whether
/// it has begun (a non-blank line ran) and whether a `%` on its first line opened it, so that the
/// next `%` ends it. A fresh one is a program not yet begun.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ProgramStream {
    started: bool,
    delimited: bool,
}

/// How one piece of a program fed to [`Interpreter::run_streamed`] ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Piece {
    /// An M2/M30 or the closing `%` ended the program.
    Over(RunOutcome),
    /// The piece ran out after `lines` lines; the program goes on.
    RanOut {
        /// Lines in the piece.
        lines: u32,
    },
}

/// A G-code interpreter for one machine.
///
/// It owns the modal state, the parameters and the tool table, and runs G-code text
/// ([`Interpreter::run`]) or single operations for a host ([`Interpreter::context`]). Events go
/// to the sink given to each call; the interpreter keeps none of them. A clone is a complete,
/// independent copy of the machine state: a host can ask "where would this move go?" on a
/// clone without disturbing the original.
#[derive(Debug, Clone)]
pub struct Interpreter {
    /// The set-up; `config.tools` is the live tool table.
    config: InterpreterConfig,
    params: ParameterTable,
    modal: Modal,
    parser: Parser,
    stack: Vec<f64>,
    assigns: Vec<(Target, f64)>,
    pending: Vec<Pending>,
    /// Where the machine position is published for [`PositionWatch`]es (not shared by clones).
    publisher: Publisher,
    /// Modal states saved by [`Interpreter::push_modal_state`], newest last.
    saved_modal: Vec<Modal>,
    /// Whether committed lines keep their events for [`Interpreter::emit_held`].
    chunked: bool,
    /// Events of committed lines not emitted yet (chunked only), in order.
    held: VecDeque<Pending>,
}

/// The largest repeat count a program may write: a canned cycle's and M98's `L`, G2/G3's `P`
/// turns, an o-word `repeat [n]`. Above it a count is a typo (`L10000000`) that would run for
/// hours; the loops without a count (`while`, `do`) are bounded by
/// [`InterpreterConfig::max_loop_iterations`] instead.
pub const MAX_REPEATS: u32 = 100_000;

/// The most modal states [`Interpreter::push_modal_state`] keeps at once.
pub const MAX_SAVED_MODAL_STATES: usize = 16;

impl Interpreter {
    /// An interpreter at machine position zero, in its start-up modes.
    #[must_use]
    pub fn new(config: InterpreterConfig) -> Interpreter {
        let modal = Modal::initial(&config);
        let parser = Parser::for_dialect(config.dialect);
        let params = ParameterTable::for_dialect(config.dialect);
        let mut interp = Interpreter {
            config,
            params,
            modal,
            parser,
            stack: Vec::new(),
            assigns: Vec::new(),
            pending: Vec::new(),
            publisher: Publisher::default(),
            saved_modal: Vec::new(),
            chunked: false,
            held: VecDeque::new(),
        };
        interp.refresh_mirrors();
        interp
    }

    /// The set-up it was built with, except `tools`: the interpreter keeps its one, live tool
    /// table there (the same as [`Interpreter::tools`]), so handler and host writes show in it.
    #[must_use]
    pub fn config(&self) -> &InterpreterConfig {
        &self.config
    }

    /// Runs `text` (lines separated by LF or CRLF, numbered from 1) until its end or an M2/M30.
    ///
    /// User M-codes go to `handler`; with `None` they are reported as [`Event::UserMCode`] and
    /// not executed.
    ///
    /// # Errors
    /// The first line that fails; it changed nothing (for user M-code lines see "A line is
    /// atomic" in the repository's `docs/gcode-interpreter.md`) and no later line ran. Under
    /// LinuxCNC, [`RunProblem::NoProgramEnd`] at the last line when the text ends without M2/M30
    /// or a closing `%`.
    pub fn run(
        &mut self,
        text: &str,
        handler: Option<&mut dyn MCodeHandler>,
        sink: &mut dyn EventSink,
    ) -> Result<RunOutcome, GcodeError> {
        let mut program = ProgramStream::default();
        match self.run_streamed(&mut program, text, handler, sink)? {
            Piece::Over(outcome) => Ok(outcome),
            Piece::RanOut { lines } => self.end_of_text(lines),
        }
    }

    /// The text of a program ended after `lines` lines without M2/M30 or a closing `%`:
    /// complete, except under LinuxCNC, whose rs274 refuses such a file ("File ended with no
    /// percent sign or program end"); Mach4 and seed 002 run it.
    ///
    /// # Errors
    /// Under LinuxCNC, [`RunProblem::NoProgramEnd`] at line `lines`.
    pub fn end_of_text(&self, lines: u32) -> Result<RunOutcome, GcodeError> {
        if self.config.rules().program_end_required {
            return Err(GcodeError::run(lines, RunProblem::NoProgramEnd));
        }
        Ok(RunOutcome::Completed { lines })
    }

    /// Runs one piece of a program that is fed in pieces (a line at a time, say, so that the
    /// caller need not hold the whole text), by [`Interpreter::run`]'s rules: `program` carries
    /// between the pieces whether the program has begun and whether a `%` opened it. The
    /// piece's lines are numbered from 1. When the text ends, call [`Interpreter::end_of_text`].
    ///
    /// A piece that starts control flow (an o-word, M98, M99: [`needs_program`]) runs its
    /// subroutines from the same piece, so it must hold the rest of the program.
    ///
    /// # Errors
    /// As [`Interpreter::run`], except that running out of text is not an error here.
    pub fn run_streamed(
        &mut self,
        program: &mut ProgramStream,
        text: &str,
        mut handler: Option<&mut dyn MCodeHandler>,
        sink: &mut dyn EventSink,
    ) -> Result<Piece, GcodeError> {
        let mut lines = 0;
        for (i, raw) in text.split('\n').enumerate() {
            let line = u32::try_from(i + 1).unwrap_or(u32::MAX);
            let at = At { line, tag: line, nested: false };
            match self.exec_line(raw, at, handler.as_deref_mut(), sink)? {
                Flow::End(code) => return Ok(Piece::Over(RunOutcome::Ended { line, code })),
                Flow::Percent if program.delimited => return Ok(Piece::Over(RunOutcome::Completed { lines: line })),
                // `%` on the first non-blank line opens a delimited program; the next `%` ends it.
                Flow::Percent if program.started && self.config.rules().percent_inside_refused => {
                    return Err(GcodeError::run(line, RunProblem::PercentInside))
                }
                Flow::Percent => program.delimited = !program.started,
                Flow::OWord => return self.run_flow(text, i, None, program, handler, sink),
                call @ (Flow::Call { .. } | Flow::Return) => {
                    return self.run_flow(text, i + 1, Some(call), program, handler, sink)
                }
                Flow::Continue => {}
            }
            if !program.started {
                program.started = !raw.trim().is_empty();
            }
            lines = line;
        }
        Ok(Piece::RanOut { lines })
    }

    /// Chunked events, for a caller that pulls them (the path planner): when on, a line that
    /// commits keeps its events, and [`Interpreter::emit_held`] hands them out a bounded chunk
    /// at a time — a canned cycle one hole at a time, an arc's polyline 1024 segments at a
    /// time — so a line that expands into millions of moves never sits whole in the caller's
    /// queue. Held events go out before the next line runs in any case.
    pub fn set_chunked_events(&mut self, on: bool) {
        self.chunked = on;
    }

    /// Events held back go out before the next line runs (off the hot path of every line).
    #[cold]
    #[inline(never)]
    fn flush_held(&mut self, sink: &mut dyn EventSink) {
        while self.emit_held(sink) {}
    }

    /// Keeps the committed line's events for [`Interpreter::emit_held`].
    #[cold]
    #[inline(never)]
    fn hold_pending(&mut self) {
        self.held.extend(self.pending.drain(..));
    }

    /// Emits the next part of the events held back by chunked lines: the plain events up to
    /// and including one chunk of a long expansion. Whether more is held.
    pub fn emit_held(&mut self, sink: &mut dyn EventSink) -> bool {
        while let Some(front) = self.held.front_mut() {
            let more = match front {
                Pending::Event(e) => {
                    sink.event(e);
                    false
                }
                Pending::Polyline(p) => p.emit_some(sink),
                Pending::Cycle(c) => c.emit_some(sink),
            };
            if more {
                return true;
            }
            if !matches!(self.held.pop_front(), Some(Pending::Event(_))) {
                return !self.held.is_empty();
            }
        }
        false
    }

    /// Host-side access to the same operations a handler has (positions, parameters, tools,
    /// synchronous G-code, dwell), outside any program. Events of `execute` and `dwell` go to
    /// `sink` tagged with line 0.
    pub fn context<'a>(&'a mut self, sink: &'a mut dyn EventSink) -> Context<'a> {
        Context::new(self, sink, 0)
    }

    /// Restores the start-up modes as M2/M30 do: G54, G17, G90, G91.1, no motion mode, the
    /// initial path mode, G51/G68/G52 cancelled, G92 zeroed. Units, feed, tools, parameters and
    /// the machine position stay.
    pub fn reset(&mut self) {
        self.saved_modal.clear();
        self.modal.end_program(&self.config, &mut self.params);
        self.params.begin();
        self.refresh_mirrors();
    }

    /// Runs `text` as G-code from a handler: no user M-codes, no M2/M30, events tagged `tag`.
    pub(crate) fn run_nested(&mut self, text: &str, tag: u32, sink: &mut dyn EventSink) -> Result<(), GcodeError> {
        for (i, raw) in text.split('\n').enumerate() {
            let line = u32::try_from(i + 1).unwrap_or(u32::MAX);
            match self.exec_line(raw, At { line, tag: line_tag(tag, line), nested: true }, None, sink)? {
                Flow::OWord | Flow::Call { .. } | Flow::Return => {
                    return Err(GcodeError::run(line, RunProblem::FlowInHandler))
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// One line: parse, read, write the assignments, execute, commit or roll back.
    fn exec_line<'h>(
        &mut self,
        text: &str,
        at: At,
        handler: Option<&mut (dyn MCodeHandler + 'h)>,
        sink: &mut dyn EventSink,
    ) -> Result<Flow, GcodeError> {
        if !self.held.is_empty() {
            self.flush_held(sink);
        }
        let line = at.line;
        let block = self.parser.parse_line(text, line)?;
        if block.is_empty() || (self.config.block_delete && block.block_delete()) {
            return Ok(if block.is_percent() {
                Flow::Percent
            } else if block.is_oword() && !(self.config.block_delete && block.block_delete()) {
                Flow::OWord
            } else {
                Flow::Continue
            });
        }
        let mut words = Words::default();
        self.params.begin();
        let read = evaluate(&block, &self.params, &mut self.stack, &mut words, &mut self.assigns);
        let range = &self.config.user_mcodes;
        let user = words.m.as_slice().iter().copied().find(|&m| is_user_mcode(range, m));
        // A user M-code's handler gets the line's comments (the only lines that allocate).
        let comments: Vec<&str> = if user.is_some() { block.comments().collect() } else { Vec::new() };
        read.map_err(|p| GcodeError::run(line, p))?;
        let (mut offsets_written, mut g92_written) = (false, false);
        for (target, v) in &self.assigns {
            let written = match target {
                Target::Number(n) => {
                    offsets_written |= affects_frame(*n);
                    g92_written |= (G92_OFFSET..G92_OFFSET + 3).contains(n);
                    self.params.write(*n, *v)
                }
                Target::Named(name) => self.params.write_named(name, *v),
            };
            if let Err(p) = written {
                self.params.rollback();
                return Err(GcodeError::run(line, p));
            }
        }
        if let Some(code) = user {
            if let Err(problem) = user_line_alone(code, &words, at.nested) {
                self.params.rollback();
                return Err(GcodeError::run(line, problem));
            }
            if offsets_written {
                self.modal.after_offset_write(&self.config, &self.params, g92_written);
            }
            self.refresh_mirrors();
            return self.user_line(code, &words, &comments, at, handler, sink);
        }
        self.pending.clear();
        let mut st = self.modal;
        if offsets_written {
            st.after_offset_write(&self.config, &self.params, g92_written);
        }
        let mut run = LineRun {
            cfg: &self.config,
            params: &mut self.params,
            st,
            out: &mut self.pending,
            w: words,
            line: at.tag,
            nested: at.nested,
        };
        let outcome = run.run();
        let st = run.st;
        match outcome {
            Ok(flow) => {
                self.modal = st;
                if self.chunked {
                    self.hold_pending();
                }
                for pending in self.pending.drain(..) {
                    match pending {
                        Pending::Event(e) => sink.event(&e),
                        Pending::Polyline(mut p) => p.emit(sink),
                        Pending::Cycle(mut c) => c.emit(sink),
                    }
                }
                self.refresh_mirrors();
                Ok(flow)
            }
            Err(p) => {
                self.params.rollback();
                Err(GcodeError::run(line, p))
            }
        }
    }

    /// A user M-code line (already checked by [`user_line_alone`]): the call takes every word;
    /// its assignments are already written.
    fn user_line<'h>(
        &mut self,
        code: u32,
        words: &Words,
        comments: &[&str],
        at: At,
        handler: Option<&mut (dyn MCodeHandler + 'h)>,
        sink: &mut dyn EventSink,
    ) -> Result<Flow, GcodeError> {
        let At { line, tag, .. } = at;
        let args: Vec<(char, f64)> = words.all().collect();
        let Some(handler) = handler else {
            sink.event(&Event::UserMCode(UserCall {
                line: tag,
                code,
                words: args,
                comments: comments.iter().map(|c| (*c).to_string()).collect(),
            }));
            return Ok(Flow::Continue);
        };
        let call = UserMCode::new(code, tag, &args, comments);
        let reply = handler.call(&call, &mut Context::new(self, sink, tag));
        let wrap = |e: GcodeError| GcodeError::HandlerGcode { line, code, inner: Box::new(e) };
        match reply {
            Ok(lines) => {
                if !lines.is_empty() {
                    self.run_nested(&lines.join("\n"), tag, sink).map_err(wrap)?;
                }
                Ok(Flow::Continue)
            }
            Err(HandlerError::Failed(message)) => Err(GcodeError::Handler { line, code, message }),
            Err(HandlerError::Gcode(e)) => Err(wrap(e)),
        }
    }

    /// Updates the read-only parameters that report the state (current units) and publishes
    /// the machine position. Every change of the state ends here.
    fn refresh_mirrors(&mut self) {
        let st = self.modal;
        self.publisher.publish(st.machine);
        self.params.set_mirror(ACTIVE_SYSTEM, f64::from(st.system));
        self.params.set_mirror(TOOL_NUMBER, f64::from(st.tool));
        let off = self.current(self.config.rules().applied_tool_offset(st.tool_offset));
        let pos = self.current(st.program);
        for (i, (o, p)) in [(off.x, pos.x), (off.y, pos.y), (off.z, pos.z)].into_iter().enumerate() {
            let i = u32::try_from(i).unwrap_or(0);
            self.params.set_mirror(TOOL_OFFSET + i, o);
            self.params.set_mirror(POSITION + i, p);
        }
        if self.config.rules().named_predefined_parameters {
            let flag = |b: bool| if b { 1.0 } else { 0.0 };
            let inch = st.units == LengthUnit::Inch;
            let feed = st.feed.map_or(0.0, |f| self.config.machine_unit.convert(f, st.units));
            // In PREDEFINED's order.
            self.params.set_predefined([
                0.0,
                2.9,
                0.0,
                pos.x,
                pos.y,
                pos.z,
                flag(inch),
                flag(!inch),
                flag(st.absolute),
                flag(!st.absolute),
                f64::from(st.tool),
                f64::from(st.selected_tool),
                feed,
                st.speed.unwrap_or(0.0),
            ]);
        }
    }

    /// A triple in machine units, in the current program units.
    fn current(&self, v: Xyz) -> Xyz {
        v.convert(self.config.machine_unit, self.modal.units)
    }

    // ---- readers -------------------------------------------------------------------------

    /// The machine (spindle) position, machine units.
    #[must_use]
    pub fn machine_position(&self) -> Xyz {
        self.modal.machine
    }

    /// A shared, read-only view of [`Interpreter::machine_position`] that follows this
    /// interpreter from now on (every watch of it reads the same cell), for a reader that
    /// cannot borrow the interpreter — a simulated camera triggered from inside an M-code
    /// handler. A clone of the interpreter does not update it.
    pub fn watch_position(&mut self) -> PositionWatch {
        self.publisher.watch(self.modal.machine)
    }

    /// The current point in the program frame (before G51/G68/G52), current units.
    #[must_use]
    pub fn program_position(&self) -> Xyz {
        self.current(self.modal.program)
    }

    /// The current point in the work frame (after G51/G68/G52, before work, G92 and tool
    /// offsets), current units.
    #[must_use]
    pub fn work_position(&self) -> Xyz {
        self.current(self.modal.placement(&self.params).work_of(self.modal.program))
    }

    /// G20 (inch) or G21 (millimetre).
    #[must_use]
    pub fn units(&self) -> LengthUnit {
        self.modal.units
    }

    /// The unit of machine coordinates and events.
    #[must_use]
    pub fn machine_unit(&self) -> LengthUnit {
        self.config.machine_unit
    }

    /// The active motion mode, `None` before the first G0–G3.
    #[must_use]
    pub fn motion_mode(&self) -> Option<MotionMode> {
        self.modal.motion
    }

    /// The arc plane.
    #[must_use]
    pub fn plane(&self) -> Plane {
        self.modal.plane
    }

    /// True under G90, false under G91.
    #[must_use]
    pub fn is_absolute(&self) -> bool {
        self.modal.absolute
    }

    /// True under G90.1 (absolute arc centres), false under G91.1.
    #[must_use]
    pub fn is_arc_absolute(&self) -> bool {
        self.modal.arc_absolute
    }

    /// G61 / G64 (tolerance in machine units).
    #[must_use]
    pub fn path_mode(&self) -> PathMode {
        self.modal.path
    }

    /// The active coordinate system, 1 (G54) … 6 (G59).
    #[must_use]
    pub fn coordinate_system(&self) -> u32 {
        self.modal.system
    }

    /// Origin of coordinate system `system` (1 = G54 … 6 = G59; 0 reads G54, above 6 G59),
    /// machine units.
    #[must_use]
    pub fn work_offset(&self, system: u32) -> Xyz {
        let [x, y, z] = self.params.triple(work_offset_base(system));
        Xyz::new(x, y, z)
    }

    /// The G92 offset, machine units.
    #[must_use]
    pub fn g92_offset(&self) -> Xyz {
        let [x, y, z] = self.params.triple(G92_OFFSET);
        Xyz::new(x, y, z)
    }

    /// The feed rate as programmed: machine units per minute, or per spindle revolution under
    /// G95 (`None` before any `F` without a default). Feed moves carry the rate per minute.
    #[must_use]
    pub fn feed(&self) -> Option<f64> {
        self.modal.feed
    }

    /// The tool loaded by the last M6 (0 = none).
    #[must_use]
    pub fn active_tool(&self) -> u32 {
        self.modal.tool
    }

    /// The tool named by the last `T` (loaded by the next M6).
    #[must_use]
    pub fn selected_tool(&self) -> u32 {
        self.modal.selected_tool
    }

    /// The tool table as it is now (machine units): the start-up table with every
    /// [`Interpreter::set_tool`] and tool-offset write applied.
    #[must_use]
    pub fn tools(&self) -> &ToolTable {
        &self.config.tools
    }

    /// Tool `tool`'s X/Y offset and Z length in current units, `None` when not in the table.
    #[must_use]
    pub fn tool_offset(&self, tool: u32) -> Option<Xyz> {
        self.config.tools.get(tool).map(|t| self.current(t.offset))
    }

    /// The active G51/G68/G52 as one chain in current units; `None` when it is the identity
    /// (all three cancelled).
    #[must_use]
    pub fn active_alignment(&self) -> Option<AlignmentChain> {
        let chain = self.modal.frame.chain;
        if chain == AlignmentChain::IDENTITY {
            return None;
        }
        let (from, to) = (self.config.machine_unit, self.modal.units);
        Some(AlignmentChain {
            scale: chain.scale,
            center: Point2::new(from.convert(chain.center.x, to), from.convert(chain.center.y, to)),
            rotation_deg: chain.rotation_deg,
            shift: Vector2::new(from.convert(chain.shift.x, to), from.convert(chain.shift.y, to)),
        })
    }

    /// Parameter `#n` (0 for numbers outside the dialect's range, [`crate::Dialect::last_parameter`]).
    #[must_use]
    pub fn param(&self, n: u32) -> f64 {
        self.params.get(n)
    }

    /// Parameter `#n`, refused outside the dialect's range; reported at `line`.
    pub(crate) fn read_param(&self, n: u32, line: u32) -> Result<f64, GcodeError> {
        if !self.params.exists(n) {
            return Err(GcodeError::run(line, self.params.bad(f64::from(n))));
        }
        Ok(self.params.get(n))
    }
}

/// A user M-code must be alone on its line (its words are its arguments) and may not appear in
/// G-code a handler runs.
fn user_line_alone(code: u32, words: &Words, nested: bool) -> Result<(), RunProblem> {
    if nested {
        return Err(RunProblem::NestedUserMCode { code });
    }
    if let Some(&g) = words.g.as_slice().first() {
        return Err(RunProblem::UserMCodeNotAlone { code, other: crate::GCode(g).to_string() });
    }
    if words.m.as_slice().len() > 1 {
        let other = words.m.as_slice().iter().copied().find(|&m| m != code).unwrap_or(code);
        return Err(RunProblem::UserMCodeNotAlone { code, other: format!("M{other}") });
    }
    Ok(())
}

/// Whether M`code` goes to the handler.
fn is_user_mcode(range: &std::ops::RangeInclusive<u32>, code: u32) -> bool {
    !is_builtin_m(code) && range.contains(&code)
}

/// Events from handler G-code carry the M-code's line; outside a program (tag 0) they carry
/// their own line in the text.
fn line_tag(tag: u32, line: u32) -> u32 {
    if tag == 0 {
        line
    } else {
        tag
    }
}
