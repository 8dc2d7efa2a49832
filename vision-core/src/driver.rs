//! The camera side: what a driver must do, and nothing more (SPEC §7: drivers are dumb).
//!
//! A driver triggers the camera and returns the **native** pixel reading. Every conversion to
//! machine units lives in the core. Each driver keeps its own rich error type and maps it to a
//! [`DriverErrorKind`] so the core can react without knowing the driver.

use std::fmt;
use std::time::Duration;

/// The camera's pass/fail verdict for a trigger.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Judgment {
    /// The inspection passed (`1` / `OK`).
    Ok,
    /// The inspection failed (`0` / `NG`).
    Ng,
    /// The camera did not say (a bare `x,y` reply).
    Unknown,
}

impl Judgment {
    /// The manual's numeric code: 1 OK, 0 NG, −1 unknown (`VisionLastJudgment`).
    #[must_use]
    pub fn code(self) -> i32 {
        match self {
            Judgment::Ok => 1,
            Judgment::Ng => 0,
            Judgment::Unknown => -1,
        }
    }

    /// How reports write it: `OK`, `NG` or `unknown`.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            Judgment::Ok => "OK",
            Judgment::Ng => "NG",
            Judgment::Unknown => "unknown",
        }
    }
}

/// One trigger's result in native camera pixels (origin top-left, +x right, +y down).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reading {
    /// The verdict.
    pub judgment: Judgment,
    /// Number of marks found, when the camera reports it (`None` for the short formats).
    /// `Some(0)` means no mark.
    pub count: Option<u32>,
    /// Mark centre x, pixels.
    pub x_px: f64,
    /// Mark centre y, pixels.
    pub y_px: f64,
    /// Mark width, pixels (0 when not reported).
    pub width_px: f64,
    /// Mark height, pixels (0 when not reported).
    pub height_px: f64,
    /// Mark angle, degrees (0 when not reported).
    pub angle_deg: f64,
    /// Match score, camera-defined scale (0 when not reported).
    pub score: f64,
}

impl Reading {
    /// A reading with only a position (judgment unknown, nothing else reported).
    #[must_use]
    pub fn position(x_px: f64, y_px: f64) -> Reading {
        Reading {
            judgment: Judgment::Unknown,
            count: None,
            x_px,
            y_px,
            width_px: 0.0,
            height_px: 0.0,
            angle_deg: 0.0,
            score: 0.0,
        }
    }

    /// True when the camera found a usable mark: not NG, count not 0, finite coordinates.
    #[must_use]
    pub fn found(&self) -> bool {
        self.judgment != Judgment::Ng && self.count != Some(0) && self.x_px.is_finite() && self.y_px.is_finite()
    }
}

/// What a driver can do beyond triggering.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Capabilities {
    /// The driver can switch camera jobs/programs (M284).
    pub select_job: bool,
    /// The camera writes images that can be grabbed from a watch folder (M281 D1).
    pub grab_image: bool,
}

/// The common kind of a driver failure, so the core can react without knowing the driver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum DriverErrorKind {
    /// No answer within the timeout (unreachable camera, wrong IP/port, no data output).
    Timeout,
    /// The connection was refused or closed (not in Run mode, another client holds it).
    Refused,
    /// The camera answered, but its reply could not be understood.
    Malformed,
    /// The camera refused the command (an `ER,…` reply or equivalent). The core shows the
    /// driver's message as it is, so it says what the refusal means and what to do.
    Rejected,
    /// The driver does not support the operation.
    Unsupported,
    /// An argument was out of range before anything was sent.
    InvalidArgument,
    /// Anything else (I/O, internal).
    Other,
}

/// A driver failure: its kind, and the driver's own message (what happened, what to do).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DriverError {
    /// The common kind.
    pub kind: DriverErrorKind,
    /// The driver's message, in its own terms.
    pub message: String,
}

impl DriverError {
    /// Builds an error of `kind` with `message`.
    pub fn new(kind: DriverErrorKind, message: impl Into<String>) -> Self {
        DriverError { kind, message: message.into() }
    }
}

impl fmt::Display for DriverError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for DriverError {}

/// A smart camera, seen by the core. Implemented by `vision-driver-keyence`,
/// `vision-driver-sim`, and test fakes.
pub trait CameraDriver: Send {
    /// Short driver name (`Keyence`, `Sim`, …).
    fn name(&self) -> &str;

    /// What the driver can do beyond triggering.
    fn capabilities(&self) -> Capabilities;

    /// Triggers one inspection and returns its native reading.
    ///
    /// # Errors
    /// Timeout, refused/closed connection, malformed reply or camera-side rejection.
    fn trigger(&mut self) -> Result<Reading, DriverError>;

    /// Switches the camera to job `job` (0–999). Drivers without `select_job` return
    /// [`DriverErrorKind::Unsupported`].
    ///
    /// # Errors
    /// Unsupported, out of range, or the camera's refusal.
    fn select_job(&mut self, job: u32) -> Result<(), DriverError>;

    /// Tests the connection and returns the camera's firmware/version text.
    ///
    /// # Errors
    /// As [`CameraDriver::trigger`].
    fn test_connection(&mut self) -> Result<String, DriverError>;

    /// The I/O timeout the driver applies to one exchange (for diagnostics).
    fn timeout(&self) -> Duration {
        Duration::from_secs(3)
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)]
mod tests {
    use super::*;

    #[test]
    fn found_requires_not_ng_and_nonzero_count() {
        let mut r = Reading::position(10.0, 20.0);
        assert!(r.found());
        r.count = Some(0);
        assert!(!r.found());
        r.count = Some(1);
        r.judgment = Judgment::Ng;
        assert!(!r.found());
        r.judgment = Judgment::Ok;
        r.x_px = f64::NAN;
        assert!(!r.found());
        assert_eq!(Judgment::Unknown.code(), -1);
        assert_eq!(Judgment::Ok.code(), 1);
        assert_eq!(Judgment::Ng.code(), 0);
        assert_eq!([Judgment::Ok, Judgment::Ng, Judgment::Unknown].map(Judgment::label), ["OK", "NG", "unknown"]);
    }
}
