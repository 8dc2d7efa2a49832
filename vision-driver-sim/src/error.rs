//! The one error type of the simulator.

/// Why a world or a simulator request was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// The world file is not valid TOML or does not match the schema.
    #[error("world file: {reason} — see the world format in the vision-driver-sim docs or the README")]
    Parse {
        /// The parser's message (with line and column).
        reason: String,
    },
    /// A world value is out of range.
    #[error("world: {field} {reason}")]
    Invalid {
        /// The field, as a path (`camera.units_per_pixel`).
        field: String,
        /// What is allowed.
        reason: String,
    },
    /// No fixture of that name.
    #[error("world has no fixture named {name:?} (fixtures: {known})")]
    UnknownFixture {
        /// The name asked for.
        name: String,
        /// The fixture names, comma-separated.
        known: String,
    },
    /// The kept machine state (tool table and offsets kept beside a profile) is unusable.
    #[error("kept machine state: {reason}")]
    Kept {
        /// What is wrong, with the parser's line and column where it has them.
        reason: String,
    },
    /// The simulated machine refused a request (a G-code error, in its words).
    #[error("simulated machine: {reason}")]
    Machine {
        /// What the interpreter said.
        reason: String,
    },
}
