//! Keyence VS-series driver (placeholder doc, completed later).

mod error;
pub mod protocol;

pub use error::{er_meaning, KeyenceError};
