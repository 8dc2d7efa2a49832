//! The OEM parameters (SPEC §5, manual appendix A) under the manual's own names.
//!
//! [`Params`] holds every parameter, typed, with the manual's defaults. Read them with the typed
//! getters (`params.cal_k()`, `params.pound_var_base()`, …) or by name with [`Params::get`];
//! write them by name with [`Params::set`], which validates the value and refuses read-only
//! telemetry. The Vision module writes telemetry itself.
//!
//! Units: lengths follow the parameter's doc (K and the pixel centre offset are per `Cal_Units`;
//! the fit gates are in inches and are converted to millimetres under G21); times are seconds.
//!
//! Decision: the three fit quality gates (`VisionFitMaxScaleDev` in percent, `VisionFitMaxShift`
//! and `VisionFitMaxResidual` in inches) are additions to the manual's set; 0 disables a gate.

use std::fmt;

use vision_math::{LengthUnit, Matrix2, Remap};

use crate::error::VisionError;
use crate::pound::PoundBlock;

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
            #[allow(clippy::cast_precision_loss)] // parameter integers are small
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
    /// K matrix and pixel centre.
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
}

/// A Rust type a parameter can have.
trait ParamType: Sized {
    type Out<'a>
    where
        Self: 'a;
    const KIND: ParamKind;
    fn out(&self) -> Self::Out<'_>;
    fn to_value(&self) -> ParamValue;
    fn from_value(v: &ParamValue) -> Option<Self>;
}

impl ParamType for bool {
    type Out<'a> = bool;
    const KIND: ParamKind = ParamKind::YesNo;
    fn out(&self) -> bool {
        *self
    }
    fn to_value(&self) -> ParamValue {
        ParamValue::Bool(*self)
    }
    fn from_value(v: &ParamValue) -> Option<Self> {
        match v {
            ParamValue::Bool(b) => Some(*b),
            ParamValue::Int(0) => Some(false),
            ParamValue::Int(1) => Some(true),
            ParamValue::Float(f) if *f == 0.0 => Some(false),
            ParamValue::Float(f) if (*f - 1.0).abs() < f64::EPSILON => Some(true),
            ParamValue::Text(s) => match s.trim().to_ascii_lowercase().as_str() {
                "yes" | "true" | "1" | "on" => Some(true),
                "no" | "false" | "0" | "off" => Some(false),
                _ => None,
            },
            _ => None,
        }
    }
}

impl ParamType for i64 {
    type Out<'a> = i64;
    const KIND: ParamKind = ParamKind::Integer;
    fn out(&self) -> i64 {
        *self
    }
    fn to_value(&self) -> ParamValue {
        ParamValue::Int(*self)
    }
    fn from_value(v: &ParamValue) -> Option<Self> {
        match v {
            ParamValue::Int(i) => Some(*i),
            #[allow(clippy::cast_possible_truncation)] // checked integral and in range
            ParamValue::Float(f) if f.fract() == 0.0 && f.abs() < 9.0e15 => Some(*f as i64),
            ParamValue::Text(s) => s.trim().parse().ok(),
            _ => None,
        }
    }
}

impl ParamType for f64 {
    type Out<'a> = f64;
    const KIND: ParamKind = ParamKind::Float;
    fn out(&self) -> f64 {
        *self
    }
    fn to_value(&self) -> ParamValue {
        ParamValue::Float(*self)
    }
    fn from_value(v: &ParamValue) -> Option<Self> {
        match v {
            ParamValue::Float(f) => Some(*f),
            #[allow(clippy::cast_precision_loss)]
            ParamValue::Int(i) => Some(*i as f64),
            ParamValue::Text(s) => s.trim().parse().ok(),
            ParamValue::Bool(_) => None,
        }
    }
}

impl ParamType for String {
    type Out<'a> = &'a str;
    const KIND: ParamKind = ParamKind::Text;
    fn out(&self) -> &str {
        self
    }
    fn to_value(&self) -> ParamValue {
        ParamValue::Text(self.clone())
    }
    fn from_value(v: &ParamValue) -> Option<Self> {
        match v {
            ParamValue::Text(s) => Some(s.clone()),
            _ => None,
        }
    }
}

