//! Camera drivers by name (`VisionDriver`), with their settings, so a host can pick one at run
//! time.
//!
//! The core knows no driver: each driver crate registers a factory closure under its name, and
//! its settings table when it has settings ([`DriverRegistry::register_with_settings`]).
//! [`DriverRegistry::params`] gives the parameters that know every registered driver's settings
//! (what a profile load starts from), and [`DriverRegistry::create`] builds the driver
//! `VisionDriver` names from the parameters.

use crate::driver::{CameraDriver, DriverError};
use crate::error::VisionError;
use crate::params::{Params, SettingsTable};

/// Builds a driver from the parameters.
pub type DriverFactory = std::sync::Arc<dyn Fn(&Params) -> Result<Box<dyn CameraDriver>, DriverError> + Send + Sync>;

/// One registered driver.
struct Entry {
    name: String,
    settings: Option<&'static SettingsTable>,
    factory: DriverFactory,
}

/// Driver name → settings and factory. Names match case-insensitively.
#[derive(Default)]
pub struct DriverRegistry {
    entries: Vec<Entry>,
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

    /// Registers `factory` under `name` for a driver without settings, replacing a driver of
    /// the same name.
    pub fn register<F>(&mut self, name: &str, factory: F)
    where
        F: Fn(&Params) -> Result<Box<dyn CameraDriver>, DriverError> + Send + Sync + 'static,
    {
        self.insert(name, None, std::sync::Arc::new(factory));
    }

    /// Registers `factory` under `name` for a driver whose settings are `settings`, replacing
    /// a driver of the same name. The factory always sees the settings' table in its
    /// parameters (at its defaults when the parameters had none).
    pub fn register_with_settings<F>(&mut self, name: &str, settings: &'static SettingsTable, factory: F)
    where
        F: Fn(&Params) -> Result<Box<dyn CameraDriver>, DriverError> + Send + Sync + 'static,
    {
        self.insert(name, Some(settings), std::sync::Arc::new(factory));
    }

    fn insert(&mut self, name: &str, settings: Option<&'static SettingsTable>, factory: DriverFactory) {
        self.entries.retain(|e| !e.name.eq_ignore_ascii_case(name));
        self.entries.push(Entry { name: name.to_string(), settings, factory });
    }

    /// The registered names, in registration order.
    #[must_use]
    pub fn names(&self) -> Vec<&str> {
        self.entries.iter().map(|e| e.name.as_str()).collect()
    }

    /// True when `name` is registered.
    #[must_use]
    pub fn contains(&self, name: &str) -> bool {
        self.entry(name).is_some()
    }

    /// The registered name `name` matches (case-insensitive), as it was registered.
    #[must_use]
    pub fn name(&self, name: &str) -> Option<&str> {
        self.entry(name).map(|e| e.name.as_str())
    }

    /// The settings table of driver `name`, when it has settings.
    #[must_use]
    pub fn settings(&self, name: &str) -> Option<&'static SettingsTable> {
        self.entry(name).and_then(|e| e.settings)
    }

    /// The default parameters with every registered driver's settings at their defaults: what
    /// a profile load starts from, so each driver's settings are known by name.
    #[must_use]
    pub fn params(&self) -> Params {
        self.entries.iter().filter_map(|e| e.settings).fold(Params::default(), Params::with_driver_settings)
    }

    /// Builds driver `name` from `params`.
    ///
    /// # Errors
    /// [`VisionError::UnknownDriver`], or the factory's error as [`VisionError::Driver`].
    pub fn create(&self, name: &str, params: &Params) -> Result<Box<dyn CameraDriver>, VisionError> {
        let entry = self
            .entry(name)
            .ok_or_else(|| VisionError::UnknownDriver { name: name.to_string(), known: self.names().join(", ") })?;
        match entry.settings {
            Some(table) if params.driver_settings(table.table).is_none() => {
                Ok((entry.factory)(&params.clone().with_driver_settings(table))?)
            }
            _ => Ok((entry.factory)(params)?),
        }
    }

    /// Passes every driver the registry builds from now on through `wrap`: a host that must act
    /// around a camera's calls (wait for its machine to stop before a trigger) without knowing
    /// which camera it is.
    pub fn wrap_drivers<W>(&mut self, wrap: W)
    where
        W: Fn(Box<dyn CameraDriver>) -> Box<dyn CameraDriver> + Send + Sync + 'static,
    {
        let wrap = std::sync::Arc::new(wrap);
        for entry in &mut self.entries {
            let (wrap, inner) = (std::sync::Arc::clone(&wrap), std::sync::Arc::clone(&entry.factory));
            entry.factory = std::sync::Arc::new(move |params| inner(params).map(|driver| wrap(driver)));
        }
    }

    fn entry(&self, name: &str) -> Option<&Entry> {
        self.entries.iter().find(|e| e.name.eq_ignore_ascii_case(name))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::driver::{Capabilities, DriverErrorKind, Reading};

    /// A camera that always sees a mark at (1, 2) px.
    struct Fixed;

    impl CameraDriver for Fixed {
        fn name(&self) -> &str {
            "Fixed"
        }
        fn capabilities(&self) -> Capabilities {
            Capabilities::default()
        }
        fn trigger(&mut self) -> Result<Reading, DriverError> {
            Ok(Reading::position(1.0, 2.0))
        }
        fn select_job(&mut self, _job: u32) -> Result<(), DriverError> {
            Err(DriverError::new(DriverErrorKind::Unsupported, "no jobs"))
        }
        fn test_connection(&mut self) -> Result<String, DriverError> {
            Ok("fixed".into())
        }
    }

    /// Refuses every trigger, as a host whose machine never stopped would.
    struct Refusing(Box<dyn CameraDriver>);

    impl CameraDriver for Refusing {
        fn name(&self) -> &str {
            self.0.name()
        }
        fn capabilities(&self) -> Capabilities {
            self.0.capabilities()
        }
        fn trigger(&mut self) -> Result<Reading, DriverError> {
            Err(DriverError::new(DriverErrorKind::Other, "the machine is still moving"))
        }
        fn select_job(&mut self, job: u32) -> Result<(), DriverError> {
            self.0.select_job(job)
        }
        fn test_connection(&mut self) -> Result<String, DriverError> {
            self.0.test_connection()
        }
    }

    #[test]
    fn every_driver_built_after_wrapping_goes_through_the_wrapper() {
        let mut registry = DriverRegistry::new();
        registry.register("Fixed", |_| Ok(Box::new(Fixed)));
        registry.register("Other", |_| Ok(Box::new(Fixed)));
        let mut plain = registry.create("fixed", &Params::default()).expect("built");
        assert!(plain.trigger().is_ok());
        registry.wrap_drivers(|d| Box::new(Refusing(d)));
        for name in ["Fixed", "other"] {
            let mut wrapped = registry.create(name, &Params::default()).expect("built");
            assert_eq!(wrapped.name(), "Fixed");
            assert_eq!(wrapped.test_connection().expect("passed through"), "fixed");
            let e = wrapped.trigger().expect_err("the wrapper refuses");
            assert!(e.to_string().contains("still moving"), "{e}");
        }
    }
}
