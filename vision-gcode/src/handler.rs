//! The extension point: user M-codes (default M100–M999) and what their handler may do.

use vision_math::{AlignmentChain, LengthUnit};

use crate::error::{GcodeError, RunProblem};
use crate::event::{Event, EventSink};
use crate::geom::Xyz;
use crate::Interpreter;

/// One user M-code call: its number, the line's other words (evaluated) and its comments.
#[derive(Debug, Clone, Copy)]
pub struct UserMCode<'a> {
    code: u32,
    line: u32,
    words: &'a [(char, f64)],
    comments: &'a [&'a str],
}

impl<'a> UserMCode<'a> {
    /// A call of M`code` at `line` with `words` (letter upper case, `$` allowed) and `comments`.
    #[must_use]
    pub fn new(code: u32, line: u32, words: &'a [(char, f64)], comments: &'a [&'a str]) -> UserMCode<'a> {
        UserMCode { code, line, words, comments }
    }

    /// The M number.
    #[must_use]
    pub fn code(&self) -> u32 {
        self.code
    }

    /// The line of the call.
    #[must_use]
    pub fn line(&self) -> u32 {
        self.line
    }

    /// The value of word `letter` (case-insensitive), if present.
    #[must_use]
    pub fn word(&self, letter: char) -> Option<f64> {
        let letter = letter.to_ascii_uppercase();
        self.words.iter().find(|(l, _)| *l == letter).map(|(_, v)| *v)
    }

    /// All words, alphabetical (`$` last).
    #[must_use]
    pub fn words(&self) -> &'a [(char, f64)] {
        self.words
    }

    /// The first comment on the line (inside `( )` or after `;`), untrimmed.
    #[must_use]
    pub fn comment(&self) -> Option<&'a str> {
        self.comments.first().copied()
    }

    /// Every comment on the line, in order.
    #[must_use]
    pub fn comments(&self) -> &'a [&'a str] {
        self.comments
    }
}

/// Why a handler failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HandlerError {
    /// The handler's own failure, in its words (what went wrong and what to do).
    #[error("{0}")]
    Failed(String),
    /// G-code the handler ran through [`Context::execute`] failed.
    #[error(transparent)]
    Gcode(#[from] GcodeError),
}

/// Executes user M-codes. This is how M280–M284 plug in.
pub trait MCodeHandler {
    /// Runs `call`. `ctx` reads and writes parameters, reads positions and state, writes tool
    /// offsets and runs G-code synchronously. The returned lines run right after the call, in
    /// place, with the call's line number.
    ///
    /// # Errors
    /// [`HandlerError`]; the program stops at the M-code's line.
    fn call(&mut self, call: &UserMCode<'_>, ctx: &mut Context<'_>) -> Result<Vec<String>, HandlerError>;
}

/// What a handler (or a host outside any program) may do to the interpreter.
///
/// Lengths are in the **current** program units (G20/G21) unless a method says machine units.
pub struct Context<'a> {
    interp: &'a mut Interpreter,
    sink: &'a mut dyn EventSink,
    line: u32,
}