impl ParamType for LengthUnit {
    type Out<'a> = LengthUnit;
    const KIND: ParamKind = ParamKind::Choice(&["in", "mm"]);
    fn out(&self) -> LengthUnit {
        *self
    }
    fn to_value(&self) -> ParamValue {
        ParamValue::Text(self.short_name().to_string())
    }
    fn from_value(v: &ParamValue) -> Option<Self> {
        match v {
            ParamValue::Text(s) => match s.trim().to_ascii_lowercase().as_str() {
                "in" | "inch" | "inches" => Some(LengthUnit::Inch),
                "mm" | "millimetre" | "millimeter" => Some(LengthUnit::Millimetre),
                _ => None,
            },
            _ => None,
        }
    }
}

type Check<T> = fn(&T) -> Result<(), String>;

fn any<T>(_: &T) -> Result<(), String> {
    Ok(())
}
fn finite(v: &f64) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err("must be a finite number".into())
    }
}
fn non_negative(v: &f64) -> Result<(), String> {
    if v.is_finite() && *v >= 0.0 {
        Ok(())
    } else {
        Err("must be a finite number ≥ 0 (0 disables)".into())
    }
}
fn seconds_60(v: &f64) -> Result<(), String> {
    if v.is_finite() && (0.0..=60.0).contains(v) {
        Ok(())
    } else {
        Err("must be between 0 and 60 seconds".into())
    }
}
fn timeout_s(v: &f64) -> Result<(), String> {
    if v.is_finite() && *v > 0.0 && *v <= 300.0 {
        Ok(())
    } else {
        Err("must be more than 0 and at most 300 seconds".into())
    }
}
fn pixel_offset(v: &f64) -> Result<(), String> {
    if v.is_finite() && v.abs() <= 100_000.0 {
        Ok(())
    } else {
        Err("must be a finite number of pixels (|v| ≤ 100000)".into())
    }
}
fn port(v: &i64) -> Result<(), String> {
    if (1..=65_535).contains(v) {
        Ok(())
    } else {
        Err("must be a TCP port 1..65535".into())
    }
}
fn job(v: &i64) -> Result<(), String> {
    if (0..=999).contains(v) {
        Ok(())
    } else {
        Err("must be a camera job 0..999 (0 = leave the camera's job)".into())
    }
}
fn resolution(v: &i64) -> Result<(), String> {
    if (2..=100_000).contains(v) {
        Ok(())
    } else {
        Err("must be an image size of 2..100000 pixels".into())
    }
}
fn tool(v: &i64) -> Result<(), String> {
    if (0..=i64::from(u32::MAX)).contains(v) {
        Ok(())
    } else {
        Err("must be a tool number ≥ 0 (0 disables the camera-tool check)".into())
    }
}
fn pound_base(v: &i64) -> Result<(), String> {
    PoundBlock::new(*v).map(|_| ()).map_err(|e| e.to_string())
}
#[allow(clippy::ptr_arg)] // the signature is `Check<String>`
fn driver_name(v: &String) -> Result<(), String> {
    if !v.is_empty() && v.len() <= 64 && v.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-') {
        Ok(())
    } else {
        Err("must be a driver name (letters, digits, _ or -), e.g. Keyence".into())
    }
}
#[allow(clippy::ptr_arg)]
fn host(v: &String) -> Result<(), String> {
    let ok = v.parse::<std::net::IpAddr>().is_ok()
        || (!v.is_empty()
            && v.len() <= 253
            && v.chars().all(|c| c.is_ascii_alphanumeric() || c == '.' || c == '-')
            && !v.starts_with('-'));
    if ok {
        Ok(())
    } else {
        Err("must be an IP address (e.g. 192.168.208.80) or a host name".into())
    }
}
#[allow(clippy::ptr_arg)]
fn short_text(v: &String) -> Result<(), String> {
    if v.len() <= 4096 && !v.contains('\0') {
        Ok(())
    } else {
        Err("must be text of at most 4096 bytes".into())
    }
}

