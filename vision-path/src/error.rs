//! The one error type of `vision-path`.

/// Why a configuration, a program or a run was refused. Every message says what to do.
///
/// Errors that belong to a program line carry it ([`PathError::line`]); the setpoint stream
/// delivers them at their place, after bringing the machine to rest at the end of the last
/// good motion.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PathError {
    /// A limit, the period or another configuration number is out of range.
    #[error("{what} = {} is invalid: {reason}", vision_math::show::number(*value))]
    InvalidConfig {
        /// The setting, with its unit (`max path acceleration (units/s²)`).
        what: &'static str,
        /// The value given.
        value: f64,
        /// What is allowed.
        reason: &'static str,
    },
    /// A motion segment, dwell or event cannot be executed as given.
    #[error("line {line}: {reason}")]
    InvalidItem {
        /// Source line of the item.
        line: usize,
        /// What is wrong and what to do.
        reason: String,
    },
    /// The G-code interpreter (or another item source) failed at a line.
    #[error("{}: {message}", vision_gcode::error::source_position(*line as u64, *column))]
    Program {
        /// Source line where the program failed.
        line: usize,
        /// The column (1-based, characters) of a syntax error.
        column: Option<u32>,
        /// The source's message.
        message: String,
    },
    /// A program moves an axis that no drive is mapped to.
    #[error("line {line}: the program moves the {axis} axis, but no drive is mapped to {axis}; map it (axis → drive) or remove the move")]
    UnmappedAxis {
        /// Source line of the move.
        line: usize,
        /// `'X'`, `'Y'` or `'Z'`.
        axis: char,
    },
    /// M3/M4/M5 names a tool that is not in the tool table.
    #[error("line {line}: tool {tool} is not configured; define it (tool → clockwise / counter-clockwise outputs) before starting the path")]
    UnknownTool {
        /// Source line of the M-code.
        line: usize,
        /// The tool number.
        tool: u32,
    },
    /// M3/M4/M5 without `$n` before any `T… M6`.
    #[error("line {line}: no tool is selected; use `M3 $n`, or select one first with `T<n> M6`")]
    NoToolSelected {
        /// Source line of the M-code.
        line: usize,
    },
    /// The tool table or the axis map is inconsistent.
    #[error("{0}")]
    BadMapping(String),
    /// `start` while a path is still running.
    #[error("a path is already running; stop it (or wait for it) before starting another")]
    AlreadyRunning,
    /// The motion sink (drives or I/O) refused a setpoint or an output.
    #[error("the drive/output sink failed: {message}; motion was halted")]
    Sink {
        /// The sink's message.
        message: String,
    },
}

impl PathError {
    /// The program line the error belongs to, if any.
    pub fn line(&self) -> Option<usize> {
        match self {
            PathError::InvalidItem { line, .. }
            | PathError::Program { line, .. }
            | PathError::UnmappedAxis { line, .. }
            | PathError::UnknownTool { line, .. }
            | PathError::NoToolSelected { line } => Some(*line),
            _ => None,
        }
    }
}
