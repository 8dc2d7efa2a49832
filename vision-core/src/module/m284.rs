//! M284: switch the camera job.

use super::{Reply, VisionModule};
use crate::error::VisionError;

/// What M284 did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct JobReport {
    /// The job applied (0 = the camera was left on its loaded job).
    pub job: u32,
    /// True when the driver was asked to switch.
    pub switched: bool,
}

/// Highest camera job number.
pub const MAX_JOB: u32 = 999;

impl VisionModule {
    /// **M284**: switches the camera to `job` (`Pn`); `None` or `Some(0)` applies the stored
    /// `VisionActiveJob`. On success `VisionActiveJob` is updated and the profile saved.
    ///
    /// Decision: when the job to apply is 0 ("leave the camera on whatever job it has loaded"),
    /// the camera is not contacted and the call succeeds with `switched = false`. The
    /// camera-tool check does not apply (the manual lists it for M280–M283 only).
    ///
    /// # Errors
    /// [`VisionError::NotEnabled`], [`VisionError::NoDriver`],
    /// [`VisionError::SelectJobUnsupported`] for drivers without `select_job`,
    /// [`VisionError::BadWord`] for a job above 999, the driver's error, or a failed profile
    /// save; on error `VisionActiveJob` keeps its value.
    pub fn m284(&mut self, job: Option<u32>) -> Result<Reply<JobReport>, VisionError> {
        self.check_enabled()?;
        if let Some(j) = job.filter(|j| *j > MAX_JOB) {
            return Err(VisionError::BadWord {
                mcode: "M284",
                word: format!("P{j}"),
                reason: format!("the camera job must be 0..{MAX_JOB}"),
            });
        }
        let driver = self.driver_mut()?;
        if !driver.capabilities().select_job {
            return Err(VisionError::SelectJobUnsupported { driver: driver.name().to_string() });
        }
        let job = match job {
            Some(j) if j != 0 => j,
            _ => u32::try_from(self.params.active_job()).unwrap_or(0),
        };
        if job == 0 {
            return Ok(Reply { gcode: Vec::new(), report: JobReport { job, switched: false } });
        }
        self.driver_mut()?.select_job(job)?;
        let previous = self.params.active_job;
        self.params.active_job = i64::from(job);
        if let Err(e) = self.save_profile() {
            self.params.active_job = previous;
            return Err(e);
        }
        Ok(Reply { gcode: Vec::new(), report: JobReport { job, switched: true } })
    }
}