macro_rules! params {
    ($(
        $(#[doc = $doc:literal])+
        ($section:ident, $access:ident) $field:ident : $ty:ty => $ret:ty = $default:expr, $name:literal, $check:expr;
    )*) => {
        /// Every Vision parameter, typed, with the manual's defaults (see the module doc).
        ///
        /// Fields are private so that every external write goes through [`Params::set`]
        /// (validated, telemetry refused); read them with the typed getters.
        #[derive(Debug, Clone, PartialEq)]
        pub struct Params {
            $( pub(crate) $field: $ty, )*
        }

        impl Default for Params {
            fn default() -> Self {
                Params { $( $field: $default, )* }
            }
        }

        impl Params {
            $(
                $(#[doc = $doc])+
                #[must_use]
                pub fn $field(&self) -> $ret {
                    ParamType::out(&self.$field)
                }
            )*

            /// Every parameter, in the manual's order.
            pub const SPECS: &'static [ParamSpec] = &[$(
                ParamSpec {
                    name: $name,
                    kind: <$ty as ParamType>::KIND,
                    access: Access::$access,
                    section: Section::$section,
                    doc: concat!($($doc),+),
                },
            )*];

            fn get_raw(&self, name: &str) -> Option<ParamValue> {
                $( if name.eq_ignore_ascii_case($name) { return Some(ParamType::to_value(&self.$field)); } )*
                None
            }

            /// Sets `spec.name` to `value` after type and range checks; access is not checked.
            fn set_raw(&mut self, spec: &ParamSpec, value: &ParamValue) -> Result<(), VisionError> {
                $(
                    if spec.name == $name {
                        let invalid = |reason: String| VisionError::InvalidParam {
                            name: $name.to_string(),
                            value: value.to_string(),
                            reason,
                        };
                        let v = <$ty as ParamType>::from_value(value)
                            .ok_or_else(|| invalid(kind_reason(<$ty as ParamType>::KIND)))?;
                        let check: Check<$ty> = $check;
                        check(&v).map_err(invalid)?;
                        self.$field = v;
                        return Ok(());
                    }
                )*
                Err(VisionError::UnknownParam { name: spec.name.to_string() })
            }
        }
    };
}

fn kind_reason(kind: ParamKind) -> String {
    match kind {
        ParamKind::YesNo => "must be Yes or No".into(),
        ParamKind::Integer => "must be an integer".into(),
        ParamKind::Float => "must be a number".into(),
        ParamKind::Text => "must be text".into(),
        ParamKind::Choice(words) => format!("must be one of {}", words.join(", ")),
    }
}

