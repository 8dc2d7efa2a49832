//! The one error type of the host session.

use vision_core::{MachineError, MachineErrorKind};
use vision_mcode::McodeError;

/// Why a Vision M-code or the session failed. Its message is what the operator sees.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum HostError {
    /// The M-code was refused (bad word, or the Vision module's refusal: the manual's message;
    /// a machine failure during the call is [`vision_core::VisionError::Machine`] inside it).
    #[error("{0}")]
    Mcode(#[from] McodeError),
    /// The controller failed a call the bridge made outside the Vision module (reading the
    /// M-code's words, the profile's path, …).
    #[error("{0}")]
    Machine(#[from] MachineError),
    /// A parameter read by a name no parameter has ([`vision_core::VisionError::UnknownParam`]).
    #[error("{0}")]
    Param(vision_core::VisionError),
    /// The session could not start: the profile or the camera driver.
    #[error("Vision session: {message}")]
    Setup {
        /// What went wrong and what to do.
        message: String,
    },
}

impl HostError {
    /// A controller failure with `message`, of kind [`MachineErrorKind::Communication`] (a
    /// scripting call that failed or answered a value of the wrong type).
    pub fn host(message: impl Into<String>) -> HostError {
        HostError::Machine(MachineError::new(MachineErrorKind::Communication, message.into()))
    }

    /// The machine failure behind this error, wherever it sits, for a bridge that reacts to its
    /// [`MachineError::kind`] (an e-stop is not a missing tool).
    #[must_use]
    pub fn machine_error(&self) -> Option<&MachineError> {
        match self {
            HostError::Machine(e) | HostError::Mcode(McodeError::Vision(vision_core::VisionError::Machine(e))) => {
                Some(e)
            }
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vision_core::VisionError;

    #[test]
    fn a_bridge_finds_the_machine_failure_and_its_kind_wherever_it_sits() {
        let stop = MachineError::new(MachineErrorKind::Stopped, "feed hold");
        let inside = HostError::Mcode(McodeError::Vision(VisionError::Machine(stop.clone())));
        assert_eq!(inside.machine_error().map(MachineError::kind), Some(MachineErrorKind::Stopped));
        assert_eq!(inside.to_string(), "machine: feed hold");
        let outside = HostError::host("mc.mcCntlGetLocalVar returned nil");
        assert_eq!(outside.machine_error().map(MachineError::kind), Some(MachineErrorKind::Communication));
        let refusal = HostError::Mcode(McodeError::Vision(VisionError::NotEnabled));
        assert_eq!(refusal.machine_error(), None);
    }
}
