//! Where the emulated camera's results come from.

use vision_core::{CameraDriver, DriverError, DriverErrorKind, Reading};

use crate::error::KeyenceError;

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
/// A failure answers the `ER` code a camera would: a Keyence driver's refusal
/// ([`KeyenceError::Rejected`]) its own code; else, for a trigger, `07` (the measurement did not
/// complete); for a job switch, `03` when the driver refused the job (it does not exist, or is
/// out of range), `01` when the driver cannot switch jobs, else `05` (not acceptable now).
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
            Err(e) => Shot::Reject(camera_code(&e).unwrap_or(7)),
        }
    }

    fn select_job(&mut self, job: u32) -> Result<(), u8> {
        self.0.select_job(job).map_err(|e| {
            camera_code(&e).unwrap_or(match e.kind() {
                DriverErrorKind::Rejected | DriverErrorKind::InvalidArgument => 3,
                DriverErrorKind::Unsupported => 1,
                _ => 5,
            })
        })
    }
}

/// The `ER` code of a Keyence camera's refusal behind `e`.
fn camera_code(e: &DriverError) -> Option<u8> {
    e.downcast_ref::<KeyenceError>()?.code()?.parse().ok()
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
        let refusal = |code: &str| KeyenceError::Rejected {
            command: "TRG".into(),
            code: code.into(),
            reply: format!("ER,TRG,{code}"),
            previous: vec!["ER,PL,01".into()],
        };
        // A Keyence refusal keeps its code, for a trigger and a job switch alike.
        let mut s = DriverSource(Box::new(Failing(refusal("06").into())));
        assert_eq!(s.trigger(), Shot::Reject(6));
        assert_eq!(s.select_job(1), Err(6));
        let mut s = DriverSource(Box::new(Failing(refusal("04").into())));
        assert_eq!(s.trigger(), Shot::Reject(4));
        // Another driver's errors, by kind; a text that quotes an ER reply is not a code.
        let mut s = DriverSource(Box::new(Failing(DriverError::new(DriverErrorKind::Unsupported, "ER,TRG,05"))));
        assert_eq!(s.trigger(), Shot::Reject(7));
        assert_eq!(s.select_job(1), Err(1));
        let mut s = DriverSource(Box::new(Failing(DriverError::new(DriverErrorKind::InvalidArgument, "ER,"))));
        assert_eq!(s.trigger(), Shot::Reject(7));
        assert_eq!(s.select_job(1), Err(3));
        // A camera without the job: ER,PL,03 (the job does not exist), not 05.
        let mut s = DriverSource(Box::new(Failing(DriverError::new(DriverErrorKind::Rejected, "no job 7"))));
        assert_eq!(s.select_job(7), Err(3));
        let mut s = DriverSource(Box::new(Failing(DriverError::new(DriverErrorKind::Timeout, "busy"))));
        assert_eq!(s.select_job(7), Err(5));
        assert_eq!(format!("{s:?}"), "DriverSource(Failing)");
    }
}
