//! The camera side: what a driver must do, and nothing more (SPEC §7: drivers are dumb).
//!
//! A driver triggers the camera and returns the **native** pixel reading. Every conversion to
//! machine units lives in the core. Each driver keeps its own rich error type and maps it to a
//! [`DriverErrorKind`] so the core can react without knowing the driver.

use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

use crate::kind_error::{Kind, KindError};

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
    /// The driver can keep the image of a trigger (M281 D1, [`CameraDriver::grab_image`]).
    pub grab_image: bool,
}

/// What M281 D1 asks of [`CameraDriver::grab_image`]: which trigger's image, and where to keep it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImageRequest<'a> {
    /// The folder to save the image into (the module's images folder; created if missing).
    pub dir: &'a Path,
    /// When the trigger was sent (the host's clock): an image older than this is not its image.
    pub since: SystemTime,
    /// The trigger's time as a file-name stamp (`YYYYMMDD_HHMMSS_mmm`): the saved file is named
    /// `vision_<stamp>.<ext>` (`_2`, `_3`, … when taken); a file is never overwritten.
    pub stamp: &'a str,
}

/// The common kind of a driver failure, so the core can react without knowing the driver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum DriverErrorKind {
    /// No complete answer within the timeout (unreachable camera, wrong address, or a camera
    /// that answered but sent no result).
    Timeout,
    /// The connection was refused or closed (not in Run mode, another client holds it).
    Refused,
    /// The camera answered, but its reply could not be understood.
    Malformed,
    /// The camera refused the command (an error reply). The driver's message says what the
    /// refusal means and what to do.
    Rejected,
    /// The driver does not support the operation.
    Unsupported,
    /// An argument was out of range before anything was sent.
    InvalidArgument,
    /// Anything else (I/O, internal).
    Other,
}

impl Kind for DriverErrorKind {
    const NAME: &'static str = "DriverError";
    const PREFIX: &'static str = "";
}

/// A driver failure: the common [`DriverErrorKind`] the core reacts to, and the driver's own
/// typed error, kept whole as the cause ([`KindError`]).
///
/// `Display` is the driver's explanation as it is: what happened in the camera's terms and
/// what to do. Only the driver knows its camera, so the core never rewrites or prefixes it.
/// The typed error is reachable with [`KindError::get_ref`] and [`KindError::downcast_ref`].
pub type DriverError = KindError<DriverErrorKind>;

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

    /// What the operator should know about `reading`, a usable reading [`CameraDriver::trigger`]
    /// just returned, in the driver's words: e.g. that the camera found several marks and which
    /// one it reported. The core shows it as the capture's warning (`VisionLastStatus` =
    /// `OK (warning: …)`). The default has nothing to say.
    fn reading_warning(&self, reading: &Reading) -> Option<String> {
        let _ = reading;
        None
    }

    /// Why the last trigger found no mark, in the driver's words (e.g. "the finder saw 2
    /// candidate marks and would not pick one"), for the NG message. A camera that judges its
    /// own job (Keyence) has nothing more to say than NG: the default is `None`.
    fn miss_reason(&self) -> Option<String> {
        None
    }

    /// M281 D1: keeps the image of the trigger `request` describes, saved into `request.dir`,
    /// and returns the saved file's path. How the camera delivers images (a folder it pushes
    /// them to, a download, …) is the driver's business and its settings'. The default, for a
    /// driver without [`Capabilities::grab_image`], answers [`DriverErrorKind::Unsupported`].
    ///
    /// # Errors
    /// Unsupported, no image in time, or the image could not be saved; M281 reports it as a
    /// warning, never as a failed capture.
    fn grab_image(&mut self, request: &ImageRequest<'_>) -> Result<PathBuf, DriverError> {
        let _ = request;
        Err(DriverError::new(DriverErrorKind::Unsupported, format!("camera driver {} cannot keep images", self.name())))
    }

    /// The mark the driver searches for, as a short text (`dot, dark on light`), for the
    /// calibration's record: M281 warns when it differs from the one M283 calibrated with. The
    /// default, for a camera that runs its own job (Keyence), is `None`.
    fn mark_spec(&self) -> Option<String> {
        None
    }

    /// The size of the frames the camera delivers, `(width, height)` in pixels, when the camera
    /// reports one (a camera whose images the driver decodes; the simulator). A driver that
    /// has not seen a frame yet may take one to find out; a failure to take it is `None` (the
    /// next trigger reports it). The default, for a camera that reports only positions
    /// (Keyence), is `None`: then `VisionCameraResX/Y` are the operator's word.
    fn frame_size(&mut self) -> Option<(u32, u32)> {
        None
    }

    /// The I/O timeout the driver applies to one exchange (for diagnostics).
    fn timeout(&self) -> Duration {
        Duration::from_secs(3)
    }

    /// The image the last trigger searched, for a host that shows it (the operator panel). The
    /// core knows no image type, so the driver hands its own (`vision_driver_camera::Frame`)
    /// for the host to downcast. The default, for a camera that sends only positions (Keyence,
    /// the simulator), is `None`.
    fn last_frame(&self) -> Option<&dyn std::any::Any> {
        None
    }
}

#[cfg(test)]
mod tests {
    use std::fmt;

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

    /// A driver's own error type, with a cause of its own.
    #[derive(Debug)]
    struct CameraFault(std::io::Error);

    impl fmt::Display for CameraFault {
        fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            f.write_str("the camera closed the connection — another client holds it")
        }
    }

    impl std::error::Error for CameraFault {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            Some(&self.0)
        }
    }

    #[test]
    fn the_drivers_typed_error_is_kept_whole() {
        use std::error::Error as _;
        let reset = std::io::Error::from(std::io::ErrorKind::ConnectionReset);
        let e = DriverError::new(DriverErrorKind::Refused, CameraFault(reset));
        assert_eq!(e.kind(), DriverErrorKind::Refused);
        assert_eq!(e.to_string(), "the camera closed the connection — another client holds it");
        let typed = e.downcast_ref::<CameraFault>().expect("the driver's own type");
        assert_eq!(typed.0.kind(), std::io::ErrorKind::ConnectionReset);
        assert!(e.get_ref().is::<CameraFault>());
        // Transparent: the chain goes on with the driver error's own cause, not its text again.
        let cause = e.source().expect("the cause's cause").to_string();
        assert_eq!(cause, std::io::Error::from(std::io::ErrorKind::ConnectionReset).to_string());
        // A clone shares the cause; equality is kind and text.
        assert_eq!(e.clone(), e);
        assert_ne!(DriverError::new(DriverErrorKind::Timeout, e.to_string()), e);
        assert_eq!(DriverError::new(DriverErrorKind::Refused, e.to_string()), e);
        assert!(DriverError::new(DriverErrorKind::Other, "text").downcast_ref::<CameraFault>().is_none());
    }
}
