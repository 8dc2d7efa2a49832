//! The one error type of `vision-core`: every failure of M280–M284, the parameters and the
//! profile, worded like the manual's error table — what went wrong, then what to do.

use vision_math::show::number;
use vision_math::MathError;

use crate::controller::sheet_calibrations;
use crate::driver::{DriverError, DriverErrorKind};
use crate::machine::MachineError;

/// Why a Vision operation was refused. A refused operation changes nothing (see each M-code).
///
/// Messages follow the manual's error table: the symptom first, then the likely cause and fix.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum VisionError {
    /// `VisionEnabled` is No.
    #[error("Vision is not enabled — set VisionEnabled to Yes in the Vision configuration")]
    NotEnabled,

    /// `VisionCameraToolNumber` is set and another tool is active.
    #[error(
        "camera tool T{camera} is not the active tool (T{active} is active) — issue T{camera} M6 \
         for the camera tool first, or set VisionCameraToolNumber to 0 to disable the check"
    )]
    WrongTool {
        /// `VisionCameraToolNumber`.
        camera: u32,
        /// The tool the machine reports as active.
        active: u32,
    },

    /// The camera tool is active but its X/Y offset is not the one the machine applies
    /// (LinuxCNC applies a tool's offsets only under `G43`): the camera is not over the
    /// commanded point.
    #[error(
        "camera tool T{camera}'s X/Y offset is not applied (the tool table holds X{} Y{}, the machine applies \
         X{} Y{}): the camera is not over the commanded point — program G43 H{camera} after T{camera} M6 \
         (LinuxCNC applies a tool's offsets only under G43; again after M283 writes the offset)",
        number(.table[0]), number(.table[1]), number(.applied[0]), number(.applied[1])
    )]
    ToolOffsetNotApplied {
        /// `VisionCameraToolNumber`.
        camera: u32,
        /// Its X/Y table entry, current units.
        table: [f64; 2],
        /// The X/Y offset the machine applies, in the table's form, current units.
        applied: [f64; 2],
    },

    /// K11..K22 are all zero.
    #[error("K matrix is zero — run M283 to calibrate first ({}, or M283 Q)", sheet_calibrations())]
    NotCalibrated,

    /// K cannot be inverted or holds a non-finite number.
    #[error("K matrix is unusable ({reason}) — re-run M283 to calibrate ({}, or M283 Q)", sheet_calibrations())]
    BadCalibration {
        /// What is wrong with it.
        reason: String,
    },

    /// The pound-variable block would overlap a reserved range, start below 100 or end past
    /// #9999.
    #[error(
        "VisionPoundVarBase is in reserved range (base {base}, block #{base}..#{end}) — move the \
         base out of 5061..5081 or 5201..5500; pick a value from 100 to 9960"
    )]
    PoundBaseReserved {
        /// The configured base.
        base: i64,
        /// The last variable of the 40-variable block.
        end: i64,
    },

    /// The 40-variable block does not exist on the host (it runs past its last variable).
    #[error(
        "VisionPoundVarBase {base} does not fit this machine: #{base}..#{end} must all exist ({reason}) — \
         pick a base whose 40 variables exist, e.g. 500"
    )]
    PoundBlockMissing {
        /// The configured base.
        base: i64,
        /// The last variable of the block.
        end: i64,
        /// What the host said.
        reason: String,
    },

    /// The camera judged NG or found no mark.
    #[error(
        "NG / no mark found — the camera job did not find a fiducial in the field of view{}; re-jog \
         over the mark, check lighting, verify the camera job is locating the right feature",
        miss_note(.reason.as_deref())
    )]
    NoMark {
        /// Why, in the driver's words, when it says ([`crate::CameraDriver::miss_reason`]): a
        /// camera that runs no job of its own (the `Camera` driver) knows what its finder saw.
        reason: Option<String>,
    },

    /// The driver failed. The text is the driver's own ([`DriverError`]'s `Display`): only the
    /// driver knows its camera, its protocol and what each refusal means, and it names the
    /// settings it reads (its [`crate::SettingsTable`]). The core adds
    /// nothing of a camera's vocabulary; it only describes the [`DriverErrorKind`] when a driver
    /// sent no text at all.
    #[error("{}", driver_message(.0))]
    Driver(DriverError),

    /// No camera driver is loaded.
    #[error("no camera driver is loaded (VisionDriver = {name:?}) — check VisionDriver and restart the Vision module")]
    NoDriver {
        /// The configured driver name.
        name: String,
    },

    /// `VisionDriver` names no registered driver.
    #[error("unknown camera driver {name:?} — VisionDriver must be one of: {known}")]
    UnknownDriver {
        /// The requested name.
        name: String,
        /// The registered names, comma-separated.
        known: String,
    },

    /// M282 with fewer captures than the run's fit needs.
    #[error(
        "{mode} fit needs at least {needed} captured marks, got {got} — run M280, then M281 over \
         each mark, before M282"
    )]
    TooFewDots {
        /// The run's fit name.
        mode: &'static str,
        /// Captures needed.
        needed: usize,
        /// Captures taken.
        got: usize,
    },

    /// The math refused the input (degenerate marks, non-finite numbers).
    #[error("{0}")]
    Math(MathError),

    /// A fit failed a quality gate (`VisionFitMax*`).
    #[error(
        "alignment refused: {reason} — likely causes: the camera found the wrong mark, the part \
         moved during the run, a bad calibration (re-run {}), or the marks were captured in the wrong order; \
         nothing was applied",
        sheet_calibrations()
    )]
    FitRejected {
        /// Which gate tripped, with the numbers.
        reason: String,
    },

    /// M284 on a driver that cannot switch jobs.
    #[error("camera driver {driver} cannot select jobs — M284 needs a driver that advertises select_job")]
    SelectJobUnsupported {
        /// The driver's name.
        driver: String,
    },

    /// A parameter name that does not exist.
    #[error("unknown parameter {name:?} — Vision parameter names start with Vision (e.g. VisionCal_K11)")]
    UnknownParam {
        /// The name given.
        name: String,
    },

    /// A write to read-only telemetry.
    #[error("{name} is read-only telemetry written by the Vision module; it cannot be set")]
    ReadOnlyParam {
        /// The parameter.
        name: String,
    },

    /// A parameter value of the wrong type or out of range.
    #[error("{name} = {value} is invalid: {reason}")]
    InvalidParam {
        /// The parameter.
        name: String,
        /// The value given, as text.
        value: String,
        /// What is allowed.
        reason: String,
    },

    /// The profile could not be read, parsed or written.
    #[error("Vision profile {path}: {reason}")]
    Profile {
        /// The profile file.
        path: String,
        /// What failed (the previous file is left intact on a failed save).
        reason: String,
    },

    /// The host machine refused or failed a request.
    #[error("{0}")]
    Machine(MachineError),

    /// A controller name that is not one of [`crate::controller::CONTROLLERS`].
    #[error("unknown controller '{name}' — known controllers: {known}")]
    UnknownController {
        /// The name asked for.
        name: String,
        /// The known names.
        known: String,
    },

    /// `M283 Cn` with a sheet number not in `CAL_SHEETS`.
    #[error("unknown calibration sheet {sheet} — known sheets: {known}")]
    UnknownSheet {
        /// The requested sheet.
        sheet: u32,
        /// The known sheet numbers.
        known: String,
    },

    /// What M283 calibrated with has changed since (the camera's resolution, its driver, the
    /// camera tool's offset): every capture would be read off, so M280–M282 refuse.
    #[error("{what} changed since M283 calibrated K: {detail} — {fix}")]
    CalibrationChanged {
        /// What changed (`the camera's resolution`, …).
        what: &'static str,
        /// The value now and the value M283 recorded.
        detail: String,
        /// What to do: restore it, or calibrate again (the controller's sheet word).
        fix: String,
    },

    /// Calibration could not complete.
    #[error("calibration failed: {reason}; K, the axis flags and the tool offsets were left unchanged")]
    Calibration {
        /// What went wrong and what to do.
        reason: String,
    },

    /// An operation that needs the alignment modals cancelled found them active.
    #[error(
        "an alignment transform (a shift, rotation or scale of the program frame) is active — cancel \
         it with M280 before calibrating"
    )]
    AlignmentActive,

    /// A step of the stepwise M283 walk came out of order.
    #[error("M283 walk: {what}")]
    WalkOrder {
        /// What was out of order and what to do.
        what: &'static str,
    },

    /// A word written as the manual writes it where the controller's dialect writes another
    /// (LinuxCNC's M283 sheet `P` for the manual's `C`); the message names the replacement.
    #[error("{message}")]
    DialectWord {
        /// What to write instead.
        message: String,
    },

    /// A step of the stepwise M281 (re-centring on a controller that waits itself) came out
    /// of order.
    #[error("M281: {what}")]
    CaptureOrder {
        /// What was out of order and what to do.
        what: &'static str,
    },
}

