//! The OEM parameters (SPEC §5, manual appendix A) under the manual's own names.
//!
//! The parameters fall into three parts with one owner each:
//! * [`Config`]: connection, camera, output and quality gates — the operator's settings;
//! * [`Calibration`]: K, the axis flags, `Cal_Units`, `Cal_Date`, the pixel centre offset —
//!   replaced as a whole by M283;
//! * [`Telemetry`]: `Last*` and `Run_*` — written by the module after each operation, read-only
//!   by name, never persisted and never read back to decide anything.
//!
//! [`Params`] is the persisted profile (configuration and calibration). The alignment run's
//! state (mode, open or not, the dot list) is typed in [`crate::module::Run`], not here.
//! Read parameters with the typed getters (`params.cal_k()`, `params.pound_var_base()`, …) or by
//! name with [`Params::get`] (case-insensitive); write them by name with [`Params::set`], which
//! validates the value and refuses telemetry.
//!
//! Units: lengths follow the parameter's doc (K and the pixel centre offset are per `Cal_Units`;
//! the fit gates are in inches and are converted to millimetres under G21); times are seconds.
//!
//! Decision: the fit quality gates (`VisionFitMaxScaleDev` in percent, `VisionFitMaxShift`,
//! `VisionFitMaxResidual` and `VisionFitMaxAxisScaleError` in inches), `VisionOutlierFactor` and
//! `VisionCameraNoisePx` are additions to the manual's set; 0 disables a gate. Each default
//! says why it was chosen.

use std::fmt;

