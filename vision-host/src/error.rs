//! The one error type of the host session.

use vision_mcode::McodeError;

/// Why a Vision M-code or the session failed. Its message is what the operator sees.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum HostError {
    /// The M-code was refused (bad word, or the Vision module's refusal: the manual's message).
    #[error("{0}")]
    Mcode(#[from] McodeError),
    /// The controller refused a call (in its own words, e.g. a non-zero Mach4 return code).
    #[error("controller: {message}")]
    Host {
        /// What the controller said went wrong.
        message: String,
    },
    /// The session could not start: the profile or the camera driver.
    #[error("Vision session: {message}")]
    Setup {
        /// What went wrong and what to do.
        message: String,
    },
}

impl HostError {
    /// A controller failure with `message`.
    pub fn host(message: impl Into<String>) -> HostError {
        HostError::Host { message: message.into() }
    }
}
