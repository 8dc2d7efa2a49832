//! The driver's own error type: what went wrong in the camera's terms, what to do about it,
//! and the common [`DriverErrorKind`] the core reacts to.
//!
//! As with the Keyence driver, the messages for the manual's troubleshooting symptoms start
//! with its words (`timeout: `, `connection refused: `, `Malformed response: `) so an operator
//! searching the manual finds them. A local video device is no connection: a missing or
//! unopenable one is named as such, with its path.

use std::fmt;
use std::time::Duration;

use vision_core::{DriverError, DriverErrorKind};

/// Why the camera driver failed.
///
/// `Display` prints what happened ([`CameraError::what`]), then ` — `, then what to do
/// ([`CameraError::fix`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum CameraError {
    /// A setting is unusable (nothing was opened).
    Config {
        /// The setting's name (`VisionCameraSource`, …).
        setting: &'static str,
        /// What is wrong with it.
        reason: String,
    },

    /// An image file or folder could not be read.
    File {
        /// The path.
        path: String,
        /// The operating system's words.
        reason: String,
    },

    /// The path exists but is not a regular file or folder (a FIFO, a device, a socket): it is
    /// not read.
    NotAFile {
        /// The path.
        path: String,
        /// What it is (`FIFO`, `character device`, …).
        kind: &'static str,
    },

    /// A frame ends before its image does (a cut-short file or transfer): refused, not
    /// searched, since its missing part would read as background.
    Damaged {
        /// Where the frame came from.
        from: String,
        /// What is missing.
        reason: String,
    },

    /// The replay folder holds no image file (`.jpg`, `.jpeg`, `.png`, `.pgm`, `.pnm`).
    EmptyFolder {
        /// The folder.
        dir: String,
    },

    /// Every image of the replay folder has been used.
    ReplayEnded {
        /// The folder.
        dir: String,
        /// How many images it held.
        count: usize,
    },

    /// A frame's bytes are not an image the driver can decode.
    Decode {
        /// Where the frame came from (a path, a URL, a device).
        from: String,
        /// What is wrong.
        reason: String,
    },

    /// A frame is larger than the driver accepts (a broken or hostile source).
    TooLarge {
        /// Where the frame came from.
        from: String,
        /// The bound, bytes or pixels as `what` says.
        limit: usize,
        /// `bytes` or `pixels`.
        what: &'static str,
    },

    /// A frame's header declares more pixels than the driver decodes (checked before decoding).
    TooManyPixels {
        /// Where the frame came from.
        from: String,
        /// Declared width, pixels.
        width: u32,
        /// Declared height, pixels.
        height: u32,
        /// The bound exceeded, in words (`100000000 pixels`, `16384 pixels a side`).
        limit: String,
    },

    /// The snapshot host name does not resolve.
    Resolve {
        /// `host:port`.
        addr: String,
        /// The resolver's words.
        reason: String,
    },

    /// No TCP connection to the snapshot server within the timeout.
    ConnectTimeout {
        /// The address tried.
        addr: String,
        /// The time allowed.
        timeout: Duration,
    },

    /// The snapshot server refused the connection.
    Refused {
        /// The address tried.
        addr: String,
        /// The operating system's words.
        reason: String,
    },

    /// The snapshot server, or the device, did not deliver a whole frame within the timeout.
    Timeout {
        /// The URL or device.
        from: String,
        /// The time allowed for the whole frame.
        timeout: Duration,
        /// What was still missing (`the status line`, `the body`, `a frame`).
        waiting_for: &'static str,
    },

    /// The snapshot server closed the connection before the frame was complete.
    Closed {
        /// The URL.
        url: String,
        /// What was still missing.
        waiting_for: &'static str,
    },

    /// The snapshot server answered, but not with a readable HTTP response.
    Http {
        /// The URL.
        url: String,
        /// What is wrong with the response.
        reason: String,
    },

    /// The snapshot server answered with an HTTP status other than 200.
    Status {
        /// The URL.
        url: String,
        /// The status code.
        code: u16,
        /// The reason phrase as sent (escaped, shortened).
        phrase: String,
    },

    /// The URL serves a continuous MJPEG stream, not one snapshot.
    Stream {
        /// The URL.
        url: String,
    },

    /// A socket error other than the ones above.
    Io {
        /// The URL or device.
        from: String,
        /// The operating system's words.
        reason: String,
    },

    /// The V4L2 device path names nothing (an unplugged camera, a typo).
    NoDevice {
        /// The device path.
        device: String,
    },

    /// The V4L2 device exists but could not be opened, or is no capture device.
    DeviceOpen {
        /// The device path.
        device: String,
        /// The operating system's words.
        reason: String,
    },

    /// The V4L2 device offers no format the driver can use, or not the one asked for.
    Format {
        /// The device path.
        device: String,
        /// What was asked for (`MJPEG 1280×960`, `any`).
        wanted: String,
        /// What the device offers (`YUYV 640×480, MJPEG 1280×720`, …).
        offered: String,
    },

    /// The V4L2 driver set another format than the one negotiated.
    FormatChanged {
        /// The device path.
        device: String,
        /// What was asked for.
        wanted: String,
        /// What the device set.
        got: String,
    },

    /// A raw frame has the wrong number of bytes for its format.
    ShortFrame {
        /// The device path.
        device: String,
        /// Bytes received.
        got: usize,
        /// Bytes the format needs.
        want: usize,
    },

    /// The source refused a camera job switch.
    Job {
        /// The job asked for.
        job: u32,
        /// The source's words.
        reason: String,
    },

    /// The operation is not supported by this driver (a camera job switch).
    Unsupported {
        /// What was asked.
        what: &'static str,
    },

    /// The mark search of a frame ran past `VisionCameraTimeout` and was cut off: nothing is
    /// known of the mark.
    SearchCutOff {
        /// The searched frame's (or search window's) width, px.
        width: u32,
        /// Its height, px.
        height: u32,
        /// The time allowed for the search.
        timeout: Duration,
    },
}

