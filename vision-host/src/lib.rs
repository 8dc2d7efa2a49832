//! The Vision session every front end runs the M-codes through: the CLI on the simulated
//! machine, Mach4's Lua module (`vision-lua`) and LinuxCNC's Python module (`vision-py`) on
//! their controllers.
//!
//! * [`Session`]: owns the [`vision_core::VisionModule`] (parameters, dot list, camera driver,
//!   profile) and runs one M-code at a time on a [`vision_core::Machine`] through
//!   `vision-mcode`; the module runs its commands on that machine as it goes (the machine writes
//!   them in its controller's G-code text, from `vision-mcode`). For a controller whose M-code
//!   cannot both move and trigger (LinuxCNC), M283 also runs stepwise: [`Session::walk_begin`],
//!   then [`Session::walk_next`] → the machine moves → [`Session::walk_capture`], then
//!   [`Session::walk_finish`].
//! * [`ProgramHandler`]: the interpreter's M280–M284 handler that runs a whole program on the
//!   simulated machine ([`ContextMachine`], telling time by a [`Clock`]) through a [`Session`]
//!   (what `mach-vision run` does).
//! * [`cameras`]: the one list of camera drivers, with their settings; [`registry`]: the ones a
//!   real machine can use (no simulator), picked by `VisionDriver`.
//! * [`panel`]: the folder beside a profile (`P.panel/`) a bridge's session publishes its state
//!   into ([`Session::publish`]) for `mach-vision panel --profile P`, and its reader.
//!
//! A bridge implements [`vision_core::Machine`] over its controller's API and nothing else;
//! every rule that differs between controllers is the machine's
//! [`vision_core::Controller`].
//!
//! ```
//! use vision_host::{registry, HostError, Session};
//!
//! // A profile that does not exist yet: a fresh, disabled module (every M-code is refused
//! // with the manual's "Vision is not enabled" until the integrator enables it).
//! let profile = std::env::temp_dir().join("vision-host-doc-missing.toml");
//! let session = Session::open(&profile, &registry())?;
//! assert!(!session.module().params().enabled());
//! # Ok::<(), HostError>(())
//! ```

mod cameras;
mod error;
mod handler;
mod machine;
pub mod panel;
mod session;
#[cfg(feature = "testkit")]
pub mod testkit;

pub use cameras::{cameras, sim_image_config, SimFrames, SIM_IMAGE};
pub use error::HostError;
pub use handler::{ProgramHandler, Record, MAX_RECORDS};
pub use machine::{fixed_clock, system_clock, Clock, ContextMachine};
pub use session::{registry, Session};
/// The machine trait a bridge implements, its errors, and the controllers.
pub use vision_core::controller::{self, linuxcnc};
/// How a bridge makes a message safe to show (control characters escaped, huge quoted input
/// cut): the same rule as the CLI's.
pub use vision_core::text::{printable_line, MAX_MESSAGE_CHARS};
pub use vision_core::{Controller, Machine, MachineCommand, MachineError, MachineErrorKind, ParamValue, Timestamp};
