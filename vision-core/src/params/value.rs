//! What a parameter is: its value ([`ParamValue`]), its type ([`ParamKind`]), who may write it
//! ([`Access`]), the manual's section ([`Section`]) and its description ([`ParamSpec`]).

use std::fmt;

use vision_math::LengthUnit;

/// A parameter value, as the profile, the CLI or a DRO sees it.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamValue {
    /// Yes / No.
    Bool(bool),
    /// An integer.
    Int(i64),
    /// A real number.
    Float(f64),
    /// Text (also the choice parameters, e.g. `Cal_Units` = `in`).
    Text(String),
}

impl ParamValue {
    /// The numeric view a G-code program or DRO reads (Yes = 1, No = 0); `None` for text.
    #[must_use]
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            ParamValue::Bool(b) => Some(if *b { 1.0 } else { 0.0 }),
            ParamValue::Int(i) => Some(*i as f64),
            ParamValue::Float(f) => Some(*f),
            ParamValue::Text(_) => None,
        }
    }
}

impl fmt::Display for ParamValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamValue::Bool(b) => f.write_str(if *b { "Yes" } else { "No" }),
            ParamValue::Int(i) => write!(f, "{i}"),
            ParamValue::Float(x) => write!(f, "{x}"),
            ParamValue::Text(s) => write!(f, "{s:?}"),
        }
    }
}

impl From<bool> for ParamValue {
    fn from(v: bool) -> Self {
        ParamValue::Bool(v)
    }
}
impl From<i64> for ParamValue {
    fn from(v: i64) -> Self {
        ParamValue::Int(v)
    }
}
impl From<i32> for ParamValue {
    fn from(v: i32) -> Self {
        ParamValue::Int(i64::from(v))
    }
}
impl From<u32> for ParamValue {
    fn from(v: u32) -> Self {
        ParamValue::Int(i64::from(v))
    }
}
impl From<f64> for ParamValue {
    fn from(v: f64) -> Self {
        ParamValue::Float(v)
    }
}
impl From<&str> for ParamValue {
    fn from(v: &str) -> Self {
        ParamValue::Text(v.to_string())
    }
}
impl From<String> for ParamValue {
    fn from(v: String) -> Self {
        ParamValue::Text(v)
    }
}
impl From<LengthUnit> for ParamValue {
    fn from(v: LengthUnit) -> Self {
        ParamValue::Text(v.short_name().to_string())
    }
}

/// The type of a parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamKind {
    /// Yes / No (also accepts 1/0, true/false).
    YesNo,
    /// Integer.
    Integer,
    /// Real number.
    Float,
    /// Free text.
    Text,
    /// One of a fixed set of words.
    Choice(&'static [&'static str]),
}

/// Who may write a parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// Configuration or calibration: writable, validated, persisted in the profile.
    Config,
    /// Runtime telemetry: written by the module only, never persisted.
    Telemetry,
}

/// The manual's section a parameter is listed under.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Section {
    /// Connection and camera setup.
    Connection,
    /// K matrix, camera axis flags and pixel centre.
    Calibration,
    /// Pound-variable output and camera tool.
    Output,
    /// Fit quality gates (an addition to the manual).
    Quality,
    /// Last trigger result (telemetry).
    LastResult,
    /// Alignment run state (telemetry).
    RunState,
}

/// Description of one parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParamSpec {
    /// The manual's name, e.g. `VisionCal_K11`.
    pub name: &'static str,
    /// Its type.
    pub kind: ParamKind,
    /// Who may write it.
    pub access: Access,
    /// Its section.
    pub section: Section,
    /// What it means, with units.
    pub doc: &'static str,
    /// Its unit as the parameter reference shows it (`px`, `in`, `s`, `%`, `Cal_Units/px`;
    /// empty: a count, a flag or text).
    pub unit: &'static str,
    /// The values it accepts, worded to follow "must be" (the refusal quotes the same words);
    /// empty: every value of its [`ParamKind`].
    pub range: &'static str,
    /// Who writes it in normal use (`operator`, `M283`, `M284`, …); the operator may edit every
    /// persisted parameter in the profile.
    pub writer: &'static str,
}

impl ParamSpec {
    /// A camera driver's connection setting, which the operator writes: `unit` and `range`
    /// (worded to follow "must be", as the check's refusal says it) for the parameter reference.
    #[must_use]
    pub const fn driver_setting(
        name: &'static str,
        kind: ParamKind,
        unit: &'static str,
        range: &'static str,
        doc: &'static str,
    ) -> Self {
        Self { name, kind, access: Access::Config, section: Section::Connection, doc, unit, range, writer: "operator" }
    }
}
