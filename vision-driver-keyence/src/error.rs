//! The driver's own error type: what went wrong in Keyence terms, what to do about it, and the
//! common [`DriverErrorKind`] the core reacts to.

use std::fmt;
use std::time::Duration;

use vision_core::{DriverError, DriverErrorKind};

/// Why a Keyence command failed.
///
/// Each variant says what happened ([`KeyenceError::what`]) and what to do
/// ([`KeyenceError::fix`]); `Display` prints both, and is what the operator reads: the core shows
/// a driver error as the driver words it. [`KeyenceError::kind`] maps it to the core's
/// [`DriverErrorKind`]; `From<KeyenceError> for DriverError` keeps the typed error whole as the
/// cause ([`DriverError::downcast_ref`] gets it back).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum KeyenceError {
    /// The configuration is unusable (nothing was sent).
    Config {
        /// What is wrong.
        reason: String,
    },

    /// The camera host name does not resolve to an address.
    Resolve {
        /// `VisionIP` as given.
        host: String,
        /// `VisionPort`.
        port: u16,
        /// The resolver's words.
        reason: String,
    },

    /// No TCP connection within the timeout (nothing answered the connection request).
    ConnectTimeout {
        /// The address tried.
        addr: String,
        /// The time allowed.
        timeout: Duration,
    },

    /// The network says the camera cannot be reached (no route, host or network unreachable).
    Unreachable {
        /// The address tried.
        addr: String,
        /// The operating system's words.
        reason: String,
    },

    /// The camera actively refused the connection.
    Refused {
        /// The address tried.
        addr: String,
        /// The operating system's words.
        reason: String,
    },

    /// The camera did not complete its reply within the timeout. The connection was dropped,
    /// so a late reply can never answer a later command.
    Timeout {
        /// The command sent (`TRG`, `FVR`, …).
        command: String,
        /// The time allowed for the whole exchange.
        timeout: Duration,
        /// What was still missing (`the TRG echo`, `the data line`, …).
        waiting_for: String,
        /// Whether the command's echo had arrived: the camera accepted the command but sent no
        /// data (for `TRG`: no Data Output tool, or an inspection longer than the timeout).
        echoed: bool,
        /// A line that arrived but belonged to no command (stale or foreign), if any.
        ignored: Option<String>,
    },

    /// The camera closed the connection (or reset it) before its reply was complete.
    Closed {
        /// The command sent.
        command: String,
        /// What was still missing (for `connect`, the address).
        waiting_for: String,
    },

    /// Another socket error.
    Io {
        /// The command sent.
        command: String,
        /// The error's kind.
        kind: std::io::ErrorKind,
        /// The operating system's words.
        message: String,
    },

    /// The camera answered with a line the driver cannot understand.
    Malformed {
        /// The command sent.
        command: String,
        /// The line received (escaped, shortened for display).
        line: String,
        /// What is wrong with it.
        reason: String,
    },

    /// The device at the camera's address answered, but not in the Non-Procedural protocol
    /// (a web server, an SSH server, another device on that port).
    NotKeyence {
        /// `VisionIP:VisionPort`.
        addr: String,
        /// The command sent.
        command: String,
        /// The first bytes it sent, escaped (at most [`FIRST_BYTES_SHOWN`] of them).
        answered: String,
    },

    /// The camera refused the command with `ER,<cmd>,<nn>`.
    Rejected {
        /// The command the camera refused.
        command: String,
        /// The two-digit error code (`01`…`07`).
        code: String,
        /// The reply line as received, e.g. `ER,TRG,06`.
        reply: String,
        /// Earlier refusals in the same call, e.g. `ER,PL,01` before the `PW` fallback.
        previous: Vec<String>,
    },

    /// A reply line is longer than the configured bound (a broken or hostile peer).
    LineTooLong {
        /// The command sent.
        command: String,
        /// The bound, bytes.
        limit: usize,
    },

    /// A reply has more lines than the configured bound (a broken or hostile peer).
    TooManyLines {
        /// The command sent.
        command: String,
        /// The bound, lines.
        limit: usize,
    },

    /// A job number outside 0–999 (nothing was sent).
    InvalidJob {
        /// The job asked for.
        job: u32,
    },

    /// M281 D1, but `VisionImageWatchDir` is empty: the driver does not know where the camera
    /// pushes its images.
    NoImageFolder,

    /// No image newer than the trigger came into the watch folder in time.
    NoImage {
        /// The watch folder.
        dir: String,
        /// The time waited (`VisionImageGrabTimeout`).
        timeout: Duration,
    },

    /// The watch folder could not be read, or the image not copied.
    Image {
        /// What failed, with the operating system's words.
        reason: String,
    },
}

