//! The Vision session a CNC controller bridge keeps alive between M-code calls, shared by every
//! host (Mach4's Lua module `vision-lua`, LinuxCNC's Python module).
//!
//! * [`Host`]: the few callbacks a controller offers (run a G-code line and wait, pound
//!   variables, tool X/Y offsets, position, units, dwell, a message to the operator). A bridge
//!   implements it over its controller's API and nothing else.
//! * [`Session`]: owns the [`vision_core::VisionModule`] (parameters, dot list, camera driver,
//!   profile), runs one M-code at a time on a [`Host`] through `vision-mcode`, and runs the
//!   G-code the module emits on the host — the one place that G-code leaves the library. For a
//!   host whose M-code cannot both move and trigger (LinuxCNC), M283 also runs stepwise:
//!   [`Session::walk_begin`], then [`Session::walk_next`] → the host moves →
//!   [`Session::walk_capture`], then [`Session::walk_finish`].
//! * [`cameras`]: the one list of camera drivers, with their settings; [`registry`]: the ones a
//!   real machine can use (no simulator), picked by `VisionDriver`.
//!
//! The key decision: controllers do not report the G51/G68/G52 chain they have active, so the
//! session remembers the chain its own M282 emitted (M280 cancels it) and tells the module. A
//! host that can at least tell whether an alignment is active ([`Host::alignment_active`]) lets
//! the session forget a chain the program cancelled itself; on one that cannot (Mach4), run M280
//! before capturing or calibrating in a program that follows an aligned one.
//!
//! LinuxCNC ([`Controller::LinuxCnc`]) is different: it has no G68 and no G51, so M282 rotates
//! the G5x system and shifts with G52 and cannot scale ([`vision_math::linuxcnc`]); it keeps
//! that rotation and G52 across restarts, so the alignment's flag and the rotation before it
//! (θ₀) live in persistent parameters ([`linuxcnc::PERSISTENT_PARAMS`]) and the session reads
//! the active alignment from the host at every call.
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
mod host;
mod session;
#[cfg(feature = "testkit")]
pub mod testkit;

pub use cameras::cameras;
pub use error::HostError;
pub use host::Host;
pub use session::{registry, Session};
/// How a bridge makes a message safe to show (control characters escaped, huge quoted input
/// cut): the same rule as the CLI's.
pub use vision_core::text::{printable_line, MAX_MESSAGE_CHARS};
/// The controller a [`Host`] is ([`Host::controller`]), and LinuxCNC's persistent parameters.
pub use vision_core::{linuxcnc, Controller};
