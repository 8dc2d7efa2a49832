//! [`PanelState`]: what `state.json` in a panel folder holds, and [`read`], its reader.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use vision_core::ParamValue;

/// The version of `state.json` this build writes and reads.
pub const FORMAT: u32 = 1;

/// The state file's name inside the panel folder.
pub const STATE_FILE: &str = "state.json";

/// The last image's file name inside the panel folder (PNG).
pub const FRAME_FILE: &str = "frame.png";

/// The largest `state.json` [`read`] accepts, bytes: the writer caps what it lists, so a bigger
/// file is not one of ours.
pub const MAX_STATE_BYTES: u64 = 4 << 20;

/// The most calibrations a state lists: the newest are kept.
pub const MAX_CALIBRATIONS: usize = 20;

/// The parameters a calibration's history entry keeps: K, the camera tool's offset, the pixel
/// centre, the units they are in, and the lens with its 1σ.
pub const CALIBRATION_PARAMS: [&str; 18] = [
    "VisionCal_K11",
    "VisionCal_K12",
    "VisionCal_K21",
    "VisionCal_K22",
    "VisionCal_ToolOffsetX",
    "VisionCal_ToolOffsetY",
    "VisionPxCenterOffsetX",
    "VisionPxCenterOffsetY",
    "VisionCal_Units",
    "VisionLensK1",
    "VisionLensK2",
    "VisionLensP1",
    "VisionLensP2",
    "VisionLensK1Sigma",
    "VisionLensK2Sigma",
    "VisionLensP1Sigma",
    "VisionLensP2Sigma",
    "VisionLensFocalPx",
];

/// One calibration M283 saved, as the profile held it right after: for the panel's history.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PanelCalibration {
    /// `VisionCal_Date`, as M283 stamped it.
    pub date: String,
    /// [`CALIBRATION_PARAMS`] by manual name.
    pub values: BTreeMap<String, PanelValue>,
}

/// The panel folder of profile file `profile`: `P.toml` → `P.panel` beside it.
#[must_use]
pub fn panel_dir(profile: &Path) -> PathBuf {
    profile.with_extension("panel")
}

/// A parameter's value as the panel shows it: JSON's boolean, integer, number or string.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum PanelValue {
    /// Yes / No.
    Bool(bool),
    /// An integer.
    Int(i64),
    /// A real number (always finite).
    Number(f64),
    /// Text.
    Text(String),
}

impl From<ParamValue> for PanelValue {
    /// A non-finite number becomes its text (`NaN`, `inf`): JSON has no such number.
    fn from(v: ParamValue) -> PanelValue {
        match v {
            ParamValue::Bool(b) => PanelValue::Bool(b),
            ParamValue::Int(i) => PanelValue::Int(i),
            ParamValue::Float(f) if f.is_finite() => PanelValue::Number(f),
            ParamValue::Float(f) => PanelValue::Text(f.to_string()),
            ParamValue::Text(t) => PanelValue::Text(t),
        }
    }
}

/// The last Vision M-code a session ran, as the operator saw it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LastCall {
    /// The M number (280–284).
    pub mcode: u32,
    /// Whether it succeeded.
    pub ok: bool,
    /// The status line on success, the refusal's message otherwise.
    pub message: String,
    /// The G-code lines it ran (a record, never to be run again).
    pub gcode: Vec<String>,
    /// The call's report as `run --json` writes it (capture, fit, calibration, job), when it
    /// succeeded.
    pub report: Option<serde_json::Value>,
}

/// One capture of the current run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PanelDot {
    /// Commanded camera position, program frame, `[x, y]` in `unit`.
    pub commanded: [f64; 2],
    /// Observed mark centre, program frame, `[x, y]` in `unit`.
    pub observed: [f64; 2],
    /// `"in"` or `"mm"`.
    pub unit: PanelUnit,
}

/// A length unit in the panel's files.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum PanelUnit {
    /// Inches.
    #[serde(rename = "in")]
    Inch,
    /// Millimetres.
    #[serde(rename = "mm")]
    Millimetre,
}

/// What a session publishes into its panel folder, and what [`read`] hands back.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PanelState {
    /// [`FORMAT`].
    pub format: u32,
    /// Grows with every state the session publishes (across restarts too); a reader that sees
    /// the same number has nothing new.
    pub seq: u64,
    /// When the state was taken, seconds since the Unix epoch.
    pub time_unix: f64,
    /// The profile file the session runs with.
    pub profile: String,
    /// The persisted parameters by manual name.
    pub params: BTreeMap<String, PanelValue>,
    /// The telemetry (`VisionLast*`, `VisionRun_*`) by manual name.
    pub telemetry: BTreeMap<String, PanelValue>,
    /// The last Vision M-code, if any ran.
    pub last: Option<LastCall>,
    /// The current run's captures, in order (the first [`super::MAX_DOTS`]).
    pub dots: Vec<PanelDot>,
    /// [`FRAME_FILE`] when the folder holds the last image, else `None`.
    pub frame: Option<String>,
    /// The calibrations this folder has seen, oldest first (the last [`MAX_CALIBRATIONS`]),
    /// across sessions; absent in a state written before there was a history.
    #[serde(default)]
    pub calibrations: Vec<PanelCalibration>,
}