impl KeyenceError {
    /// The common kind the core reacts to.
    #[must_use]
    pub fn kind(&self) -> DriverErrorKind {
        match self {
            KeyenceError::Config { .. } | KeyenceError::InvalidJob { .. } | KeyenceError::NoImageFolder => {
                DriverErrorKind::InvalidArgument
            }
            KeyenceError::Resolve { .. } | KeyenceError::Io { .. } | KeyenceError::Image { .. } => {
                DriverErrorKind::Other
            }
            KeyenceError::ConnectTimeout { .. }
            | KeyenceError::Unreachable { .. }
            | KeyenceError::Timeout { .. }
            | KeyenceError::NoImage { .. } => DriverErrorKind::Timeout,
            KeyenceError::Refused { .. } | KeyenceError::Closed { .. } => DriverErrorKind::Refused,
            KeyenceError::Malformed { .. }
            | KeyenceError::NotKeyence { .. }
            | KeyenceError::LineTooLong { .. }
            | KeyenceError::TooManyLines { .. } => DriverErrorKind::Malformed,
            KeyenceError::Rejected { .. } => DriverErrorKind::Rejected,
        }
    }

    /// What happened, in one clause, without advice.
    #[must_use]
    pub fn what(&self) -> String {
        match self {
            KeyenceError::Config { reason } => format!("invalid Keyence driver configuration: {reason}"),
            KeyenceError::Resolve { host, port, reason } => {
                format!("camera address {host}:{port} does not resolve ({reason})")
            }
            KeyenceError::ConnectTimeout { addr, timeout } => {
                format!("timeout: no connection to the camera at {addr} within {}", secs(*timeout))
            }
            KeyenceError::Unreachable { addr, reason } => format!("camera at {addr} is unreachable ({reason})"),
            KeyenceError::Refused { addr, reason } => {
                format!("connection refused: camera at {addr} refused the connection ({reason})")
            }
            KeyenceError::Timeout { command, timeout, waiting_for, echoed, ignored } => {
                let mut s = if *echoed {
                    format!("timeout: the camera echoed {command} but sent no data within {}", secs(*timeout))
                } else {
                    format!(
                        "timeout: no complete reply to {command} within {}: {waiting_for} never came",
                        secs(*timeout)
                    )
                };
                if let Some(line) = ignored {
                    s.push_str(&format!("; ignored a line that answered no command: {line}"));
                }
                s
            }
            KeyenceError::Closed { command, waiting_for } if command == "connect" => {
                format!("camera at {waiting_for} closed the connection as it was made")
            }
            KeyenceError::Closed { command, waiting_for } => {
                format!("camera closed the connection during {command} ({waiting_for} never came)")
            }
            KeyenceError::Io { command, message, .. } => format!("socket error during {command}: {message}"),
            KeyenceError::Malformed { command, line, reason } => {
                format!("Malformed response: reply to {command} not understood ({reason}): {line}")
            }
            KeyenceError::NotKeyence { addr, command, answered } => format!(
                "Malformed response: the device at {addr} does not speak the Keyence Non-Procedural protocol: to \
                 {command} it answered \"{answered}\""
            ),
            KeyenceError::Rejected { command, reply, previous, .. } => {
                let mut s = String::from("camera replied ");
                for p in previous {
                    s.push_str(p);
                    s.push_str(" then ");
                }
                s.push_str(reply);
                s.push_str(" to ");
                s.push_str(command);
                s
            }
            KeyenceError::LineTooLong { command, limit } => {
                format!("Malformed response: a reply line to {command} is longer than {limit} bytes")
            }
            KeyenceError::TooManyLines { command, limit } => {
                format!("Malformed response: the reply to {command} ran past {limit} lines without the expected answer")
            }
            KeyenceError::InvalidJob { job } => format!("camera job {job} is out of range (0–999)"),
            KeyenceError::NoImageFolder => "VisionImageWatchDir is empty".into(),
            KeyenceError::NoImage { dir, timeout } => {
                format!("no image newer than the trigger appeared in {dir} within {:.1} s", timeout.as_secs_f64())
            }
            KeyenceError::Image { reason } => reason.clone(),
        }
    }