use vision_math::{LengthUnit, Matrix2, Remap, Vector2};

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
fn noise_px(v: &f64) -> Result<(), String> {
    if v.is_finite() && (0.0..=10.0).contains(v) {
        Ok(())
    } else {
        Err("must be between 0 and 10 pixels".into())
    }
}
fn passes(v: &i64) -> Result<(), String> {
    if (0..=10).contains(v) {
        Ok(())
    } else {
        Err("must be 0..10 passes (0 reads in one shot)".into())
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

/// Declares one part of the parameter set: a struct with one private field per parameter, its
/// typed getters, its [`ParamSpec`] table and by-name read/write. Adding a parameter is one
/// entry here (name, type, default, range check); the profile, the CLI and the DRO views follow.
macro_rules! param_struct {
    (
        $(#[doc = $sdoc:literal])+
        $Struct:ident ($access:ident) {
            $(
                $(#[doc = $doc:literal])+
                ($section:ident) $field:ident : $ty:ty => $ret:ty = $default:expr, $name:literal, $check:expr;
            )*
        }
    ) => {
        $(#[doc = $sdoc])+
        #[derive(Debug, Clone, PartialEq)]
        pub struct $Struct {
            $( pub(crate) $field: $ty, )*
        }

        impl Default for $Struct {
            fn default() -> Self {
                $Struct { $( $field: $default, )* }
            }
        }

        impl $Struct {
            $(
                $(#[doc = $doc])+
                #[must_use]
                pub fn $field(&self) -> $ret {
                    ParamType::out(&self.$field)
                }
            )*

            /// This part's parameters, in the manual's order.
            pub const SPECS: &'static [ParamSpec] = &[$(
                ParamSpec {
                    name: $name,
                    kind: <$ty as ParamType>::KIND,
                    access: Access::$access,
                    section: Section::$section,
                    doc: concat!($($doc),+),
                },
            )*];

            /// Reads parameter `name` (case-insensitive); `None` when it is not in this part.
            #[must_use]
            pub fn get(&self, name: &str) -> Option<ParamValue> {
                $( if name.eq_ignore_ascii_case($name) { return Some(ParamType::to_value(&self.$field)); } )*
                None
            }

            /// Sets `name` (case-insensitive) to `value` after type and range checks; `Ok(false)`
            /// when `name` is not in this part. Access is the caller's business.
            #[allow(dead_code)] // telemetry is never written by name
            fn set_raw(&mut self, name: &str, value: &ParamValue) -> Result<bool, VisionError> {
                $(
                    if name.eq_ignore_ascii_case($name) {
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
                        return Ok(true);
                    }
                )*
                Ok(false)
            }
        }
    };
}

/// A persisted part of [`Params`]: [`param_struct!`] plus getters on [`Params`] that read
/// through to the part (one value, two ways to name the reader).
macro_rules! profile_part {
    ($(#[doc = $sdoc:literal])+ $Struct:ident in $via:ident { $($body:tt)* }) => {
        param_struct! { $(#[doc = $sdoc])+ $Struct (Config) { $($body)* } }
        profile_part!(@getters $via { $($body)* });
    };
    (@getters $via:ident {
        $(
            $(#[doc = $doc:literal])+
            ($section:ident) $field:ident : $ty:ty => $ret:ty = $default:expr, $name:literal, $check:expr;
        )*
    }) => {
        impl Params {
            $(
                $(#[doc = $doc])+
                #[must_use]
                pub fn $field(&self) -> $ret {
                    self.$via.$field()
                }
            )*
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

profile_part! {
    /// The persisted configuration: connection, camera, pound-variable output and the fit
    /// quality gates. Written by the operator (profile, CLI, DRO) and by M284
    /// (`VisionActiveJob`).
    Config in config {
        /// `VisionEnabled`: master enable. When No, every Vision M-code fails with "Vision is not
        /// enabled" and no driver is loaded.
        (Connection) enabled: bool => bool = false, "VisionEnabled", any;
        /// `VisionDriver`: the camera driver's registry name (default `Keyence`).
        (Connection) driver: String => &str = "Keyence".to_string(), "VisionDriver", driver_name;
        /// `VisionIP`: camera IP address or host name.
        (Connection) ip: String => &str = "192.168.208.80".to_string(), "VisionIP", host;
        /// `VisionPort`: camera TCP port (Keyence VS default 8500).
        (Connection) port: i64 => i64 = 8500, "VisionPort", port;
        /// `VisionTimeout`: per-command socket I/O timeout, seconds.
        (Connection) timeout_s: f64 => f64 = 3.0, "VisionTimeout", timeout_s;
        /// `VisionActiveJob`: camera job 0..999 applied by M284 without P; written by M284. 0 =
        /// leave the camera on its loaded job.
        (Connection) active_job: i64 => i64 = 0, "VisionActiveJob", job;
        /// `VisionImageWatchDir`: folder the camera FTP-pushes images into; empty disables M281 D1.
        (Connection) image_watch_dir: String => &str = String::new(), "VisionImageWatchDir", short_text;
        /// `VisionImageGrabTimeout`: how long M281 D1 waits for a fresh image, seconds.
        (Connection) image_grab_timeout_s: f64 => f64 = 2.0, "VisionImageGrabTimeout", seconds_60;
        /// `VisionCameraResX`: image width, pixels.
        (Connection) camera_res_x: i64 => i64 = 1776, "VisionCameraResX", resolution;
        /// `VisionCameraResY`: image height, pixels.
        (Connection) camera_res_y: i64 => i64 = 1776, "VisionCameraResY", resolution;
        /// `VisionTriggerSettleSec`: dwell M283 inserts after each move before triggering, seconds.
        (Connection) trigger_settle_s: f64 => f64 = 0.25, "VisionTriggerSettleSec", seconds_60;
        /// `VisionCameraNoisePx`: the camera's repeatability, the standard deviation of a
        /// reported mark centre on each pixel axis, pixels. M282 turns it into machine units
        /// with K for the fit's predicted error (the residuals' own σ is used when larger).
        /// Default 0.1 px: what a sub-pixel pattern search on a sharp dot typically repeats
        /// to, and the simulator's σ in the acceptance tests.
        (Connection) camera_noise_px: f64 => f64 = 0.1, "VisionCameraNoisePx", noise_px;
        /// `VisionRecenterPasses`: how many times M281 may move the camera over a mark it saw
        /// off the image centre and trigger again (0 = read in one shot, as the seed did).
        /// Default 2: one pass brings the mark to within K's error times its first distance,
        /// the second to the noise.
        (Connection) recenter_passes: i64 => i64 = 2, "VisionRecenterPasses", passes;
        /// `VisionRecenterTolerance`: M281 re-centres while the mark is farther than this from
        /// the image centre, pixels. Default 16 px: with the part 4 % closer or farther than at
        /// calibration a mark 16 px off centre is read 0.64 px (0.0013 in at 0.002 in/px) wrong,
        /// and the acceptance runs at ±4 % then cut within 0.002 in; on example 4 it re-reads
        /// one mark of four, adding 21 % to the alignment time (the issue allows 25 %).
        (Connection) recenter_tolerance_px: f64 => f64 = 16.0, "VisionRecenterTolerance", non_negative;
        /// `VisionMarkDiameter`: the fiducial's true diameter, inches (0 disables the height
        /// check). M281 compares the measured mark size with it and warns when they differ by
        /// more than `VisionMarkSizeTolerance`, with the implied working-distance change.
        (Connection) mark_diameter_in: f64 => f64 = 0.0, "VisionMarkDiameter", non_negative;
        /// `VisionMarkSizeTolerance`: the height check's threshold, percent of the diameter.
        /// Default 2 %: a mark's edge is found to a fraction of a pixel, so 2 % of a 0.25 in
        /// dot (~2.5 px at 0.002 in/px) is a real height change of about 2 %, the change at
        /// which a mark half a field (0.9 in) off centre is read 0.018 in wrong in one shot.
        (Connection) mark_size_tolerance_pct: f64 => f64 = 2.0, "VisionMarkSizeTolerance", non_negative;
        /// `VisionCameraToolNumber`: the camera's tool number; M280–M283 require it active. 0
        /// disables the check.
        (Output) camera_tool_number: i64 => i64 = 0, "VisionCameraToolNumber", tool;
        /// `VisionPoundVarBase`: base B of the 5-slot × 8-field pound-variable block `#B..#B+39`.
        /// B ≥ 100, block outside 5061..5081 and 5201..5500.
        (Output) pound_var_base: i64 => i64 = 500, "VisionPoundVarBase", pound_base;
        /// `VisionFitMaxScaleDev`: M282 refuses a fit whose X or Y scale deviates from 1 by more
        /// than this, percent (0 disables). Default 2 %: prints and sheet goods stay well inside
        /// it, while a wrong unit (25.4×) or a wrong mark is far outside.
        (Quality) fit_max_scale_dev_pct: f64 => f64 = 2.0, "VisionFitMaxScaleDev", non_negative;
        /// `VisionFitMaxShift`: M282 refuses a fit whose shift (observed centroid − commanded
        /// centroid) is longer than this, inches (25.4 mm per inch under G21; 0 disables).
        /// Default 2.5 in: the manual's workflow places parts within roughly 2 in of nominal,
        /// and a capture that far off is still a real mark, not a sign of the wrong program.
        (Quality) fit_max_shift_in: f64 => f64 = 2.5, "VisionFitMaxShift", non_negative;
        /// `VisionFitMaxResidual`: M282 refuses a fit whose worst mark residual exceeds this,
        /// inches (0 disables). Default 0.020 in: a mark the model cannot follow (a burr, a
        /// wrong feature) beyond ten times the cut budget; the finer model error is
        /// `VisionFitMaxAxisScaleError`'s, a single bad mark `VisionOutlierFactor`'s.
        (Quality) fit_max_residual_in: f64 => f64 = 0.020, "VisionFitMaxResidual", non_negative;
        /// `VisionFitMaxAxisScaleError`: M282 refuses a similarity fit when the marks show X
        /// and Y scaled differently by enough to miss a mark by more than this, inches (0
        /// disables). Default 0.002 in: the cut-error budget; such a part needs rectangle mode.
        (Quality) fit_max_axis_scale_error_in: f64 => f64 = 0.002, "VisionFitMaxAxisScaleError", non_negative;
        /// `VisionOutlierFactor`: with five marks or more, M282 leaves out the one mark whose
        /// distance from the fit of the others exceeds this many times the noise (the larger
        /// of the camera's and the others' residual σ), and reports it; 0 disables. Default
        /// 6: clean marks stay under it (at most 1 % false alarms in vision-math's test of 500
        /// noisy six-mark fits), while a 0.05 in slip is over a hundred σ of a 0.1 px camera.
        (Quality) outlier_factor: f64 => f64 = 6.0, "VisionOutlierFactor", non_negative;
    }
}

profile_part! {
    /// The calibration: K, the camera axis flags, `Cal_Units`, `Cal_Date` and the pixel centre
    /// offset. M283 replaces it as a whole (see [`crate::calibrate`]).
    ///
    /// Decision: `VisionPxCenterOffsetX/Y` belong here, as the manual lists them: they describe
    /// the camera's optics like K does, and are persisted with it. M283 does not solve them
    /// (the sheet walk absorbs a centre bias into the camera tool offset), so a calibration
    /// keeps the offset it had.
    Calibration in calibration {
        /// `VisionCameraSwapXY`: swap the centred pixel x and y (set by M283's axis detect).
        (Calibration) camera_swap_xy: bool => bool = false, "VisionCameraSwapXY", any;
        /// `VisionCameraInvertX`: negate pixel x after the swap (set by M283).
        (Calibration) camera_invert_x: bool => bool = false, "VisionCameraInvertX", any;
        /// `VisionCameraInvertY`: negate pixel y after the swap (set by M283).
        (Calibration) camera_invert_y: bool => bool = false, "VisionCameraInvertY", any;
        /// `VisionCal_K11`: K row 1 column 1, `Cal_Units` per pixel.
        (Calibration) cal_k11: f64 => f64 = 0.0, "VisionCal_K11", finite;
        /// `VisionCal_K12`: K row 1 column 2, `Cal_Units` per pixel.
        (Calibration) cal_k12: f64 => f64 = 0.0, "VisionCal_K12", finite;
        /// `VisionCal_K21`: K row 2 column 1, `Cal_Units` per pixel.
        (Calibration) cal_k21: f64 => f64 = 0.0, "VisionCal_K21", finite;
        /// `VisionCal_K22`: K row 2 column 2, `Cal_Units` per pixel.
        (Calibration) cal_k22: f64 => f64 = 0.0, "VisionCal_K22", finite;
        /// `VisionCal_Date`: ISO local time of the last successful calibration (empty = never).
        (Calibration) cal_date: String => &str = String::new(), "VisionCal_Date", short_text;
        /// `VisionCal_Units`: the unit K is calibrated in (`in` or `mm`).
        (Calibration) cal_units: LengthUnit => LengthUnit = LengthUnit::Inch, "VisionCal_Units", any;
        /// `VisionPxCenterOffsetX`: optical-centre bias subtracted after the image-centre shift,
        /// pixels.
        (Calibration) px_center_offset_x: f64 => f64 = 0.0, "VisionPxCenterOffsetX", pixel_offset;
        /// `VisionPxCenterOffsetY`: same, Y, pixels.
        (Calibration) px_center_offset_y: f64 => f64 = 0.0, "VisionPxCenterOffsetY", pixel_offset;
    }
}

param_struct! {
    /// Telemetry: what the last operation measured and emitted, written by the module after
    /// each operation and never read back to decide anything (the run's own state is
    /// [`crate::module::Run`]). Read-only by name; never persisted.
    Telemetry (Telemetry) {
        /// `VisionLastJudgment`: 1 OK, 0 NG, −1 unknown, of the last trigger.
        (LastResult) last_judgment: i64 => i64 = -1, "VisionLastJudgment", any;
        /// `VisionLastOffsetPxX`: last centred pixel x (after the centre shift, before remap and K),
        /// pixels.
        (LastResult) last_offset_px_x: f64 => f64 = 0.0, "VisionLastOffsetPxX", any;
        /// `VisionLastOffsetPxY`: last centred pixel y, pixels.
        (LastResult) last_offset_px_y: f64 => f64 = 0.0, "VisionLastOffsetPxY", any;
        /// `VisionLastOffsetX`: last offset `d` from the camera to the mark, X, current units.
        (LastResult) last_offset_x: f64 => f64 = 0.0, "VisionLastOffsetX", any;
        /// `VisionLastOffsetY`: same, Y, current units.
        (LastResult) last_offset_y: f64 => f64 = 0.0, "VisionLastOffsetY", any;
        /// `VisionLastWidth`: last mark width, current units.
        (LastResult) last_width: f64 => f64 = 0.0, "VisionLastWidth", any;
        /// `VisionLastHeight`: last mark height, current units.
        (LastResult) last_height: f64 => f64 = 0.0, "VisionLastHeight", any;
        /// `VisionLastAngle`: last mark angle, degrees.
        (LastResult) last_angle: f64 => f64 = 0.0, "VisionLastAngle", any;
        /// `VisionLastScore`: last match score (driver scale).
        (LastResult) last_score: f64 => f64 = 0.0, "VisionLastScore", any;
        /// `VisionLastStatus`: `OK` (possibly with a warning) or the last error text.
        (LastResult) last_status: String => &str = String::new(), "VisionLastStatus", any;
        /// `VisionRun_Active`: 1 between M280 and a successful M282, else 0 (from the run).
        (RunState) run_active: i64 => i64 = 0, "VisionRun_Active", any;
        /// `VisionRun_Mode`: 4 rectangle, 3 similarity (from the run).
        (RunState) run_mode: i64 => i64 = 4, "VisionRun_Mode", any;
        /// `VisionRun_DotCount`: captures taken in the current run (the dot list's length).
        (RunState) run_dot_count: i64 => i64 = 0, "VisionRun_DotCount", any;
        /// `VisionRun_Tx`: emitted G52 X shift, current units.
        (RunState) run_tx: f64 => f64 = 0.0, "VisionRun_Tx", any;
        /// `VisionRun_Ty`: emitted G52 Y shift, current units.
        (RunState) run_ty: f64 => f64 = 0.0, "VisionRun_Ty", any;
        /// `VisionRun_Theta`: emitted rotation, radians (G68 R is its value in degrees).
        (RunState) run_theta: f64 => f64 = 0.0, "VisionRun_Theta", any;
        /// `VisionRun_Sx`: emitted G51 X factor.
        (RunState) run_sx: f64 => f64 = 1.0, "VisionRun_Sx", any;
        /// `VisionRun_Sy`: emitted G51 Y factor.
        (RunState) run_sy: f64 => f64 = 1.0, "VisionRun_Sy", any;
        /// `VisionRun_CenterX`: emitted G68 X rotation centre, current units.
        (RunState) run_center_x: f64 => f64 = 0.0, "VisionRun_CenterX", any;
        /// `VisionRun_CenterY`: emitted G68 Y rotation centre, current units.
        (RunState) run_center_y: f64 => f64 = 0.0, "VisionRun_CenterY", any;
        /// `VisionRun_PredictedSigma`: the last fit's predicted cut error over the marks'
        /// bounding box, 1σ (root-mean-square length), current units.
        (RunState) run_predicted_sigma: f64 => f64 = 0.0, "VisionRun_PredictedSigma", any;
        /// `VisionRun_PredictedBound`: a radius that holds the last fit's largest cut error over
        /// the marks' bounding box with ≥ 99 % probability, current units.
        (RunState) run_predicted_bound: f64 => f64 = 0.0, "VisionRun_PredictedBound", any;
    }
}

/// The smallest pixel footprint a K may give, inches per pixel (2.5 nm: beyond any microscope
/// objective a machine camera carries).
pub const K_SCALE_MIN_IN: f64 = 1e-7;
/// The largest pixel footprint a K may give, inches per pixel (a 1776-pixel image would see
/// 178 in, more than any machine table).
pub const K_SCALE_MAX_IN: f64 = 0.1;
/// The largest ratio between K's two axis scales (square-ish pixels and no more than a steep
/// viewing angle; a larger ratio is a nearly singular K).
pub const K_MAX_ANISOTROPY: f64 = 10.0;

/// The persisted profile (SPEC §5): the [`Config`] and the [`Calibration`], read and written by
/// the manual's names. The module's run state and its [`Telemetry`] are not part of it.
///
/// Every configuration and calibration getter is also available on `Params` directly
/// (`params.ip()`, `params.cal_k()`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Params {
    /// Connection, camera, output and quality gates.
    pub config: Config,
    /// K, the axis flags, `Cal_Units`, `Cal_Date` and the pixel centre offset.
    pub calibration: Calibration,
}

impl Params {
    /// Every parameter: configuration, calibration, then telemetry.
    pub fn specs() -> impl Iterator<Item = &'static ParamSpec> {
        Config::SPECS.iter().chain(Calibration::SPECS).chain(Telemetry::SPECS)
    }

    /// The spec of parameter `name` (case-insensitive), telemetry included.
    #[must_use]
    pub fn spec(name: &str) -> Option<&'static ParamSpec> {
        Params::specs().find(|s| s.name.eq_ignore_ascii_case(name))
    }

    /// Reads configuration or calibration parameter `name` (case-insensitive). Telemetry is
    /// not in the profile: read it with [`Telemetry::get`] or [`crate::VisionModule::param`].
    ///
    /// # Errors
    /// [`VisionError::UnknownParam`] (also for a telemetry name).
    pub fn get(&self, name: &str) -> Result<ParamValue, VisionError> {
        self.config
            .get(name)
            .or_else(|| self.calibration.get(name))
            .ok_or_else(|| VisionError::UnknownParam { name: name.to_string() })
    }

    /// Writes configuration or calibration parameter `name` (case-insensitive) after
    /// validating `value`.
    ///
    /// Text is accepted for every type (`"Yes"`, `"8500"`, `"0.00203"`, `"mm"`), so a CLI can
    /// pass what the user typed.
    ///
    /// # Errors
    /// [`VisionError::UnknownParam`], [`VisionError::ReadOnlyParam`] for telemetry,
    /// [`VisionError::InvalidParam`] for a wrong type or an out-of-range value; on error the
    /// parameter keeps its value.
    pub fn set(&mut self, name: &str, value: impl Into<ParamValue>) -> Result<(), VisionError> {
        let value = value.into();
        if self.config.set_raw(name, &value)? || self.calibration.set_raw(name, &value)? {
            return Ok(());
        }
        match Telemetry::SPECS.iter().find(|s| s.name.eq_ignore_ascii_case(name)) {
            Some(spec) => Err(VisionError::ReadOnlyParam { name: spec.name.to_string() }),
            None => Err(VisionError::UnknownParam { name: name.to_string() }),
        }
    }

    /// K as a matrix `[[K11, K12], [K21, K22]]`, `Cal_Units` per pixel.
    #[must_use]
    pub fn cal_k(&self) -> Matrix2<f64> {
        self.calibration.cal_k()
    }

    /// As [`Calibration::set_cal_k`].
    ///
    /// # Errors
    /// [`VisionError::InvalidParam`] for a non-finite entry.
    pub fn set_cal_k(&mut self, k: Matrix2<f64>) -> Result<(), VisionError> {
        self.calibration.set_cal_k(k)
    }

    /// The axis remap from the three `VisionCamera*` flags.
    #[must_use]
    pub fn remap(&self) -> Remap {
        self.calibration.remap()
    }

    /// As [`Calibration::set_remap`].
    pub fn set_remap(&mut self, r: Remap) {
        self.calibration.set_remap(r);
    }

    /// The camera tool number, or `None` when the check is disabled (0).
    #[must_use]
    pub fn camera_tool(&self) -> Option<u32> {
        self.config.camera_tool()
    }

    /// Every persisted parameter with its value: configuration, then calibration.
    #[must_use]
    pub fn config_values(&self) -> Vec<(&'static str, ParamValue)> {
        Config::SPECS
            .iter()
            .filter_map(|s| self.config.get(s.name).map(|v| (s.name, v)))
            .chain(Calibration::SPECS.iter().filter_map(|s| self.calibration.get(s.name).map(|v| (s.name, v))))
            .collect()
    }
}

impl serde::Serialize for Telemetry {
    /// A map from each telemetry parameter's manual name to its value, in the manual's order.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        crate::ser::named_values(Telemetry::SPECS, |name| self.get(name), s)
    }
}

impl Config {
    /// The camera tool number, or `None` when the check is disabled (0).
    #[must_use]
    pub fn camera_tool(&self) -> Option<u32> {
        u32::try_from(self.camera_tool_number).ok().filter(|t| *t != 0)
    }
}

impl Calibration {
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

    /// Checks K as a whole, as a profile load does: all zero ("not calibrated") or a pixel
    /// footprint `√|det K|` of [`K_SCALE_MIN_IN`]..[`K_SCALE_MAX_IN`] inches per pixel with its
    /// two axes within [`K_MAX_ANISOTROPY`]× of each other.
    ///
    /// # Errors
    /// [`VisionError::InvalidParam`] naming `VisionCal_K11..K22` and what is wrong.
    pub fn check_k(&self) -> Result<(), VisionError> {
        let k = self.cal_k();
        if k.iter().all(|v| *v == 0.0) {
            return Ok(());
        }
        let bad = |reason: String| VisionError::InvalidParam {
            name: "VisionCal_K11..K22".into(),
            value: format!("[[{:e}, {:e}], [{:e}, {:e}]]", k[(0, 0)], k[(0, 1)], k[(1, 0)], k[(1, 1)]),
            reason,
        };
        let in_per_unit = self.cal_units.factor_to(LengthUnit::Inch);
        // Singular values of K, in inches per pixel, by the closed form for 2×2 matrices.
        // Normalised first so 1e300 entries do not overflow.
        let k_in = k.map(|v| v * in_per_unit);
        let m = k_in.amax();
        let sv = (k_in / m).singular_values() * m;
        let (big, small) = (sv.max(), sv.min());
        if !(big.is_finite() && small > 0.0 && big / small <= K_MAX_ANISOTROPY) {
            return Err(bad(format!(
                "is singular or nearly so (the axes' scales differ by more than {K_MAX_ANISOTROPY}×) — \
                 recalibrate with M283, or set all four to 0 for \"not calibrated\""
            )));
        }
        let scale = big.sqrt() * small.sqrt();
        if !(K_SCALE_MIN_IN..=K_SCALE_MAX_IN).contains(&scale) {
            return Err(bad(format!(
                "gives {scale:.3e} in per pixel, outside the physical {K_SCALE_MIN_IN:e}..{K_SCALE_MAX_IN} in per \
                 pixel (VisionCal_Units is {}) — recalibrate with M283, or set all four to 0",
                self.cal_units.short_name()
            )));
        }
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

    /// The pixel centre offset, pixels.
    #[must_use]
    pub fn center_offset(&self) -> Vector2<f64> {
        Vector2::new(self.px_center_offset_x, self.px_center_offset_y)
    }

    /// This calibration with a new K, remap, unit and date (the pixel centre offset is kept).
    ///
    /// # Errors
    /// [`VisionError::InvalidParam`] for a K [`Calibration::check_k`] refuses (a profile
    /// load would) or a date longer than the profile allows; `self` is unchanged either way.
    pub fn solved(
        &self,
        k: Matrix2<f64>,
        remap: Remap,
        units: LengthUnit,
        date: &str,
    ) -> Result<Calibration, VisionError> {
        let mut next = self.clone();
        next.set_cal_k(k)?;
        next.set_remap(remap);
        next.cal_units = units;
        next.set_raw("VisionCal_Date", &ParamValue::from(date))?;
        next.check_k()?;
        Ok(next)
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
        assert_eq!(Telemetry::default().last_judgment(), -1);
        assert_eq!(Telemetry::default().get("visionrun_mode"), Some(ParamValue::Int(4)));
        assert_eq!(p.get("visionenabled"), Ok(ParamValue::Bool(false)));
        assert_eq!(p.get("VisionCal_Units"), Ok(ParamValue::Text("in".into())));
        assert_eq!(p.fit_max_scale_dev_pct(), 2.0);
        assert_eq!(p.fit_max_shift_in(), 2.5);
        assert_eq!(p.outlier_factor(), 6.0);
        assert_eq!(p.camera_noise_px(), 0.1);
        assert_eq!(p.fit_max_residual_in(), 0.020);
        // Every name carries the prefix, is unique, and is read by the part its access says.
        let specs: Vec<_> = Params::specs().collect();
        for (i, s) in specs.iter().enumerate() {
            assert!(s.name.starts_with("Vision"), "{}", s.name);
            assert!(specs[i + 1..].iter().all(|t| !t.name.eq_ignore_ascii_case(s.name)));
            assert_eq!(p.get(s.name).is_ok(), s.access == Access::Config, "{}", s.name);
            assert_eq!(Telemetry::default().get(s.name).is_some(), s.access == Access::Telemetry, "{}", s.name);
            assert_eq!(Params::spec(&s.name.to_ascii_lowercase()), Some(*s));
        }
        assert!(matches!(p.get("VisionLastStatus"), Err(VisionError::UnknownParam { .. })));
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
        assert!(p.config_values().iter().all(|(n, _)| Params::spec(n).map(|s| s.access) == Some(Access::Config)));
        assert_eq!(p.config_values().len(), Config::SPECS.len() + Calibration::SPECS.len());
        // A solved calibration keeps the pixel centre offset and leaves the original alone.
        p.set("VisionPxCenterOffsetX", 3.5).expect("offset");
        let next = p.calibration.solved(Matrix2::identity(), Remap::IDENTITY, LengthUnit::Millimetre, "D").expect("ok");
        assert_eq!(
            (next.cal_k(), next.cal_units(), next.cal_date()),
            (Matrix2::identity(), LengthUnit::Millimetre, "D")
        );
        assert_eq!(next.center_offset(), Vector2::new(3.5, 0.0));
        assert_eq!(p.cal_k(), k);
        assert!(p.calibration.solved(Matrix2::from_element(f64::NAN), Remap::IDENTITY, LengthUnit::Inch, "").is_err());
    }
}