/// Why a panel folder's state could not be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum PanelReadError {
    /// No `state.json` yet: no session has published into this folder.
    #[error("{path}: no panel state yet (is a Mach4 or LinuxCNC session running with this profile?)")]
    Missing {
        /// The file looked for.
        path: String,
    },
    /// The file could not be read.
    #[error("{path}: {reason}")]
    Io {
        /// The file.
        path: String,
        /// The system's reason.
        reason: String,
    },
    /// The file is bigger than [`MAX_STATE_BYTES`].
    #[error("{path}: over {max} bytes, not a panel state")]
    TooLarge {
        /// The file.
        path: String,
        /// [`MAX_STATE_BYTES`].
        max: u64,
    },
    /// Not JSON, or not the shape of a [`PanelState`].
    #[error("{path}: not a panel state: {reason}")]
    Malformed {
        /// The file.
        path: String,
        /// What the parser said.
        reason: String,
    },
    /// A state of another format (a newer or older mach-vision wrote it).
    #[error("{path}: panel state format {found}, this mach-vision reads format {FORMAT}")]
    Format {
        /// The file.
        path: String,
        /// The file's format.
        found: u32,
    },
    /// Well-formed JSON with a value no writer writes (a negative time, a non-finite number).
    #[error("{path}: {what}")]
    Invalid {
        /// The file.
        path: String,
        /// What is wrong.
        what: String,
    },
}

/// Reads `state.json` in panel folder `dir`.
///
/// # Errors
/// A [`PanelReadError`]; never panics on any file content.
pub fn read(dir: &Path) -> Result<PanelState, PanelReadError> {
    let path = dir.join(STATE_FILE);
    let shown = path.display().to_string();
    let io = |e: std::io::Error| match e.kind() {
        std::io::ErrorKind::NotFound => PanelReadError::Missing { path: shown.clone() },
        _ => PanelReadError::Io { path: shown.clone(), reason: e.to_string() },
    };
    let file = std::fs::File::open(&path).map_err(io)?;
    let mut bytes = Vec::new();
    file.take(MAX_STATE_BYTES + 1).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > MAX_STATE_BYTES {
        return Err(PanelReadError::TooLarge { path: shown, max: MAX_STATE_BYTES });
    }
    parse(&bytes, &shown)
}

/// Parses and checks a state file's bytes (`path` for messages).
///
/// # Errors
/// [`PanelReadError::Malformed`], [`PanelReadError::Format`] or [`PanelReadError::Invalid`].
pub fn parse(bytes: &[u8], path: &str) -> Result<PanelState, PanelReadError> {
    /// The format alone, read first, so a newer writer's file is named as such, not malformed.
    #[derive(Deserialize)]
    struct Head {
        format: u32,
    }
    let malformed = |e: serde_json::Error| PanelReadError::Malformed { path: path.to_string(), reason: e.to_string() };
    let head: Head = serde_json::from_slice(bytes).map_err(malformed)?;
    if head.format != FORMAT {
        return Err(PanelReadError::Format { path: path.to_string(), found: head.format });
    }
    let state: PanelState = serde_json::from_slice(bytes).map_err(malformed)?;
    let invalid = |what: &str| Err(PanelReadError::Invalid { path: path.to_string(), what: what.to_string() });
    if !(state.time_unix.is_finite() && state.time_unix >= 0.0) {
        return invalid("time_unix is not a time");
    }
    let finite = |v: &PanelValue| !matches!(v, PanelValue::Number(x) if !x.is_finite());
    let history = state.calibrations.iter().flat_map(|c| c.values.values());
    if !state.params.values().chain(state.telemetry.values()).chain(history).all(finite) {
        return invalid("a value is not a finite number");
    }
    if !state.dots.iter().flat_map(|d| d.commanded.iter().chain(&d.observed)).all(|x| x.is_finite()) {
        return invalid("a dot is not a finite position");
    }
    if state.calibrations.len() > MAX_CALIBRATIONS {
        return invalid("more calibrations than a writer lists");
    }
    if state.frame.as_deref().is_some_and(|f| f != FRAME_FILE) {
        return invalid("frame names a file other than frame.png");
    }
    Ok(state)
}
