//! A G-code interpreter for the seed-002 dialect (MachineMotion path following) and the Mach
//! alignment modals `G51` / `G68` / `G52` — the machine side of SPEC §6. It proves that the
//! G-code M282 emits moves the tool onto the real part, and lets a whole program run against a
//! simulated machine. It knows nothing of vision: user M-codes (M280–M284 among them) go to an
//! [`MCodeHandler`].
//!
//! * A hand-written line parser (words, `#` parameters, `[expressions]`, comments), private.
//! * [`Interpreter`]: modal state, the frame chain, arcs, tools, outputs; streams [`Event`]s in
//!   machine coordinates to an [`EventSink`], each tagged with its source line.
//! * [`MCodeHandler`] / [`Context`]: the extension point; a handler reads and writes parameters,
//!   reads positions, writes tool offsets and runs G-code synchronously.
//! * [`PositionWatch`] ([`Interpreter::watch_position`]): the machine position, published by
//!   the interpreter for readers that cannot borrow it (a simulated camera).
//!
//! ```
//! use vision_gcode::{Event, Interpreter, InterpreterConfig, Xyz};
//!
//! // An inch machine; M282's alignment: shift, rotate 90° about (3, 2), no scale.
//! let mut interp = Interpreter::new(InterpreterConfig::default());
//! let program = "G90 G20\nG52 X0.1 Y0.05\nG68 X3 Y2 R90\nG0 X6 Y4";
//! let mut events = Vec::new();
//! interp.run(program, None, &mut events)?;
//! // (6, 4) − (3, 2) = (3, 2) → rotated (−2, 3) → + (3, 2) = (1, 5) → + (0.1, 0.05).
//! let m = interp.machine_position();
//! assert!((m - Xyz::new(1.1, 5.05, 0.0)).norm() < 1e-12);
//! assert!(matches!(events.last(), Some(Event::Linear(mv)) if mv.line == 4 && mv.end == m));
//! # Ok::<(), vision_gcode::GcodeError>(())
//! ```
//!
//! [`InterpreterConfig`] sets the machine unit, the tool table, the G-code dialect
//! ([`Dialect`]: seed 002's `MachineMotion`, `Mach4`, `LinuxCnc`, for the few rules where the
//! controllers differ) and the limits. [`Interpreter::run`] runs a whole text;
//! [`Interpreter::run_streamed`] runs a program fed in pieces by the same rules (the path
//! planner streams it line by line; from its first o-word line on, [`Interpreter::start_flow`]
//! and [`Interpreter::step_flow`] run it a line at a time, and
//! [`Interpreter::set_chunked_events`] hands a long line's events out in bounded chunks).
//! Memory does not grow with a program's moves or loop iterations: events are never collected,
//! a canned cycle's holes are walked rather than held, and every repeat count is at most
//! [`MAX_REPEATS`]. A failing line changes nothing and emits nothing; the
//! error ([`GcodeError`]) names the line and what to do.
//!
//! How it works and why — the frame chain, and every decision taken where the spec is open
//! (units, line atomicity, order within a line, LinuxCNC's G-code, o-words, tools, dialects,
//! ranges, arcs, parameters, program end, outputs, syntax) — is in the repository's
//! `docs/gcode-interpreter.md`.

mod arc;
pub mod config;
mod dialect;
pub mod error;
pub mod event;
mod expr;
mod frame;
pub mod geom;
pub mod handler;
mod interp;
mod letters;
pub mod params;
/// The line parser is crate-private; the `bench-internals` feature exposes it (unstable, not
/// part of the API) for the parse-only benchmark.
#[cfg(feature = "bench-internals")]
#[doc(hidden)]
pub mod parse;
#[cfg(not(feature = "bench-internals"))]
mod parse;
pub mod tools;
mod watch;
mod whole;
mod words;

pub use arc::{CENTRE_TOLERANCE_INCH, CENTRE_TOLERANCE_MM, RADIUS_TOLERANCE_INCH, RADIUS_TOLERANCE_MM};
pub use config::InterpreterConfig;
pub use dialect::{CommentRule, Dialect, DialectRules, OffsetParts};
pub use error::{GCode, GcodeError, RunProblem, SyntaxProblem};
pub use event::{
    ArcMove, Coolant, Event, EventSink, LinearMove, OutputChange, OutputWrite, PathMode, Rate, SpindleCommand, UserCall,
};
pub use geom::{ArcDirection, Plane, Xyz, MAX_COORDINATE};
pub use handler::{Context, HandlerError, MCodeHandler, UserMCode};
pub use interp::{
    needs_program, FlowRun, Interpreter, MotionMode, Piece, ProgramStream, RunOutcome, MAX_CYCLE_MOVES, MAX_REPEATS,
    MAX_SAVED_MODAL_STATES,
};
pub use tools::{DigitalOutput, Tool, ToolOutputs, ToolTable};
pub use watch::PositionWatch;
