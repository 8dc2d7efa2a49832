//! Where the emulated camera's results come from.

use vision_core::{CameraDriver, DriverErrorKind, Reading};

use crate::protocol::parse_error_reply;

/// What the camera answers to one `TRG`.
#[derive(Debug, Clone, PartialEq)]
pub enum Shot {
    /// The `TRG` echo, then this reading as a Data Output line in the emulator's format.
    Reading(Reading),
    /// The `TRG` echo, then this text verbatim as the data line (the delimiter is added).
    Line(String),
    /// `ER,TRG,<code>` instead of the echo (code 1–99, sent as two digits).
    Reject(u8),
    /// The `TRG` echo and nothing else (a job without a Data Output tool).
    Silent,
}

/// A supplier of trigger results for the emulator: a fixed list ([`ListSource`]), a closure
/// ([`FnSource`]) or any camera driver ([`DriverSource`], e.g. the simulated camera).
pub trait ResultSource: Send {
    /// The answer to the next `TRG`.
    fn trigger(&mut self) -> Shot;

    /// A job switch (`PL`/`PW`) to job `job`, already range-checked. `Err(code)` makes the
    /// camera answer `ER,<cmd>,<code>`. The default accepts every job.
    ///
    /// # Errors
    /// The `ER` code to answer with.
    fn select_job(&mut self, job: u32) -> Result<(), u8> {
        let _ = job;
        Ok(())
    }
}

/// A fixed list of answers, cycled or used once.
///
/// An exhausting list that has run out answers `ER,TRG,05` ("not acceptable now") to every
/// further `TRG`, so a test that triggers more often than it planned fails loudly.
#[derive(Debug, Clone, PartialEq)]
pub struct ListSource {
    shots: Vec<Shot>,
    next: usize,
    cycle: bool,
}

impl ListSource {
    /// Answers `shots` in order, then starts again. An empty list answers `ER,TRG,05`.
    #[must_use]
    pub fn cycling(shots: Vec<Shot>) -> ListSource {
        ListSource { shots, next: 0, cycle: true }
    }

    /// Answers `shots` in order once, then `ER,TRG,05`.
    #[must_use]
    pub fn exhausting(shots: Vec<Shot>) -> ListSource {
        ListSource { shots, next: 0, cycle: false }
    }

    /// Cycles through `readings`.
    #[must_use]
    pub fn readings(readings: impl IntoIterator<Item = Reading>) -> ListSource {
        ListSource::cycling(readings.into_iter().map(Shot::Reading).collect())
    }
}

impl ResultSource for ListSource {
    fn trigger(&mut self) -> Shot {
        if self.cycle && !self.shots.is_empty() {
            self.next %= self.shots.len();
        }
        match self.shots.get(self.next) {
            Some(s) => {
                self.next += 1;
                s.clone()
            }
            None => Shot::Reject(5),
        }
    }
}

/// Answers from a closure, called once per `TRG`.
pub struct FnSource<F>(pub F);

impl<F> std::fmt::Debug for FnSource<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("FnSource(..)")
    }
}

impl<F: FnMut() -> Shot + Send> ResultSource for FnSource<F> {
    fn trigger(&mut self) -> Shot {
        (self.0)()
    }
}

/// Answers from a camera driver: `TRG` → [`CameraDriver::trigger`], `PL`/`PW` →
/// [`CameraDriver::select_job`]. Plug in the simulated camera to emulate a camera that sees
/// a simulated part.
///
/// A failed trigger answers with the code of the first `ER,TRG,<nn>` word in the driver's
/// message when there is one (a word being text between spaces, brackets and punctuation
/// stripped, that reads as a whole `ER` reply), else `ER,TRG,07` (the measurement did not
/// complete). A failed job switch answers `03`
/// for an invalid argument, `01` when the driver cannot switch jobs, else `05`.
pub struct DriverSource(pub Box<dyn CameraDriver>);

impl std::fmt::Debug for DriverSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "DriverSource({})", self.0.name())
    }
}

impl ResultSource for DriverSource {
    fn trigger(&mut self) -> Shot {
        match self.0.trigger() {
            Ok(r) => Shot::Reading(r),
            Err(e) => Shot::Reject(trigger_refusal(&e.message).unwrap_or(7)),
        }
    }

