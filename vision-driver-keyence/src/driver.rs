//! [`KeyenceDriver`]: one persistent connection, the reconnect rule, and the
//! [`CameraDriver`] implementation.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use vision_core::{CameraDriver, Capabilities, DriverError, DriverRegistry, ImageRequest, Params, Reading};

use crate::config::KeyenceConfig;
use crate::error::KeyenceError;
use crate::protocol::{Exchange, JobCommand, Program, MAX_JOB};
use crate::transport::TcpLink;

/// The driver's registry name (`VisionDriver = Keyence`).
pub const DRIVER_NAME: &str = "Keyence";

/// A Keyence VS-series camera over the Non-Procedural TCP command port.
///
/// The connection is opened on the first call and reused; it is dropped after any failure
/// except a camera refusal (`ER,…`, a complete reply), and the next call reconnects.
///
/// **Never twice.** Before reuse, the idle connection is probed (stale bytes drained, a closed
/// or reset connection replaced) before anything is sent, so a camera that dropped the link
/// while idle costs a reconnect, not an error. Any failure after that is returned as it is and
/// the next call reconnects: the driver never sends a command again on its own, so it never
/// re-sends a trigger the camera may have executed.
#[derive(Debug)]
pub struct KeyenceDriver {
    config: KeyenceConfig,
    exchange: Option<Exchange<TcpLink>>,
    job_command: Option<JobCommand>,
}

impl KeyenceDriver {
    /// A driver for `config`. Does not connect.
    ///
    /// # Errors
    /// [`KeyenceError::Config`] when the configuration is unusable.
    pub fn new(config: KeyenceConfig) -> Result<KeyenceDriver, KeyenceError> {
        config.validate()?;
        Ok(KeyenceDriver { config, exchange: None, job_command: None })
    }

    /// A driver from its settings in `params` ([`KeyenceConfig::from_params`]). Does not connect.
    ///
    /// # Errors
    /// As [`KeyenceConfig::from_params`].
    pub fn from_params(params: &Params) -> Result<KeyenceDriver, KeyenceError> {
        KeyenceDriver::new(KeyenceConfig::from_params(params)?)
    }

    /// The configuration.
    #[must_use]
    pub fn config(&self) -> &KeyenceConfig {
        &self.config
    }

    /// True while a connection is open (it may still turn out dead at the next call).
    #[must_use]
    pub fn is_connected(&self) -> bool {
        self.exchange.is_some()
    }

    /// Closes the connection; the next call reconnects.
    pub fn disconnect(&mut self) {
        self.exchange = None;
    }

    /// The job command this camera accepted (`PL` or `PW`), once a job switch has succeeded.
    #[must_use]
    pub fn job_command(&self) -> Option<JobCommand> {
        self.job_command
    }

    /// `TRG`: one inspection's reading, in native pixels.
    ///
    /// # Errors
    /// Any [`KeyenceError`]; see the crate documentation for what each means.
    pub fn measure(&mut self) -> Result<Reading, KeyenceError> {
        self.call(Exchange::trigger)
    }

    /// `FVR`: the camera's firmware version text.
    ///
    /// # Errors
    /// As [`KeyenceDriver::measure`].
    pub fn firmware_version(&mut self) -> Result<String, KeyenceError> {
        self.call(Exchange::version)
    }

    /// `PR`: the job the camera runs.
    ///
    /// # Errors
    /// As [`KeyenceDriver::measure`].
    pub fn program(&mut self) -> Result<Program, KeyenceError> {
        self.call(Exchange::program)
    }

    /// Switches the camera to job `job` (0–999): `PL` on a VS, `PW` when the camera answers
    /// `ER,PL,01`. The memory device is [`KeyenceConfig::memory_device`], or the one `PR`
    /// reports.
    ///
    /// # Errors
    /// [`KeyenceError::InvalidJob`] before connecting, else as [`KeyenceDriver::measure`].
    pub fn load_job(&mut self, job: u32) -> Result<(), KeyenceError> {
        if job > MAX_JOB {
            return Err(KeyenceError::InvalidJob { job });
        }
        let configured = self.config.memory_device;
        let known = self.job_command;
        let used = self.call(|s| {
            let device = match configured {
                Some(d) => d,
                None => s.program()?.device,
            };
            s.select_job(known, device, job)
        })?;
        self.job_command = Some(used);
        Ok(())
    }

