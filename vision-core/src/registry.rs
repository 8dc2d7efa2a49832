//! Camera drivers by name (`VisionDriver`), so the CLI can pick one at run time.
//!
//! The core knows no driver: each driver crate (or the CLI) registers a factory closure under
//! its name, and [`DriverRegistry::create`] builds the one `VisionDriver` names, passing it the
//! parameters (IP, port, timeout, …).

use crate::driver::{CameraDriver, DriverError};
use crate::error::VisionError;
use crate::params::Params;

/// Builds a driver from the parameters.
pub type DriverFactory = Box<dyn Fn(&Params) -> Result<Box<dyn CameraDriver>, DriverError> + Send + Sync>;

/// Driver name → factory. Names match case-insensitively.
#[derive(Default)]
pub struct DriverRegistry {
    entries: Vec<(String, DriverFactory)>,
}

impl std::fmt::Debug for DriverRegistry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DriverRegistry").field("names", &self.names()).finish()
    }
}

impl DriverRegistry {
    /// An empty registry.
    #[must_use]
    pub fn new() -> DriverRegistry {
        DriverRegistry::default()
    }

    /// Registers `factory` under `name`, replacing a driver of the same name.
    pub fn register<F>(&mut self, name: &str, factory: F)
    where
        F: Fn(&Params) -> Result<Box<dyn CameraDriver>, DriverError> + Send + Sync + 'static,
    {
        self.entries.retain(|(n, _)| !n.eq_ignore_ascii_case(name));
        self.entries.push((name.to_string(), Box::new(factory)));
    }

    /// The registered names, in registration order.
    #[must_use]
    pub fn names(&self) -> Vec<&str> {
        self.entries.iter().map(|(n, _)| n.as_str()).collect()
    }

    /// True when `name` is registered.
    #[must_use]
    pub fn contains(&self, name: &str) -> bool {
        self.entries.iter().any(|(n, _)| n.eq_ignore_ascii_case(name))
    }

    /// Builds driver `name` from `params`.
    ///
    /// # Errors
    /// [`VisionError::UnknownDriver`], or the factory's error as [`VisionError::Driver`].
    pub fn create(&self, name: &str, params: &Params) -> Result<Box<dyn CameraDriver>, VisionError> {
        let (_, factory) = self
            .entries
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name))
            .ok_or_else(|| VisionError::UnknownDriver { name: name.to_string(), known: self.names().join(", ") })?;
        Ok(factory(params)?)
    }
}