/// A driver failure as the operator reads it: the driver's words as they are, or, when the
/// driver said nothing, what the core knows — the kind of failure.
/// `NoMark`'s reason as a parenthesis after "field of view", or nothing.
fn miss_note(reason: Option<&str>) -> String {
    match reason.map(str::trim) {
        Some(r) if !r.is_empty() => format!(" ({r})"),
        _ => String::new(),
    }
}

fn driver_message(e: &DriverError) -> String {
    let text = e.to_string();
    if !text.trim().is_empty() {
        return text;
    }
    match e.kind() {
        DriverErrorKind::Timeout => "the camera did not answer in time",
        DriverErrorKind::Refused => "the camera refused or closed the connection",
        DriverErrorKind::Malformed => "the camera's reply could not be understood",
        DriverErrorKind::Rejected => "the camera refused the command",
        DriverErrorKind::Unsupported => "the camera driver does not support this operation",
        DriverErrorKind::InvalidArgument => "the camera driver refused an argument before sending anything",
        _ => "the camera driver failed",
    }
    .to_string()
}

impl From<DriverError> for VisionError {
    fn from(e: DriverError) -> Self {
        VisionError::Driver(e)
    }
}

impl From<MachineError> for VisionError {
    fn from(e: MachineError) -> Self {
        VisionError::Machine(e)
    }
}