params! {
    /// `VisionEnabled`: master enable. When No, every Vision M-code fails with "Vision is not
    /// enabled" and no driver is loaded.
    (Connection, Config) enabled: bool => bool = false, "VisionEnabled", any;
    /// `VisionDriver`: the camera driver's registry name (default `Keyence`).
    (Connection, Config) driver: String => &str = "Keyence".to_string(), "VisionDriver", driver_name;
    /// `VisionIP`: camera IP address or host name.
    (Connection, Config) ip: String => &str = "192.168.208.80".to_string(), "VisionIP", host;
    /// `VisionPort`: camera TCP port (Keyence VS default 8500).
    (Connection, Config) port: i64 => i64 = 8500, "VisionPort", port;
    /// `VisionTimeout`: per-command socket I/O timeout, seconds.
    (Connection, Config) timeout_s: f64 => f64 = 3.0, "VisionTimeout", timeout_s;
    /// `VisionActiveJob`: camera job 0..999 applied by M284 without P; written by M284. 0 =
    /// leave the camera on its loaded job.
    (Connection, Config) active_job: i64 => i64 = 0, "VisionActiveJob", job;
    /// `VisionImageWatchDir`: folder the camera FTP-pushes images into; empty disables M281 D1.
    (Connection, Config) image_watch_dir: String => &str = String::new(), "VisionImageWatchDir", short_text;
    /// `VisionImageGrabTimeout`: how long M281 D1 waits for a fresh image, seconds.
    (Connection, Config) image_grab_timeout_s: f64 => f64 = 2.0, "VisionImageGrabTimeout", seconds_60;
    /// `VisionCameraResX`: image width, pixels.
    (Connection, Config) camera_res_x: i64 => i64 = 1776, "VisionCameraResX", resolution;
    /// `VisionCameraResY`: image height, pixels.
    (Connection, Config) camera_res_y: i64 => i64 = 1776, "VisionCameraResY", resolution;
    /// `VisionTriggerSettleSec`: dwell M283 inserts after each move before triggering, seconds.
    (Connection, Config) trigger_settle_s: f64 => f64 = 0.25, "VisionTriggerSettleSec", seconds_60;
    /// `VisionCameraSwapXY`: swap the centred pixel x and y (set by M283's axis detect).
    (Connection, Config) camera_swap_xy: bool => bool = false, "VisionCameraSwapXY", any;
    /// `VisionCameraInvertX`: negate pixel x after the swap (set by M283).
    (Connection, Config) camera_invert_x: bool => bool = false, "VisionCameraInvertX", any;
    /// `VisionCameraInvertY`: negate pixel y after the swap (set by M283).
    (Connection, Config) camera_invert_y: bool => bool = false, "VisionCameraInvertY", any;
    /// `VisionCameraToolNumber`: the camera's tool number; M280–M283 require it active. 0
    /// disables the check.
    (Output, Config) camera_tool_number: i64 => i64 = 0, "VisionCameraToolNumber", tool;

    /// `VisionCal_K11`: K row 1 column 1, `Cal_Units` per pixel.
    (Calibration, Config) cal_k11: f64 => f64 = 0.0, "VisionCal_K11", finite;
    /// `VisionCal_K12`: K row 1 column 2, `Cal_Units` per pixel.
    (Calibration, Config) cal_k12: f64 => f64 = 0.0, "VisionCal_K12", finite;
    /// `VisionCal_K21`: K row 2 column 1, `Cal_Units` per pixel.
    (Calibration, Config) cal_k21: f64 => f64 = 0.0, "VisionCal_K21", finite;
    /// `VisionCal_K22`: K row 2 column 2, `Cal_Units` per pixel.
    (Calibration, Config) cal_k22: f64 => f64 = 0.0, "VisionCal_K22", finite;
    /// `VisionCal_Date`: ISO local time of the last successful calibration (empty = never).
    (Calibration, Config) cal_date: String => &str = String::new(), "VisionCal_Date", short_text;
    /// `VisionCal_Units`: the unit K is calibrated in (`in` or `mm`).
    (Calibration, Config) cal_units: LengthUnit => LengthUnit = LengthUnit::Inch, "VisionCal_Units", any;
    /// `VisionPxCenterOffsetX`: optical-centre bias subtracted after the image-centre shift,
    /// pixels.
    (Calibration, Config) px_center_offset_x: f64 => f64 = 0.0, "VisionPxCenterOffsetX", pixel_offset;
    /// `VisionPxCenterOffsetY`: same, Y, pixels.
    (Calibration, Config) px_center_offset_y: f64 => f64 = 0.0, "VisionPxCenterOffsetY", pixel_offset;

    /// `VisionPoundVarBase`: base B of the 5-slot × 8-field pound-variable block `#B..#B+39`.
    /// B ≥ 100, block outside 5061..5081 and 5201..5500.
    (Output, Config) pound_var_base: i64 => i64 = 500, "VisionPoundVarBase", pound_base;

    /// `VisionFitMaxScaleDev`: M282 refuses a fit whose X or Y scale deviates from 1 by more
    /// than this, percent (0 disables).
    (Quality, Config) fit_max_scale_dev_pct: f64 => f64 = 2.0, "VisionFitMaxScaleDev", non_negative;
    /// `VisionFitMaxShift`: M282 refuses a fit whose shift (observed centroid − commanded
    /// centroid) is longer than this, inches (25.4 mm per inch under G21; 0 disables).
    (Quality, Config) fit_max_shift_in: f64 => f64 = 1.0, "VisionFitMaxShift", non_negative;
    /// `VisionFitMaxResidual`: M282 refuses a fit whose worst mark residual exceeds this,
    /// inches (0 disables).
    (Quality, Config) fit_max_residual_in: f64 => f64 = 0.020, "VisionFitMaxResidual", non_negative;

    /// `VisionLastJudgment`: 1 OK, 0 NG, −1 unknown, of the last trigger.
    (LastResult, Telemetry) last_judgment: i64 => i64 = -1, "VisionLastJudgment", any;
    /// `VisionLastOffsetPxX`: last centred pixel x (after the centre shift, before remap and K),
    /// pixels.
    (LastResult, Telemetry) last_offset_px_x: f64 => f64 = 0.0, "VisionLastOffsetPxX", any;
    /// `VisionLastOffsetPxY`: last centred pixel y, pixels.
    (LastResult, Telemetry) last_offset_px_y: f64 => f64 = 0.0, "VisionLastOffsetPxY", any;
    /// `VisionLastOffsetX`: last offset `d` from the camera to the mark, X, current units.
    (LastResult, Telemetry) last_offset_x: f64 => f64 = 0.0, "VisionLastOffsetX", any;
    /// `VisionLastOffsetY`: same, Y, current units.
    (LastResult, Telemetry) last_offset_y: f64 => f64 = 0.0, "VisionLastOffsetY", any;
    /// `VisionLastWidth`: last mark width, current units.
    (LastResult, Telemetry) last_width: f64 => f64 = 0.0, "VisionLastWidth", any;
    /// `VisionLastHeight`: last mark height, current units.
    (LastResult, Telemetry) last_height: f64 => f64 = 0.0, "VisionLastHeight", any;
    /// `VisionLastAngle`: last mark angle, degrees.
    (LastResult, Telemetry) last_angle: f64 => f64 = 0.0, "VisionLastAngle", any;
    /// `VisionLastScore`: last match score (driver scale).
    (LastResult, Telemetry) last_score: f64 => f64 = 0.0, "VisionLastScore", any;
    /// `VisionLastStatus`: `OK` (possibly with a warning) or the last error text.
    (LastResult, Telemetry) last_status: String => &str = String::new(), "VisionLastStatus", any;

    /// `VisionRun_Active`: 1 between M280 and a successful M282, else 0.
    (RunState, Telemetry) run_active: i64 => i64 = 0, "VisionRun_Active", any;
    /// `VisionRun_Mode`: 4 rectangle, 3 similarity.
    (RunState, Telemetry) run_mode: i64 => i64 = 4, "VisionRun_Mode", any;
    /// `VisionRun_DotCount`: captures taken in the current run.
    (RunState, Telemetry) run_dot_count: i64 => i64 = 0, "VisionRun_DotCount", any;
    /// `VisionRun_Tx`: emitted G52 X shift, current units.
    (RunState, Telemetry) run_tx: f64 => f64 = 0.0, "VisionRun_Tx", any;
    /// `VisionRun_Ty`: emitted G52 Y shift, current units.
    (RunState, Telemetry) run_ty: f64 => f64 = 0.0, "VisionRun_Ty", any;
    /// `VisionRun_Theta`: emitted rotation, radians (G68 R is its value in degrees).
    (RunState, Telemetry) run_theta: f64 => f64 = 0.0, "VisionRun_Theta", any;
    /// `VisionRun_Sx`: emitted G51 X factor.
    (RunState, Telemetry) run_sx: f64 => f64 = 1.0, "VisionRun_Sx", any;
    /// `VisionRun_Sy`: emitted G51 Y factor.
    (RunState, Telemetry) run_sy: f64 => f64 = 1.0, "VisionRun_Sy", any;
    /// `VisionRun_CenterX`: emitted G68 X rotation centre, current units.
    (RunState, Telemetry) run_center_x: f64 => f64 = 0.0, "VisionRun_CenterX", any;
    /// `VisionRun_CenterY`: emitted G68 Y rotation centre, current units.
    (RunState, Telemetry) run_center_y: f64 => f64 = 0.0, "VisionRun_CenterY", any;
}

