//! The Non-Procedural protocol, pure: framing, reply parsing and the command/reply state
//! machine over any `Read + Write` (the socket transport is a thin edge around it).

mod framing;
#[cfg(test)]
mod generate;
#[cfg(test)]
mod mock;
mod reply;
mod session;

pub use framing::{Limits, CR, LF};
pub use reply::{
    parse_data_line, parse_error_reply, parse_program, parse_version, quote, quote_bytes, ErrorReply,
    MAX_ABS_ANGLE_DEG, MAX_ABS_PIXELS, MAX_ABS_SCORE, MAX_COUNT,
};
pub use session::{JobCommand, Program, Session, MAX_COMMAND_LEN, MAX_JOB};