    /// What to do about it.
    #[must_use]
    pub fn fix(&self) -> String {
        match self {
            KeyenceError::Config { .. } => "check VisionIP, VisionPort and VisionTimeout".into(),
            KeyenceError::Resolve { .. } => "set VisionIP to the camera's IP address (default 192.168.208.80)".into(),
            KeyenceError::ConnectTimeout { .. } | KeyenceError::Unreachable { .. } => {
                "check the camera is powered and cabled, that VisionIP and VisionPort match the camera, and that \
                 the PC and the camera are on the same subnet"
                    .into()
            }
            KeyenceError::Refused { .. } => {
                "check VisionPort (Keyence default 8500), that the camera is in Run mode, and that no other client \
                 holds the camera's command socket"
                    .into()
            }
            KeyenceError::Timeout { echoed, .. } => {
                if *echoed {
                    "the camera answered but sent no data: add a Data Output (Non-Procedural) tool to the job, or \
                     raise VisionTimeout if the inspection takes longer"
                        .into()
                } else {
                    "check the camera is reachable and in Run mode, and that VisionIP and VisionPort point at its \
                     Non-Procedural command port"
                        .into()
                }
            }
            KeyenceError::Closed { .. } => {
                "another client probably holds the camera's only command socket (close it), or the camera left \
                 Run mode; the next command reconnects"
                    .into()
            }
            KeyenceError::Io { .. } => "check the network link to the camera; the next command reconnects".into(),
            KeyenceError::Malformed { command, .. }
            | KeyenceError::LineTooLong { command, .. }
            | KeyenceError::TooManyLines { command, .. } => reply_advice(command).into(),
            KeyenceError::NotKeyence { .. } => {
                "check VisionIP and VisionPort: they must address a Keyence VS camera's Non-Procedural command \
                 port (8500 by default), not a web server, an SSH server or another device"
                    .into()
            }
            KeyenceError::Rejected { command, code, .. } => rejection_advice(command, code),
            KeyenceError::InvalidJob { .. } => "use a camera job number 0–999".into(),
            KeyenceError::NoImageFolder => {
                "set VisionImageWatchDir to the folder the camera FTP-pushes its images into".into()
            }
            KeyenceError::NoImage { .. } => "check the camera's FTP push and VisionImageWatchDir".into(),
            KeyenceError::Image { .. } => {
                "check that VisionImageWatchDir is readable and the images folder writable".into()
            }
        }
    }

    /// The `ER,<cmd>,<nn>` code when the camera refused the command.
    #[must_use]
    pub fn code(&self) -> Option<&str> {
        match self {
            KeyenceError::Rejected { code, .. } => Some(code),
            _ => None,
        }
    }
}

/// The most bytes of a foreign device's answer [`KeyenceError::NotKeyence`] shows.
pub const FIRST_BYTES_SHOWN: usize = 64;

impl fmt::Display for KeyenceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} — {}", self.what(), self.fix())
    }
}

