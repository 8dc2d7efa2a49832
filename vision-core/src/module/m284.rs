//! M284: switch the camera job.

use super::{Reply, VisionModule};
use crate::error::VisionError;

/// What M284 did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
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
    /// [`VisionError::InvalidParam`] for a job above [`MAX_JOB`] (before the camera is
    /// contacted), the driver's error, or a failed profile save; on error `VisionActiveJob`
    /// keeps its value.
    pub fn m284(&mut self, job: Option<u32>) -> Result<Reply<JobReport>, VisionError> {
        self.check_enabled()?;
        let mut next = self.params.clone();
        if let Some(j) = job.filter(|j| *j != 0) {
            next.set("VisionActiveJob", j)?;
        }
        let driver = self.driver_mut()?;
        if !driver.capabilities().select_job {
            return Err(VisionError::SelectJobUnsupported { driver: driver.name().to_string() });
        }
        let job = u32::try_from(next.active_job()).unwrap_or(0);
        if job == 0 {
            return Ok(Reply { gcode: Vec::new(), report: JobReport { job, switched: false } });
        }
        self.driver_mut()?.select_job(job)?;
        self.commit_params(next)?;
        Ok(Reply { gcode: Vec::new(), report: JobReport { job, switched: true } })
    }
}
