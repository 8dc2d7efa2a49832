//! Keyence VS-series camera driver: the Non-Procedural command protocol over TCP.

mod config;
mod driver;
pub mod emulator;
mod error;
pub mod protocol;
mod transport;

pub use config::{KeyenceConfig, DEFAULT_PORT, DEFAULT_TIMEOUT, MAX_TIMEOUT};
pub use driver::{register, KeyenceDriver, DRIVER_NAME};
pub use error::{er_meaning, KeyenceError};
pub use protocol::{JobCommand, Limits, Program};