    fn select_job(&mut self, job: u32) -> Result<(), u8> {
        self.0.select_job(job).map_err(|e| match e.kind {
            DriverErrorKind::InvalidArgument => 3,
            DriverErrorKind::Unsupported => 1,
            _ => 5,
        })
    }
}

/// The code of the first whole `ER,TRG,<nn>` reply quoted in `message`.
fn trigger_refusal(message: &str) -> Option<u8> {
    message.split_whitespace().find_map(|word| {
        match parse_error_reply(word.trim_matches(|c: char| !c.is_ascii_alphanumeric())) {
            Some(Ok(r)) if r.command == "TRG" => r.code.parse().ok(),
            _ => None,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use vision_core::{Capabilities, DriverError};

    #[test]
    fn lists_cycle_or_run_out() {
        let a = Shot::Reading(Reading::position(1.0, 2.0));
        let b = Shot::Line("x".into());
        let mut c = ListSource::cycling(vec![a.clone(), b.clone()]);
        assert_eq!([c.trigger(), c.trigger(), c.trigger()], [a.clone(), b.clone(), a.clone()]);
        let mut e = ListSource::exhausting(vec![a.clone()]);
        assert_eq!([e.trigger(), e.trigger()], [a, Shot::Reject(5)]);
        assert_eq!(ListSource::cycling(Vec::new()).trigger(), Shot::Reject(5));
        let mut f = FnSource(|| Shot::Silent);
        assert_eq!(f.trigger(), Shot::Silent);
        assert_eq!(f.select_job(3), Ok(()));
    }

    struct Failing(DriverError);
    impl CameraDriver for Failing {
        fn name(&self) -> &str {
            "Failing"
        }
        fn capabilities(&self) -> Capabilities {
            Capabilities::default()
        }
        fn trigger(&mut self) -> Result<Reading, DriverError> {
            Err(self.0.clone())
        }
        fn select_job(&mut self, _job: u32) -> Result<(), DriverError> {
            Err(self.0.clone())
        }
        fn test_connection(&mut self) -> Result<String, DriverError> {
            Ok("x".into())
        }
    }

    #[test]
    fn driver_failures_become_er_codes() {
        let mut s =
            DriverSource(Box::new(Failing(DriverError::new(DriverErrorKind::Rejected, "camera replied ER,TRG,06"))));
        assert_eq!(s.trigger(), Shot::Reject(6));
        assert_eq!(s.select_job(1), Err(5));
        let mut s = DriverSource(Box::new(Failing(DriverError::new(DriverErrorKind::Unsupported, "no"))));
        assert_eq!(s.trigger(), Shot::Reject(7));
        assert_eq!(s.select_job(1), Err(1));
        let mut s = DriverSource(Box::new(Failing(DriverError::new(DriverErrorKind::InvalidArgument, "ER,"))));
        assert_eq!(s.trigger(), Shot::Reject(7));
        assert_eq!(s.select_job(1), Err(3));
        assert_eq!(format!("{s:?}"), "DriverSource(Failing)");
    }

    #[test]
    fn er_replies_are_read_whole_whatever_the_command_length() {
        for (message, code) in [
            ("camera replied ER,TRG,06 to TRG — not executable", Some(6)),
            ("no mark (camera replied ER,TRG,05)", Some(5)),
            ("ER,TRG,07: camera-side timeout", Some(7)),
            // A two-letter command first: the TRG refusal after it is still found.
            ("camera replied ER,PL,01 then ER,TRG,03 to TRG", Some(3)),
            // Refusals of other commands, whatever their length, are not TRG's.
            ("camera replied ER,PL,03 to PL", None),
            ("camera replied ER,TRGX,06", None),
            // Not a whole ER reply.
            ("ER,TRG,06x", None),
            ("ER,TRG,6", None),
            ("ER,TRG", None),
            ("ER,", None),
            ("", None),
        ] {
            assert_eq!(trigger_refusal(message), code, "{message}");
        }
        let refusal = DriverError::new(DriverErrorKind::Rejected, "camera replied ER,PL,01 then ER,TRG,04");
        assert_eq!(DriverSource(Box::new(Failing(refusal))).trigger(), Shot::Reject(4));
    }
}