impl Params {
    /// The spec of parameter `name` (case-insensitive).
    #[must_use]
    pub fn spec(name: &str) -> Option<&'static ParamSpec> {
        Params::SPECS.iter().find(|s| s.name.eq_ignore_ascii_case(name))
    }

    /// Reads parameter `name` (case-insensitive).
    ///
    /// # Errors
    /// [`VisionError::UnknownParam`].
    pub fn get(&self, name: &str) -> Result<ParamValue, VisionError> {
        self.get_raw(name).ok_or_else(|| VisionError::UnknownParam { name: name.to_string() })
    }

    /// Writes configuration parameter `name` (case-insensitive) after validating `value`.
    ///
    /// Text is accepted for every type (`"Yes"`, `"8500"`, `"0.00203"`, `"mm"`), so a CLI can
    /// pass what the user typed.
    ///
    /// # Errors
    /// [`VisionError::UnknownParam`], [`VisionError::ReadOnlyParam`] for telemetry,
    /// [`VisionError::InvalidParam`] for a wrong type or an out-of-range value; on error the
    /// parameter keeps its value.
    pub fn set(&mut self, name: &str, value: impl Into<ParamValue>) -> Result<(), VisionError> {
        let spec = Params::spec(name).ok_or_else(|| VisionError::UnknownParam { name: name.to_string() })?;
        if spec.access == Access::Telemetry {
            return Err(VisionError::ReadOnlyParam { name: spec.name.to_string() });
        }
        self.set_raw(spec, &value.into())
    }

    /// K as a matrix `[[K11, K12], [K21, K22]]`, `Cal_Units` per pixel.
    #[must_use]
    pub fn cal_k(&self) -> Matrix2<f64> {
        Matrix2::new(self.cal_k11, self.cal_k12, self.cal_k21, self.cal_k22)
    }

    /// Writes all four K entries at once (`Cal_Units` per pixel); nothing changes unless all
    /// four are finite.
    ///
    /// # Errors
    /// [`VisionError::InvalidParam`] for a non-finite entry.
    pub fn set_cal_k(&mut self, k: Matrix2<f64>) -> Result<(), VisionError> {
        if let Some(bad) = k.iter().find(|v| !v.is_finite()) {
            return Err(VisionError::InvalidParam {
                name: "VisionCal_K11..K22".into(),
                value: bad.to_string(),
                reason: "must be finite numbers".into(),
            });
        }
        self.cal_k11 = k[(0, 0)];
        self.cal_k12 = k[(0, 1)];
        self.cal_k21 = k[(1, 0)];
        self.cal_k22 = k[(1, 1)];
        Ok(())
    }

    /// The axis remap from the three `VisionCamera*` flags.
    #[must_use]
    pub fn remap(&self) -> Remap {
        Remap { swap_xy: self.camera_swap_xy, invert_x: self.camera_invert_x, invert_y: self.camera_invert_y }
    }

    /// Writes the three remap flags at once.
    pub fn set_remap(&mut self, r: Remap) {
        self.camera_swap_xy = r.swap_xy;
        self.camera_invert_x = r.invert_x;
        self.camera_invert_y = r.invert_y;
    }

    /// The camera tool number, or `None` when the check is disabled (0).
    #[must_use]
    pub fn camera_tool(&self) -> Option<u32> {
        u32::try_from(self.camera_tool_number).ok().filter(|t| *t != 0)
    }

    /// Every configuration (persisted) parameter with its value, in the manual's order.
    #[must_use]
    pub fn config_values(&self) -> Vec<(&'static str, ParamValue)> {
        Params::SPECS
            .iter()
            .filter(|s| s.access == Access::Config)
            .filter_map(|s| self.get_raw(s.name).map(|v| (s.name, v)))
            .collect()
    }

    /// Resets all telemetry to its defaults (configuration untouched).
    pub fn reset_telemetry(&mut self) {
        let d = Params::default();
        for spec in Params::SPECS.iter().filter(|s| s.access == Access::Telemetry) {
            if let Some(v) = d.get_raw(spec.name) {
                // Defaults always pass their own checks.
                let _ = self.set_raw(spec, &v);
            }
        }
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)]
mod tests {
    use super::*;

