//! The M280–M284 adapter between a G-code program and the Vision module.
//!
//! * [`VisionCall::parse`]: an M-code and the words of its line → a typed call (unknown
//!   letters, repeated words, non-finite and out-of-range values refused with a clear message).
//! * [`VisionCall::run`]: dispatches to [`vision_core::VisionModule`] and returns an
//!   [`Outcome`]: the module's report, and the G-code it ran on the machine
//!   ([`Outcome::gcode`]).
//! * [`gcode`]: the module's typed commands ([`vision_core::MachineCommand`]: what the
//!   controller decided the machine must do) → each controller's G-code text ([`TEXTS`]), with
//!   fixed decimals that move no point by more than 1e-6 units; never NaN, inf or `-0`. Every
//!   bridge's [`vision_core::Machine::gcode`] answers with it.
//!
//! M-code words in, G-code text out: a new controller is its rules in `vision-core`, its row
//! of [`TEXTS`] here, and its bridge.
//!
//! ```
//! use vision_core::RunMode;
//! use vision_mcode::VisionCall;
//!
//! assert_eq!(VisionCall::parse(280, &[('P', 3.0)])?, VisionCall::Begin(RunMode::Similarity));
//! let refused = VisionCall::parse(281, &[('X', 1.0)]).unwrap_err();
//! assert!(refused.to_string().starts_with("M281 does not take an X word"));
//! # Ok::<(), vision_mcode::McodeError>(())
//! ```

mod call;
mod error;
mod outcome;
mod text;

pub use call::{McodeSpec, VisionCall, WordSpec, MCODES, VISION_MCODES};
pub use error::McodeError;
pub use outcome::Outcome;
pub use text::{gcode, lines, text_of, AlignmentWords, ControllerText, TextError, TEXTS};