impl<'a> Context<'a> {
    pub(crate) fn new(interp: &'a mut Interpreter, sink: &'a mut dyn EventSink, line: u32) -> Context<'a> {
        Context { interp, sink, line }
    }

    /// The line of the M-code being served (0 outside a program).
    #[must_use]
    pub fn line(&self) -> u32 {
        self.line
    }

    /// The interpreter, for every reader ([`Interpreter::program_position`],
    /// [`Interpreter::coordinate_system`], …).
    #[must_use]
    pub fn interpreter(&self) -> &Interpreter {
        self.interp
    }

    /// Runs G-code now, on the same modal state, and returns when it is done. Its events go to
    /// the same sink, tagged with the M-code's line. User M-codes and M2/M30 in it are errors.
    ///
    /// # Errors
    /// The failing line (numbered from 1 within `text`); it changed nothing, and later lines did
    /// not run.
    pub fn execute(&mut self, text: &str) -> Result<(), GcodeError> {
        self.interp.run_nested(text, self.line, self.sink)
    }

    /// Emits a dwell of `seconds` (the simulated machine does not wait).
    ///
    /// # Errors
    /// [`RunProblem::Negative`] for a negative time, [`RunProblem::NonFinite`] for NaN/inf.
    pub fn dwell(&mut self, seconds: f64) -> Result<(), GcodeError> {
        if !seconds.is_finite() {
            return Err(GcodeError::run(self.line, RunProblem::NonFinite { what: "the dwell time" }));
        }
        if seconds < 0.0 {
            return Err(GcodeError::run(
                self.line,
                RunProblem::Negative { code: "dwell", letter: 'P', value: seconds },
            ));
        }
        self.sink.event(&Event::Dwell { line: self.line, seconds });
        Ok(())
    }

    /// Saves the modal state (see [`Interpreter::push_modal_state`]): what a host does before
    /// moves of its own.
    ///
    /// # Errors
    /// As [`Interpreter::push_modal_state`].
    pub fn push_modal_state(&mut self) -> Result<(), GcodeError> {
        self.interp.push_modal_state()
    }

    /// Restores the modal state saved last (see [`Interpreter::pop_modal_state`]).
    ///
    /// # Errors
    /// As [`Interpreter::pop_modal_state`].
    pub fn pop_modal_state(&mut self) -> Result<(), GcodeError> {
        self.interp.pop_modal_state()
    }

    /// Parameter `#n`.
    ///
    /// # Errors
    /// [`RunProblem::BadParameter`] for `n` outside the dialect's range
    /// ([`crate::Dialect::last_parameter`]).
    pub fn pound(&self, n: u32) -> Result<f64, GcodeError> {
        self.interp.read_param(n, self.line)
    }

    /// Writes parameter `#n`; offset parameters take effect at once (in every dialect: a
    /// handler's write stands for the control's offset table).
    ///
    /// # Errors
    /// [`RunProblem::ReadOnlyParameter`], [`RunProblem::BadParameter`], a non-finite value.
    pub fn set_pound(&mut self, n: u32, value: f64) -> Result<(), GcodeError> {
        self.interp.write_param(n, value, self.line)
    }

    /// The current point in the program frame (before G51/G68/G52), current units.
    #[must_use]
    pub fn program_position(&self) -> Xyz {
        self.interp.program_position()
    }

    /// The current point in the work frame (after G51/G68/G52), current units.
    #[must_use]
    pub fn work_position(&self) -> Xyz {
        self.interp.work_position()
    }

    /// The machine (spindle) position, machine units.
    #[must_use]
    pub fn machine_position(&self) -> Xyz {
        self.interp.machine_position()
    }

    /// G20 / G21.
    #[must_use]
    pub fn units(&self) -> LengthUnit {
        self.interp.units()
    }

    /// The tool loaded by the last M6 (0 = none).
    #[must_use]
    pub fn active_tool(&self) -> u32 {
        self.interp.active_tool()
    }

    /// Tool `tool`'s X/Y offset and Z length, current units.
    ///
    /// # Errors
    /// [`RunProblem::UnknownTool`].
    pub fn tool_offset(&self, tool: u32) -> Result<Xyz, GcodeError> {
        self.interp.tool_offset(tool).ok_or(GcodeError::run(self.line, RunProblem::UnknownTool { tool }))
    }

    /// Writes tool `tool`'s X/Y offset (current units), keeping its length; effective from the
    /// next move (the machine stays, the program position is re-derived for the active tool).
    ///
    /// # Errors
    /// [`RunProblem::UnknownTool`] (also for tool 0), a non-finite value.
    pub fn set_tool_offset(&mut self, tool: u32, x: f64, y: f64) -> Result<(), GcodeError> {
        self.interp.write_tool_offset(tool, x, y, self.line)
    }

    /// Makes `chain` (current units; `None`: none) the alignment every later move is mapped
    /// through, as a host that rewrites the program's points applies it: it replaces the
    /// G51/G68/G52 X/Y modals and [`Context::active_alignment`] reads it back.
    ///
    /// # Errors
    /// A non-finite number, a centre or shift out of range, a zero scale factor.
    pub fn set_host_alignment(&mut self, chain: Option<AlignmentChain>) -> Result<(), GcodeError> {
        self.interp.write_host_alignment(chain, self.line)
    }

    /// The active G51/G68/G52 in current units, `None` when all are cancelled.
    #[must_use]
    pub fn active_alignment(&self) -> Option<AlignmentChain> {
        self.interp.active_alignment()
    }
}
