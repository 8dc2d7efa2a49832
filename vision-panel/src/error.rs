//! [`PanelError`]: why the panel cannot serve.

use std::net::SocketAddr;

/// Why the panel cannot serve.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PanelError {
    /// An address other than loopback without a token.
    #[error(
        "--listen {listen}: not a loopback address, so the camera's view would be open to the network — give \
         --token, or listen on 127.0.0.1"
    )]
    TokenRequired {
        /// The address asked for.
        listen: SocketAddr,
    },
    /// A token that is empty, over 256 characters, or not URL-safe.
    #[error("--token: give 1 to 256 of the characters A-Z a-z 0-9 - . _ ~")]
    BadToken,
    /// The address could not be bound.
    #[error("cannot listen on {listen}: {reason}")]
    Bind {
        /// The address asked for.
        listen: SocketAddr,
        /// The system's reason.
        reason: String,
    },
}