    #[test]
    fn defaults_match_the_manual() {
        let p = Params::default();
        assert!(!p.enabled());
        assert_eq!(p.driver(), "Keyence");
        assert_eq!(p.ip(), "192.168.208.80");
        assert_eq!(p.port(), 8500);
        assert_eq!(p.get("VisionTimeout"), Ok(ParamValue::Float(3.0)));
        assert_eq!(p.camera_res_x(), 1776);
        assert_eq!(p.pound_var_base(), 500);
        assert_eq!(p.cal_units(), LengthUnit::Inch);
        assert_eq!(p.cal_k(), Matrix2::zeros());
        assert_eq!(p.last_judgment(), -1);
        assert_eq!(p.get("visionenabled"), Ok(ParamValue::Bool(false)));
        assert_eq!(p.get("VisionCal_Units"), Ok(ParamValue::Text("in".into())));
        assert_eq!(p.fit_max_scale_dev_pct(), 2.0);
        assert_eq!(p.fit_max_shift_in(), 1.0);
        assert_eq!(p.fit_max_residual_in(), 0.020);
        // Every name carries the prefix and is unique.
        for (i, s) in Params::SPECS.iter().enumerate() {
            assert!(s.name.starts_with("Vision"), "{}", s.name);
            assert!(Params::SPECS[i + 1..].iter().all(|t| t.name != s.name));
            assert!(p.get(s.name).is_ok());
        }
    }

