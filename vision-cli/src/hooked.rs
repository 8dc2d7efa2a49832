//! A camera with the host's hooks around each trigger — `send`'s wait for the machine to stop,
//! `run --panel`'s publishing of what the camera saw — and every other call passed through, so
//! the wrappers `DriverRegistry::wrap_drivers` builds need no forwarding code of their own.

use std::path::PathBuf;
use std::time::Duration;

use vision_core::{CameraDriver, Capabilities, DriverError, DriverErrorKind, ImageRequest, Reading};

/// Runs before a trigger; its refusal (in the host's words) is the capture's error.
pub(crate) type Before = Box<dyn FnMut() -> Result<(), String> + Send>;

/// Sees each trigger's result, with the driver that made it (its frame, its miss reason).
pub(crate) type After = Box<dyn FnMut(&dyn CameraDriver, &Result<Reading, DriverError>) + Send>;

/// `inner` with [`Before`] and [`After`] around each trigger.
pub(crate) struct Hooked {
    inner: Box<dyn CameraDriver>,
    before: Option<Before>,
    after: Option<After>,
}

impl Hooked {
    /// `inner`, refused a trigger when `before` says so.
    pub(crate) fn before(inner: Box<dyn CameraDriver>, before: Before) -> Hooked {
        Hooked { inner, before: Some(before), after: None }
    }

    /// `inner`, each trigger's result handed to `after`.
    pub(crate) fn after(inner: Box<dyn CameraDriver>, after: After) -> Hooked {
        Hooked { inner, before: None, after: Some(after) }
    }
}

impl CameraDriver for Hooked {
    fn name(&self) -> &str {
        self.inner.name()
    }

    fn capabilities(&self) -> Capabilities {
        self.inner.capabilities()
    }

    fn trigger(&mut self) -> Result<Reading, DriverError> {
        if let Some(before) = &mut self.before {
            before().map_err(|why| DriverError::new(DriverErrorKind::Other, why))?;
        }
        let result = self.inner.trigger();
        if let Some(after) = &mut self.after {
            after(self.inner.as_ref(), &result);
        }
        result
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

#[cfg(test)]
mod tests {
    use std::sync::{Arc, Mutex};

    use super::*;

    /// A camera that sees a mark at (1, 2) px and names itself `Fixed`.
    struct Fixed;

    impl CameraDriver for Fixed {
        fn name(&self) -> &str {
            "Fixed"
        }
        fn capabilities(&self) -> Capabilities {
            Capabilities { select_job: true, grab_image: false }
        }
        fn trigger(&mut self) -> Result<Reading, DriverError> {
            Ok(Reading::position(1.0, 2.0))
        }
        fn select_job(&mut self, job: u32) -> Result<(), DriverError> {
            if job == 7 {
                Ok(())
            } else {
                Err(DriverError::new(DriverErrorKind::Unsupported, "only job 7"))
            }
        }
        fn test_connection(&mut self) -> Result<String, DriverError> {
            Ok("fixed 1.0".into())
        }
        fn miss_reason(&self) -> Option<String> {
            Some("none".into())
        }
        fn mark_spec(&self) -> Option<String> {
            Some("dot".into())
        }
        fn timeout(&self) -> Duration {
            Duration::from_millis(1234)
        }
        fn reading_warning(&self, _reading: &Reading) -> Option<String> {
            Some("two marks".into())
        }
        fn grab_image(&mut self, request: &ImageRequest<'_>) -> Result<PathBuf, DriverError> {
            Ok(request.dir.join("kept.png"))
        }
        fn frame_size(&mut self) -> Option<(u32, u32)> {
            Some((640, 480))
        }
        fn last_frame(&self) -> Option<&dyn std::any::Any> {
            Some(&FRAME)
        }
    }

    /// What [`Fixed::last_frame`] hands over.
    static FRAME: u32 = 42;

    #[test]
    fn a_refusing_before_stops_the_trigger_and_says_why() {
        let mut camera = Hooked::before(Box::new(Fixed), Box::new(|| Err("the machine is moving".into())));
        let e = camera.trigger().expect_err("refused");
        assert_eq!(e.to_string(), "the machine is moving");
        let mut camera = Hooked::before(Box::new(Fixed), Box::new(|| Ok(())));
        assert!(camera.trigger().expect("passes").found());
    }

    #[test]
    fn after_sees_each_result_with_its_driver_and_the_rest_passes_through() {
        let seen = Arc::new(Mutex::new(Vec::new()));
        let log = Arc::clone(&seen);
        let after: After = Box::new(move |driver, result| {
            let x = result.as_ref().map(|r| r.x_px).unwrap_or(f64::NAN);
            log.lock().expect("log").push(format!("{} {x} {:?}", driver.name(), driver.mark_spec()));
        });
        let mut camera = Hooked::after(Box::new(Fixed), after);
        assert!(camera.trigger().is_ok());
        assert_eq!(*seen.lock().expect("log"), ["Fixed 1 Some(\"dot\")"]);
        assert_eq!(camera.name(), "Fixed");
        assert!(camera.capabilities().select_job);
        assert!(camera.select_job(7).is_ok() && camera.select_job(8).is_err());
        assert_eq!(camera.test_connection().expect("ok"), "fixed 1.0");
        assert_eq!(camera.miss_reason().as_deref(), Some("none"));
        assert_eq!(camera.mark_spec().as_deref(), Some("dot"));
        assert_eq!(camera.timeout(), Duration::from_millis(1234));
        assert_eq!(camera.last_frame().and_then(|f| f.downcast_ref::<u32>()), Some(&42));
        assert_eq!(camera.frame_size(), Some((640, 480)));
        let request =
            ImageRequest { dir: std::path::Path::new("/images"), since: std::time::SystemTime::UNIX_EPOCH, stamp: "x" };
        assert_eq!(camera.grab_image(&request).expect("kept"), PathBuf::from("/images/kept.png"));
        assert_eq!(camera.reading_warning(&Reading::position(0.0, 0.0)).as_deref(), Some("two marks"));
    }
}
