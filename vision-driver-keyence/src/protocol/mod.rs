//! The Non-Procedural protocol, pure: framing, reply parsing and the command/reply state
//! machine over any `Read + Write` (the socket transport is a thin edge around it).

mod exchange;
mod framing;
#[cfg(test)]
mod generate;
#[cfg(test)]
mod mock;
mod reply;

#[cfg(feature = "emulator")]
pub(crate) use exchange::MAX_COMMAND_LEN;
pub(crate) use exchange::MAX_JOB;
pub use exchange::{Exchange, JobCommand, Program};
pub use framing::Limits;
#[cfg(feature = "emulator")]
pub(crate) use framing::{CR, LF};
pub use reply::parse_data_line;