impl CameraError {
    /// The common kind the core reacts to.
    #[must_use]
    pub fn kind(&self) -> DriverErrorKind {
        match self {
            CameraError::Config { .. } => DriverErrorKind::InvalidArgument,
            CameraError::ConnectTimeout { .. } | CameraError::Timeout { .. } | CameraError::SearchCutOff { .. } => {
                DriverErrorKind::Timeout
            }
            CameraError::Refused { .. } | CameraError::Closed { .. } | CameraError::DeviceOpen { .. } => {
                DriverErrorKind::Refused
            }
            CameraError::Decode { .. }
            | CameraError::Damaged { .. }
            | CameraError::TooLarge { .. }
            | CameraError::TooManyPixels { .. }
            | CameraError::Http { .. }
            | CameraError::Stream { .. }
            | CameraError::ShortFrame { .. } => DriverErrorKind::Malformed,
            CameraError::Status { .. }
            | CameraError::Format { .. }
            | CameraError::FormatChanged { .. }
            | CameraError::Job { .. } => DriverErrorKind::Rejected,
            CameraError::Unsupported { .. } => DriverErrorKind::Unsupported,
            CameraError::File { .. }
            | CameraError::NotAFile { .. }
            | CameraError::EmptyFolder { .. }
            | CameraError::ReplayEnded { .. }
            | CameraError::NoDevice { .. }
            | CameraError::Resolve { .. }
            | CameraError::Io { .. } => DriverErrorKind::Other,
        }
    }