/// The meaning of a VS-series `ER` code (SPEC §7), `None` for a code the manual does not list.
#[must_use]
pub fn er_meaning(code: &str) -> Option<&'static str> {
    Some(match code {
        "01" => "unknown command",
        "02" => "wrong number of arguments",
        "03" => "argument out of range",
        "04" => "wrong argument type",
        "05" => "not acceptable now (the camera is loading a program, or serving the command from another route)",
        "06" => "not executable (the camera is not in Run mode, or the trigger source is not Communication)",
        "07" => "camera-side timeout (the command, or the measurement it started, did not complete in time)",
        _ => return None,
    })
}

fn rejection_advice(command: &str, code: &str) -> String {
    let meaning = er_meaning(code).unwrap_or("an error code the VS manual does not list");
    let todo = match (command, code) {
        ("TRG", "01") => {
            "switch the camera to Run mode (in Setup mode it does not accept TRG); a CV-X or IV camera does \
             not know TRG at all: this driver needs a VS-series camera"
        }
        ("TRG", "06") => "switch the camera to Run mode and set the job's trigger source to Communication",
        ("TRG", "07") => {
            "the measurement did not complete within the camera's configured window; check the job and retry"
        }
        ("PL" | "PW", "01") => "this camera series knows neither PL (VS) nor PW (CV-X, IV) for job switching",
        ("PL" | "PW", "03") => "the job number does not exist on the camera; check M284 P and VisionActiveJob",
        (_, "05") => "wait for the camera to finish loading the job, then retry",
        (_, "06") => "switch the camera to Run mode",
        (_, "07") => "the rest of the command did not arrive within 3 s; check the network link and retry",
        (_, "02" | "04") => "the camera series does not take this command's arguments; check the camera model",
        _ => "see the camera's Non-Procedural command manual",
    };
    format!("{meaning}: {todo}")
}

/// What to do about a reply the driver could not read, by the command it answered.
fn reply_advice(command: &str) -> &'static str {
    match command {
        "TRG" => {
            "set the job's Data Output (Non-Procedural) tool to emit the mark in image pixels: x,y or \
             judgment,x,y or judgment,count,x,y,width,height,angle,score, ending in CR"
        }
        "PR" | "PL" | "PW" => {
            "job switching (M284) expects PR,<device>,<job> to PR and a bare PL or PW to PL/PW, as VS, CV-X and \
             IV cameras answer: check the camera model, or leave the camera's job alone with M284 P0"
        }
        _ => "check that VisionPort is the camera's Non-Procedural command port (8500 by default)",
    }
}

fn secs(d: Duration) -> String {
    let s = d.as_secs_f64();
    if s >= 1.0 && (s - s.round()).abs() < 1e-9 {
        format!("{} s", s.round())
    } else {
        format!("{s:.3} s")
    }
}