    /// Runs `op` on the connection under one deadline: probes an idle connection and replaces
    /// a dead one before anything is sent, and drops the connection after any failure but a
    /// camera refusal.
    fn call<T>(
        &mut self,
        op: impl FnOnce(&mut Exchange<TcpLink>) -> Result<T, KeyenceError>,
    ) -> Result<T, KeyenceError> {
        let deadline = Instant::now() + self.config.timeout;
        if self.exchange.as_mut().is_some_and(|s| !s.get_mut().idle_check()) {
            self.exchange = None;
        }
        let exchange = match self.exchange.as_mut() {
            Some(s) => s,
            None => {
                let link = TcpLink::connect(&self.config, deadline)?;
                let mut exchange = Exchange::new(link, self.config.limits, self.config.timeout);
                exchange.set_peer(self.config.address());
                self.exchange.insert(exchange)
            }
        };
        exchange.get_mut().set_deadline(deadline);
        let result = op(exchange);
        if matches!(&result, Err(e) if !matches!(e, KeyenceError::Rejected { .. })) {
            self.exchange = None;
        }
        result
    }
}

impl CameraDriver for KeyenceDriver {
    fn name(&self) -> &str {
        DRIVER_NAME
    }

    /// Job switching (`PL`/`PW`), and image grabbing: the camera FTP-pushes its images into
    /// `VisionImageWatchDir`, where [`CameraDriver::grab_image`] picks them up (SPEC §7).
    fn capabilities(&self) -> Capabilities {
        Capabilities { select_job: true, grab_image: true }
    }

    fn trigger(&mut self) -> Result<Reading, DriverError> {
        self.measure().map_err(DriverError::from)
    }

    fn select_job(&mut self, job: u32) -> Result<(), DriverError> {
        self.load_job(job).map_err(DriverError::from)
    }

    fn test_connection(&mut self) -> Result<String, DriverError> {
        self.firmware_version().map_err(DriverError::from)
    }

    /// Several marks: the Data Output reports one result of the job's tool, so say which.
    fn reading_warning(&self, reading: &Reading) -> Option<String> {
        several_marks(reading)
    }

    /// The newest image the camera pushed into `VisionImageWatchDir` since the trigger,
    /// waiting up to `VisionImageGrabTimeout` (the `images` module).
    fn grab_image(&mut self, request: &ImageRequest<'_>) -> Result<PathBuf, DriverError> {
        crate::images::grab(&self.config.images, request).map_err(DriverError::from)
    }

    fn timeout(&self) -> Duration {
        self.config.timeout
    }
}

/// The warning for a reading whose count says the camera found more than one mark: the Data
/// Output carries one result, the first in the tool's result order.
fn several_marks(reading: &Reading) -> Option<String> {
    let n = reading.count.filter(|n| *n > 1)?;
    Some(format!(
        "the camera found {n} marks and reported one, the first in its tool's result order, at x {:.3} y {:.3} px \
         — narrow the job's search region so it finds one mark",
        reading.x_px, reading.y_px
    ))
}

/// Registers the driver under [`DRIVER_NAME`] with its settings ([`crate::settings::SETTINGS`]);
/// the factory reads them ([`KeyenceConfig::from_params`]) and does not connect.
pub fn register(registry: &mut DriverRegistry) {
    registry.register_with_settings(DRIVER_NAME, &crate::settings::SETTINGS, |params: &Params| {
        let driver = KeyenceDriver::from_params(params).map_err(DriverError::from)?;
        Ok(Box::new(driver) as Box<dyn CameraDriver>)
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn several_marks_say_which_one_was_taken() {
        let mut r = Reading { count: Some(2), ..Reading::position(812.125, 903.5) };
        let driver = KeyenceDriver::new(KeyenceConfig::new("127.0.0.1", 8500)).expect("config");
        let warning = driver.reading_warning(&r).expect("two marks");
        assert!(warning.starts_with("the camera found 2 marks and reported one"), "{warning}");
        assert!(warning.contains("at x 812.125 y 903.500 px"), "{warning}");
        for count in [None, Some(0), Some(1)] {
            r.count = count;
            assert_eq!(driver.reading_warning(&r), None, "{count:?}");
        }
    }
}
