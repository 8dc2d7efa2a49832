//! The camera on a streamed machine: it triggers only once the controller has stopped where the
//! program put it, since the interpreter runs ahead of the machine.

use std::path::PathBuf;
use std::time::Duration;

use vision_core::{CameraDriver, Capabilities, DriverError, DriverErrorKind, ImageRequest, Reading};

use super::link::Shared;

/// Any camera driver, triggered only after [`Shared::before_trigger`] says the machine is still.
pub(crate) struct Settled {
    inner: Box<dyn CameraDriver>,
    link: Shared,
}

impl Settled {
    /// `inner`, waiting for `link`'s machine before each trigger.
    pub(crate) fn new(inner: Box<dyn CameraDriver>, link: Shared) -> Settled {
        Settled { inner, link }
    }
}

impl CameraDriver for Settled {
    fn name(&self) -> &str {
        self.inner.name()
    }

    fn capabilities(&self) -> Capabilities {
        self.inner.capabilities()
    }

    /// The machine's refusal (it moved, it stopped, the link is lost) is the capture's error,
    /// in the link's words.
    fn trigger(&mut self) -> Result<Reading, DriverError> {
        self.link.before_trigger().map_err(|why| DriverError::new(DriverErrorKind::Other, why))?;
        self.inner.trigger()
    }

    fn select_job(&mut self, job: u32) -> Result<(), DriverError> {
        self.inner.select_job(job)
    }

    fn test_connection(&mut self) -> Result<String, DriverError> {
        self.inner.test_connection()
    }

    fn reading_warning(&self, reading: &Reading) -> Option<String> {
        self.inner.reading_warning(reading)
    }

    fn miss_reason(&self) -> Option<String> {
        self.inner.miss_reason()
    }

    fn grab_image(&mut self, request: &ImageRequest<'_>) -> Result<PathBuf, DriverError> {
        self.inner.grab_image(request)
    }

    fn mark_spec(&self) -> Option<String> {
        self.inner.mark_spec()
    }

    fn frame_size(&mut self) -> Option<(u32, u32)> {
        self.inner.frame_size()
    }

    fn timeout(&self) -> Duration {
        self.inner.timeout()
    }

    fn last_frame(&self) -> Option<&dyn std::any::Any> {
        self.inner.last_frame()
    }
}