impl From<KeyenceError> for DriverError {
    fn from(e: KeyenceError) -> Self {
        DriverError::new(e.kind(), e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vision_core::VisionError;

    fn rejected(command: &str, code: &str) -> KeyenceError {
        KeyenceError::Rejected {
            command: command.into(),
            code: code.into(),
            reply: format!("ER,{command},{code}"),
            previous: Vec::new(),
        }
    }

    /// What the operator reads: the driver error through the core's `VisionError::Driver`.
    fn user_text(e: KeyenceError) -> String {
        VisionError::Driver(DriverError::from(e)).to_string()
    }

    #[test]
    fn rejected_reads_well_through_the_core() {
        let e = rejected("TRG", "06");
        assert_eq!(e.kind(), DriverErrorKind::Rejected);
        assert_eq!(e.code(), Some("06"));
        let standalone = e.to_string();
        assert!(standalone.starts_with("camera replied ER,TRG,06 to TRG — not executable"), "{standalone}");
        let user = user_text(e);
        assert_eq!(user, standalone, "the core shows a refusal as the driver words it");
        assert_eq!(user.matches("switch the camera to Run mode").count(), 1, "{user}");
        assert!(user.contains("set the job's trigger source to Communication"), "{user}");
        // Every listed code: the raw reply survives, the advice appears once.
        for code in ["01", "02", "03", "04", "05", "06", "07"] {
            let user = user_text(rejected("TRG", code));
            assert_eq!(user.matches(&format!("ER,TRG,{code}")).count(), 1, "{user}");
            assert_eq!(user.matches(" — ").count(), 1, "{user}");
            assert!(user.contains(er_meaning(code).unwrap_or("?")), "{user}");
        }
    }

    #[test]
    fn the_manuals_fix_for_each_command_reaches_the_user() {
        // ER,PL,03 for a job the camera does not have: the driver's command-specific advice,
        // not a generic "check the job number (0–999)" for a job inside that range.
        let user = user_text(rejected("PL", "03"));
        assert!(user.contains("does not exist on the camera"), "{user}");
        assert!(user.contains("check M284 P"), "{user}");
        assert!(!user.contains("0–999"), "{user}");
        // The manual's error table for TRG.
        let user = user_text(rejected("TRG", "01"));
        assert!(user.contains("switch the camera to Run mode (in Setup mode it does not accept TRG)"), "{user}");
        assert!(user.contains("a CV-X or IV camera does not know TRG"), "{user}");
        let user = user_text(rejected("TRG", "07"));
        assert!(user.contains("did not complete within the camera's configured window"), "{user}");
        let user = user_text(rejected("PL", "07"));
        assert!(user.contains("did not arrive within 3 s"), "{user}");
        let user = user_text(rejected("PR", "05"));
        assert!(user.contains("wait for the camera to finish loading the job"), "{user}");
    }

    #[test]
    fn unknown_code_keeps_our_advice() {
        let user = user_text(rejected("TRG", "42"));
        assert!(user.starts_with("camera replied ER,TRG,42 to TRG — an error code the VS manual"), "{user}");
    }

    #[test]
    fn fallback_names_both_refusals() {
        let e = KeyenceError::Rejected {
            command: "PW".into(),
            code: "01".into(),
            reply: "ER,PW,01".into(),
            previous: vec!["ER,PL,01".into()],
        };
        assert_eq!(e.what(), "camera replied ER,PL,01 then ER,PW,01 to PW");
        assert!(e.fix().contains("neither PL"));
    }

    fn timeout(waiting_for: &str, echoed: bool) -> KeyenceError {
        KeyenceError::Timeout {
            command: "TRG".into(),
            timeout: Duration::from_secs(3),
            waiting_for: waiting_for.into(),
            echoed,
            ignored: None,
        }
    }

    #[test]
    fn a_timeout_after_the_echo_says_the_camera_answered() {
        let user = user_text(timeout("the data line (the TRG echo arrived)", true));
        assert_eq!(
            user,
            "timeout: the camera echoed TRG but sent no data within 3 s — the camera answered but sent no data: add a Data \
             Output (Non-Procedural) tool to the job, or raise VisionTimeout if the inspection takes longer"
        );
        assert!(!user.contains("unreachable"), "{user}");
        // No echo: the camera may not be there at all.
        let silent = user_text(timeout("the TRG echo", false));
        assert!(
            silent.starts_with(
                "timeout: no complete reply to TRG within 3 s: the TRG echo never came — check the camera is \
                 reachable"
            ),
            "{silent}"
        );
        // The advice follows whether the echo came, not the wording of what was missing.
        let e = timeout("the data line (the TRG echo arrived)", false);
        assert_eq!(e.fix(), timeout("the TRG echo", false).fix());
    }

    /// The manual's troubleshooting table names the symptoms "timeout", "connection refused" and
    /// "Malformed response"; operators search for those words, so each message for those faults
    /// starts with them, and keeps its own detail after.
    #[test]
    fn each_transport_fault_starts_with_the_manuals_symptom() {
        let cases = [
            (timeout("the TRG echo", false), "timeout: no complete reply to TRG within 3 s: the TRG echo never came"),
            (timeout("the data line", true), "timeout: the camera echoed TRG but sent no data within 3 s"),
            (
                KeyenceError::ConnectTimeout { addr: "192.168.208.80:8500".into(), timeout: Duration::from_secs(1) },
                "timeout: no connection to the camera at 192.168.208.80:8500 within 1 s",
            ),
            (
                KeyenceError::Refused { addr: "192.168.208.80:8500".into(), reason: "os error 111".into() },
                "connection refused: camera at 192.168.208.80:8500 refused the connection (os error 111)",
            ),
            (
                KeyenceError::Malformed {
                    command: "TRG".into(),
                    line: "1,2,3,4,5,6,7".into(),
                    reason: "7 fields".into(),
                },
                "Malformed response: reply to TRG not understood (7 fields): 1,2,3,4,5,6,7",
            ),
            (
                KeyenceError::LineTooLong { command: "TRG".into(), limit: 512 },
                "Malformed response: a reply line to TRG is longer than 512 bytes",
            ),
            (
                KeyenceError::TooManyLines { command: "TRG".into(), limit: 8 },
                "Malformed response: the reply to TRG ran past 8 lines without the expected answer",
            ),
        ];
        for (e, start) in cases {
            let kind = e.kind();
            let user = user_text(e);
            assert!(user.starts_with(&format!("{start} — ")), "{user}");
            let symptom = match kind {
                DriverErrorKind::Timeout => "timeout: ",
                DriverErrorKind::Refused => "connection refused: ",
                DriverErrorKind::Malformed => "Malformed response: ",
                other => panic!("{other:?}"),
            };
            assert!(user.starts_with(symptom), "{user}");
        }
        // A camera that closed the connection is not one that refused it.
        let closed = user_text(KeyenceError::Closed { command: "TRG".into(), waiting_for: "the TRG echo".into() });
        assert!(!closed.contains("refused"), "{closed}");
    }

    #[test]
    fn a_closed_connection_says_another_client_may_hold_the_camera() {
        let e = KeyenceError::Closed { command: "TRG".into(), waiting_for: "the TRG echo".into() };
        assert_eq!(e.kind(), DriverErrorKind::Refused);
        let user = user_text(e);
        assert!(user.starts_with("camera closed the connection during TRG (the TRG echo never came) — "), "{user}");
        assert!(user.contains("another client probably holds the camera's only command socket"), "{user}");
        assert!(!user.contains("refused"), "{user}");
    }

    #[test]
    fn an_unreadable_reply_is_explained_by_the_command_it_answered() {
        let malformed = |command: &str, line: &str| KeyenceError::Malformed {
            command: command.into(),
            line: line.into(),
            reason: "x".into(),
        };
        let trg = user_text(malformed("TRG", "1,2,3,4"));
        assert!(trg.contains("Data Output"), "{trg}");
        for command in ["PR", "PL", "PW"] {
            let user = user_text(malformed(command, "PR,9"));
            assert!(user.contains("job switching (M284)"), "{user}");
            assert!(!user.contains("Data Output"), "{user}");
        }
        let fvr = user_text(KeyenceError::TooManyLines { command: "FVR".into(), limit: 8 });
        assert!(fvr.contains("Non-Procedural command port") && !fvr.contains("Data Output"), "{fvr}");
        let trg = user_text(KeyenceError::LineTooLong { command: "TRG".into(), limit: 512 });
        assert!(trg.contains("Data Output"), "{trg}");
    }

    #[test]
    fn the_typed_error_survives_the_core() {
        let e = rejected("PL", "03");
        let d = DriverError::from(e.clone());
        assert_eq!(d.kind(), DriverErrorKind::Rejected);
        assert_eq!(d.downcast_ref::<KeyenceError>(), Some(&e));
        assert_eq!(d.to_string(), e.to_string());
    }

    #[test]
    fn invalid_arguments_carry_their_own_fix() {
        let d = DriverError::from(KeyenceError::InvalidJob { job: 1000 });
        assert_eq!(d.kind(), DriverErrorKind::InvalidArgument);
        assert_eq!(d.to_string(), "camera job 1000 is out of range (0–999) — use a camera job number 0–999");
        assert_eq!(secs(Duration::from_millis(250)), "0.250 s");
    }
}