impl From<MathError> for VisionError {
    fn from(e: MathError) -> Self {
        match e {
            MathError::NotCalibrated => VisionError::NotCalibrated,
            MathError::SingularK => VisionError::BadCalibration { reason: "singular".into() },
            MathError::NonFinite { what: "K" } => VisionError::BadCalibration { reason: "not finite".into() },
            other => VisionError::Math(other),
        }
    }
}

/// The refusals as the M-code reference (`docs/reference/mcodes.md`) lists them.
impl VisionError {
    /// What gives this refusal: the M-codes, or the step outside them (a profile load, a
    /// parameter write).
    #[must_use]
    pub fn given_by(&self) -> &'static str {
        match self {
            VisionError::NotEnabled => "M280–M284",
            VisionError::WrongTool { .. } => "M280–M283",
            VisionError::ToolOffsetNotApplied { .. } | VisionError::CaptureOrder { .. } => "M281",
            VisionError::NotCalibrated | VisionError::BadCalibration { .. } => "M281",
            VisionError::PoundBaseReserved { .. } | VisionError::PoundBlockMissing { .. } => "M280, M281",
            VisionError::NoMark { .. } => "M281, M283",
            VisionError::Driver(_) | VisionError::NoDriver { .. } => "M281, M283, M284",
            VisionError::UnknownDriver { .. } => "loading the Vision module (`VisionDriver`)",
            VisionError::TooFewDots { .. } | VisionError::FitRejected { .. } => "M282",
            VisionError::Math(_) => "M281, M282",
            VisionError::SelectJobUnsupported { .. } => "M284",
            VisionError::UnknownParam { .. } | VisionError::ReadOnlyParam { .. } => {
                "setting a parameter (profile, command line, DRO)"
            }
            VisionError::InvalidParam { .. } => "setting a parameter, loading a profile; M283 and M284 as they write",
            VisionError::Profile { .. } => "loading the profile; M283 and M284 as they save it",
            VisionError::Machine(_) => "M280–M284 (the machine refused a move, a write or a read)",
            VisionError::UnknownController { .. } => "choosing the controller (`--dialect`, world `machine.dialect`)",
            VisionError::CalibrationChanged { .. } => "M280–M282",
            VisionError::UnknownSheet { .. }
            | VisionError::Calibration { .. }
            | VisionError::AlignmentActive
            | VisionError::WalkOrder { .. } => "M283",
            VisionError::DialectWord { .. } => "M283 on LinuxCNC",
        }
    }

    /// One refusal of each kind, with example values, in the order the enum declares them.
    #[must_use]
    pub fn examples() -> Vec<VisionError> {
        use crate::machine::MachineErrorKind;
        vec![
            VisionError::NotEnabled,
            VisionError::WrongTool { camera: 98, active: 1 },
            VisionError::ToolOffsetNotApplied { camera: 98, table: [-3.25, 1.75], applied: [0.0, 0.0] },
            VisionError::NotCalibrated,
            VisionError::BadCalibration { reason: "singular".into() },
            VisionError::PoundBaseReserved { base: 5050, end: 5089 },
            VisionError::PoundBlockMissing {
                base: 5580,
                end: 5619,
                reason: "LinuxCNC's numbered parameters end at #5601".into(),
            },
            VisionError::NoMark { reason: None },
            VisionError::Driver(DriverError::new(DriverErrorKind::Timeout, "")),
            VisionError::NoDriver { name: "Keyence".into() },
            VisionError::UnknownDriver { name: "Keyense".into(), known: "Sim, Keyence, Camera".into() },
            VisionError::TooFewDots { mode: "rectangle", needed: 3, got: 2 },
            VisionError::Math(MathError::CoincidentPoints),
            VisionError::FitRejected { reason: "shift 2.8000 in exceeds VisionFitMaxShift = 2.5000 in".into() },
            VisionError::SelectJobUnsupported { driver: "Camera".into() },
            VisionError::UnknownParam { name: "VisionCameraTool".into() },
            VisionError::ReadOnlyParam { name: "VisionLastStatus".into() },
            VisionError::InvalidParam {
                name: "VisionCameraResX".into(),
                value: "1".into(),
                reason: "must be an image size of 2..100000 pixels".into(),
            },
            VisionError::Profile { path: "vision.toml".into(), reason: "unknown key VisionFoo in [vision]".into() },
            VisionError::Machine(MachineError::new(MachineErrorKind::Stopped, "the program was stopped")),
            VisionError::UnknownController { name: "fanuc".into(), known: "mach4, linuxcnc, machinemotion".into() },
            VisionError::UnknownSheet { sheet: 2, known: "1".into() },
            VisionError::CalibrationChanged {
                what: "the camera driver",
                detail: "the loaded driver is Camera, K was calibrated with Keyence".into(),
                fix: "switch back to the Keyence camera, or run M283 C1 to calibrate this one".into(),
            },
            VisionError::Calibration { reason: "dot 3 of sheet 1 was not found".into() },
            VisionError::AlignmentActive,
            VisionError::WalkOrder { what: "no M283 walk is in progress; M283 starts one" },
            VisionError::DialectWord {
                message: "M283 C1: on LinuxCNC the sheet number is P: write M283 P1 (C is an axis word)".into(),
            },
            VisionError::CaptureOrder { what: "no re-centring is in progress; M281 starts one" },
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn manual_wording() {
        assert_eq!(
            VisionError::NotCalibrated.to_string(),
            "K matrix is zero — run M283 to calibrate first (M283 C1, on LinuxCNC M283 P1, or M283 Q)"
        );
        assert!(VisionError::NotEnabled.to_string().starts_with("Vision is not enabled"));
        // NG reads as the manual's message; a driver's reason sits inside it, a blank one not.
        let ng = |reason: Option<&str>| VisionError::NoMark { reason: reason.map(String::from) }.to_string();
        assert_eq!(ng(None), ng(Some("  ")));
        assert!(ng(None)
            .starts_with("NG / no mark found — the camera job did not find a fiducial in the field of view; re-jog"));
        assert!(ng(Some("the finder: 2 marks in view")).contains("field of view (the finder: 2 marks in view); re-jog"));
        let e = VisionError::WrongTool { camera: 98, active: 1 };
        assert!(e.to_string().starts_with("camera tool T98 is not the active tool"));
        // A driver error reads as the driver words it, whatever its kind: the core puts no
        // generic advice of its own in front of the driver's specific advice.
        for kind in [
            DriverErrorKind::Timeout,
            DriverErrorKind::Refused,
            DriverErrorKind::Malformed,
            DriverErrorKind::Rejected,
            DriverErrorKind::Unsupported,
            DriverErrorKind::InvalidArgument,
            DriverErrorKind::Other,
        ] {
            let message = "the camera answered but sent no data — add an output to the camera job";
            let e = VisionError::from(DriverError::new(kind, message));
            assert_eq!(e.to_string(), message, "{kind:?}");
            // Said nothing: the kind, in the core's words.
            let silent = VisionError::from(DriverError::new(kind, "")).to_string();
            assert!(silent.starts_with("the camera"), "{kind:?}: {silent}");
        }
        let timeout = VisionError::from(DriverError::new(DriverErrorKind::Timeout, " "));
        assert_eq!(timeout.to_string(), "the camera did not answer in time");
        assert!(VisionError::PoundBaseReserved { base: 5050, end: 5089 }
            .to_string()
            .starts_with("VisionPoundVarBase is in reserved range"));
        assert_eq!(VisionError::from(MathError::NotCalibrated), VisionError::NotCalibrated);
    }

    /// The reference lists every refusal: `examples` holds each variant the enum declares
    /// (counted from this file's source, so a new variant without an example fails here).
    #[test]
    fn every_refusal_has_an_example_for_the_reference() {
        let source = include_str!("error.rs");
        let body =
            source.split("pub enum VisionError {").nth(1).and_then(|b| b.split("\n}\n").next()).expect("the enum");
        let declared: Vec<&str> = body
            .lines()
            .filter_map(|l| l.strip_prefix("    "))
            .filter(|l| l.starts_with(|c: char| c.is_ascii_uppercase()))
            .map(|l| l.split([' ', '(', ',']).next().unwrap_or(l))
            .collect();
        let examples = VisionError::examples();
        let shown: Vec<String> =
            examples.iter().map(|e| format!("{e:?}").split([' ', '(', '{']).next().unwrap_or("").to_string()).collect();
        assert_eq!(shown, declared, "VisionError::examples: one per variant, in declaration order");
        for e in &examples {
            assert!(!e.given_by().is_empty() && !e.to_string().is_empty(), "{e:?}");
        }
    }
}
