//! The M280–M284 adapter between a G-code program and the Vision module.
//!
//! * [`VisionCall::parse`]: an M-code and the words of its line → a typed call (unknown
//!   letters, repeated words, non-finite and out-of-range values refused with a clear message).
//! * [`VisionCall::run`]: dispatches to [`vision_core::VisionModule`] and returns an
//!   [`Outcome`]: the module's report, and the G-code it ran on the machine
//!   ([`Outcome::gcode`]; M282's lines formatted by `vision_math::AlignmentChain::gcode`: fixed
//!   decimals that move no point by more than 1e-6 units; never NaN, inf or `-0`).
//! * [`ContextMachine`]: the simulated machine, the one [`vision_core::Machine`] over the
//!   interpreter (inside an M-code handler, or around a standalone interpreter), so the
//!   module's moves run synchronously on it. `vision-host`'s session runs the M-codes on it as
//!   on any controller.
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
mod machine;
mod outcome;

pub use call::{McodeSpec, VisionCall, WordSpec, MCODES, VISION_MCODES};
pub use error::McodeError;
pub use machine::{fixed_clock, system_clock, Clock, ContextMachine};
pub use outcome::Outcome;