    /// What happened, in one clause, without advice.
    #[must_use]
    pub fn what(&self) -> String {
        match self {
            CameraError::Config { setting, reason } => format!("invalid camera setting {setting}: {reason}"),
            CameraError::File { path, reason } => format!("cannot read {path}: {reason}"),
            CameraError::NotAFile { path, kind } => format!("{path} is a {kind}, not a regular file: not read"),
            CameraError::Damaged { from, reason } => {
                format!("Malformed response: the frame from {from} is damaged: {reason}")
            }
            CameraError::EmptyFolder { dir } => format!("the replay folder {dir} holds no image file"),
            CameraError::ReplayEnded { dir, count } => {
                format!("the replay folder {dir} is used up: all {count} images were taken")
            }
            CameraError::Decode { from, reason } => {
                format!("Malformed response: the frame from {from} is not an image ({reason})")
            }
            CameraError::TooLarge { from, limit, what } => {
                format!("Malformed response: the frame from {from} is larger than {limit} {what}")
            }
            CameraError::TooManyPixels { from, width, height, limit } => {
                format!("Malformed response: the frame from {from} declares {width}×{height} pixels, more than {limit}")
            }
            CameraError::Resolve { addr, reason } => format!("camera address {addr} does not resolve ({reason})"),
            CameraError::ConnectTimeout { addr, timeout } => {
                format!("timeout: no connection to the camera at {addr} within {}", secs(*timeout))
            }
            CameraError::Refused { addr, reason } => {
                format!("connection refused: camera at {addr} refused the connection ({reason})")
            }
            CameraError::Timeout { from, timeout, waiting_for } => {
                format!("timeout: no complete frame from {from} within {}: {waiting_for} never came", secs(*timeout))
            }
            CameraError::Closed { url, waiting_for } => {
                format!(
                    "camera at {url} closed the connection before the frame was complete ({waiting_for} never came)"
                )
            }
            CameraError::Http { url, reason } => format!("Malformed response: {url} answered {reason}"),
            CameraError::Status { url, code, phrase } => format!("camera at {url} answered HTTP {code} {phrase}"),
            CameraError::Stream { url } => {
                format!("Malformed response: {url} serves a continuous MJPEG stream, not a snapshot")
            }
            CameraError::Io { from, reason } => format!("I/O error reading {from}: {reason}"),
            CameraError::NoDevice { device } => format!("the video device {device} does not exist"),
            CameraError::DeviceOpen { device, reason } => format!("cannot open the video device {device} ({reason})"),
            CameraError::Format { device, wanted, offered } => {
                format!("{device} does not offer {wanted}; it offers {offered}")
            }
            CameraError::FormatChanged { device, wanted, got } => {
                format!("{device} was asked for {wanted} but set {got}")
            }
            CameraError::ShortFrame { device, got, want } => {
                format!("Malformed response: a frame from {device} has {got} bytes, its format needs {want}")
            }
            CameraError::Job { job, reason } => format!("the camera refused job {job}: {reason}"),
            CameraError::Unsupported { what } => format!("the camera driver cannot {what}"),
            CameraError::SearchCutOff { width, height, timeout } => format!(
                "timeout: the mark search in a {width}×{height} frame was cut off after {} (VisionCameraTimeout); \
                 nothing is known of the mark",
                secs(*timeout)
            ),
        }
    }

    /// What to do about it.
    #[must_use]
    pub fn fix(&self) -> String {
        match self {
            CameraError::Config { .. } => "correct the setting in the profile's [camera] table".into(),
            CameraError::File { .. } => "check VisionCameraSource names an existing, readable file or folder".into(),
            CameraError::NotAFile { .. } => {
                "VisionCameraSource takes an image file or a folder of them; a V4L2 camera is written /dev/videoN or v4l2:PATH".into()
            }
            CameraError::Damaged { .. } => {
                "the frame was cut short: check the camera's link, or that the file was written completely".into()
            }
            CameraError::EmptyFolder { .. } => "put .jpg, .png or .pgm frames in the folder, or point VisionCameraSource at another".into(),
            CameraError::ReplayEnded { .. } => {
                "a replay folder holds one image per trigger, in name order: add images or restart the run".into()
            }
            CameraError::Decode { .. } => {
                "the driver reads JPEG, PNG and PGM images: check VisionCameraSource points at a still image".into()
            }
            CameraError::TooLarge { .. } | CameraError::TooManyPixels { .. } => {
                "check VisionCameraSource; frames above 100 megapixels or 16384 pixels a side are refused".into()
            }
            CameraError::Resolve { .. } => "check the host name in VisionCameraSource, or use the camera's IP address".into(),
            CameraError::ConnectTimeout { .. } => {
                "check the camera is powered and on this network, and the address and port in VisionCameraSource".into()
            }
            CameraError::Refused { .. } => {
                "check the snapshot server (mjpg-streamer, ustreamer, the camera's web server) is running on that port".into()
            }
            CameraError::Timeout { .. } => "check the camera is running, or raise VisionCameraTimeout".into(),
            CameraError::Closed { .. } => "check the snapshot server's log; the next trigger reconnects".into(),
            CameraError::Http { .. } => "check VisionCameraSource is the camera's HTTP snapshot URL".into(),
            CameraError::Status { code: 401 | 403, .. } => {
                "the camera wants a login: enable anonymous snapshots or use a URL that needs none".into()
            }
            CameraError::Status { code: 404, .. } => {
                "check the snapshot path: mjpg-streamer serves /?action=snapshot, ustreamer /snapshot".into()
            }
            CameraError::Status { .. } => "check the camera's web server and the snapshot URL".into(),
            CameraError::Stream { .. } => {
                "use the snapshot URL instead: mjpg-streamer /?action=snapshot, ustreamer /snapshot".into()
            }
            CameraError::Io { .. } => "check the link to the camera; the next trigger tries again".into(),
            CameraError::NoDevice { .. } => {
                "check the camera is plugged in and the path: ls /dev/video* lists the devices, and \
                 /dev/v4l/by-id/ names each camera by a path that survives re-plugging"
                    .into()
            }
            CameraError::DeviceOpen { .. } => {
                "check the device exists (ls /dev/video*), that you are in the video group, and that no other \
                 program (a browser, OpenPnP, mjpg-streamer) holds it"
                    .into()
            }
            CameraError::Format { .. } | CameraError::FormatChanged { .. } => {
                "set VisionCameraWidth, VisionCameraHeight and VisionCameraPixelFormat to one the device offers (v4l2-ctl --list-formats-ext)".into()
            }
            CameraError::ShortFrame { .. } => "check the USB link (a hub or a long cable drops data) and retry".into(),
            CameraError::Job { .. } => "use a job the camera has (M284 P), or P0 to leave its job alone".into(),
            CameraError::Unsupported { .. } => "leave the camera's job alone (M284 P0)".into(),
            CameraError::SearchCutOff { .. } => {
                "narrow VisionCameraSearchRadius to the mark, lower the camera's resolution, check \
                 VisionCameraMarkDiameterPx (a small diameter searches finely), or raise VisionCameraTimeout"
                    .into()
            }
        }
    }
}