    #[test]
    fn writes_are_validated_and_telemetry_refused() {
        let mut p = Params::default();
        p.set("VisionEnabled", "Yes").expect("yes");
        assert!(p.enabled());
        p.set("VisionPort", "8600").expect("port text");
        assert_eq!(p.port(), 8600);
        p.set("VisionCal_K11", 0.00203).expect("k");
        p.set("VisionCal_Units", "mm").expect("mm");
        assert_eq!(p.cal_units(), LengthUnit::Millimetre);
        assert!(matches!(p.set("VisionPort", 70_000), Err(VisionError::InvalidParam { .. })));
        assert_eq!(p.port(), 8600);
        assert!(matches!(p.set("VisionCal_K12", f64::NAN), Err(VisionError::InvalidParam { .. })));
        assert!(matches!(p.set("VisionEnabled", "maybe"), Err(VisionError::InvalidParam { .. })));
        assert!(matches!(p.set("VisionCal_Units", "ft"), Err(VisionError::InvalidParam { .. })));
        assert!(matches!(p.set("VisionPoundVarBase", 5050), Err(VisionError::InvalidParam { .. })));
        assert!(matches!(p.set("VisionPoundVarBase", 99), Err(VisionError::InvalidParam { .. })));
        p.set("VisionPoundVarBase", 100).expect("100 is allowed");
        assert_eq!(
            p.set("VisionLastStatus", "OK"),
            Err(VisionError::ReadOnlyParam { name: "VisionLastStatus".into() })
        );
        assert_eq!(p.set("VisionRun_Tx", 1.0), Err(VisionError::ReadOnlyParam { name: "VisionRun_Tx".into() }));
        assert!(matches!(p.set("VisionNope", 1), Err(VisionError::UnknownParam { .. })));
        assert!(matches!(p.set("VisionActiveJob", 1000), Err(VisionError::InvalidParam { .. })));
        assert!(matches!(p.set("VisionIP", "bad host!"), Err(VisionError::InvalidParam { .. })));
        assert!(matches!(p.set("VisionPort", 1.5), Err(VisionError::InvalidParam { .. })));
        let e = p.set("VisionPort", "x").expect_err("not a number");
        assert_eq!(e.to_string(), "VisionPort = \"x\" is invalid: must be an integer");
    }

    #[test]
    fn k_and_remap_helpers() {
        let mut p = Params::default();
        let k = Matrix2::new(1.0, 2.0, 3.0, 4.0);
        p.set_cal_k(k).expect("finite");
        assert_eq!(p.cal_k(), k);
        assert!(p.set_cal_k(Matrix2::new(1.0, f64::INFINITY, 0.0, 0.0)).is_err());
        assert_eq!(p.cal_k(), k);
        let r = Remap { swap_xy: true, invert_x: false, invert_y: true };
        p.set_remap(r);
        assert_eq!(p.remap(), r);
        assert_eq!(p.camera_tool(), None);
        p.set("VisionCameraToolNumber", 98).expect("tool");
        assert_eq!(p.camera_tool(), Some(98));
        p.last_status = "x".into();
        p.reset_telemetry();
        assert_eq!(p.last_status(), "");
        assert_eq!(p.cal_k(), k);
        assert!(p.config_values().iter().all(|(n, _)| Params::spec(n).map(|s| s.access) == Some(Access::Config)));
    }
}