impl fmt::Display for CameraError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} — {}", self.what(), self.fix())
    }
}

impl From<CameraError> for DriverError {
    fn from(e: CameraError) -> Self {
        DriverError::new(e.kind(), e)
    }
}

/// A duration as `3 s` or `0.250 s`.
pub(crate) fn secs(d: Duration) -> String {
    let s = d.as_secs_f64();
    if s >= 1.0 && (s - s.round()).abs() < 1e-9 {
        format!("{} s", s.round())
    } else {
        format!("{s:.3} s")
    }
}

/// `text` made safe to show: control characters escaped, at most `max` characters.
pub(crate) fn printable(text: &str, max: usize) -> String {
    let mut out: String = text.chars().take(max).flat_map(char::escape_default).collect();
    if text.chars().count() > max {
        out.push('…');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transport_faults_start_with_the_manuals_symptom() {
        let t = Duration::from_secs(3);
        let cases = [
            (
                CameraError::Timeout { from: "http://cam/snap".into(), timeout: t, waiting_for: "the body" },
                "timeout: ",
                DriverErrorKind::Timeout,
            ),
            (
                CameraError::ConnectTimeout { addr: "10.0.0.9:80".into(), timeout: t },
                "timeout: ",
                DriverErrorKind::Timeout,
            ),
            (
                CameraError::Refused { addr: "10.0.0.9:80".into(), reason: "os error 111".into() },
                "connection refused: ",
                DriverErrorKind::Refused,
            ),
            (
                CameraError::Http { url: "http://cam/".into(), reason: "no status line".into() },
                "Malformed response: ",
                DriverErrorKind::Malformed,
            ),
            (
                CameraError::Decode { from: "a.png".into(), reason: "bad".into() },
                "Malformed response: ",
                DriverErrorKind::Malformed,
            ),
        ];
        for (e, start, kind) in cases {
            assert_eq!(e.kind(), kind);
            let user = DriverError::from(e.clone()).to_string();
            assert!(user.starts_with(start), "{user}");
            assert_eq!(user.matches(" — ").count(), 1, "{user}");
            assert_eq!(DriverError::from(e.clone()).downcast_ref::<CameraError>(), Some(&e));
        }
    }

    #[test]
    fn http_statuses_get_their_own_advice() {
        let status = |code| CameraError::Status { url: "http://cam/x".into(), code, phrase: "P".into() };
        assert!(status(404).fix().contains("/?action=snapshot"));
        assert!(status(401).fix().contains("login"));
        assert_eq!(status(500).kind(), DriverErrorKind::Rejected);
        assert_eq!(status(500).what(), "camera at http://cam/x answered HTTP 500 P");
    }

    #[test]
    fn text_from_outside_is_escaped_and_shortened() {
        assert_eq!(printable("a\r\nb", 10), "a\\r\\nb");
        assert_eq!(printable("abcdef", 3), "abc…");
        assert_eq!(secs(Duration::from_millis(250)), "0.250 s");
        assert_eq!(secs(Duration::from_secs(2)), "2 s");
    }
}
