//! [`cameras`]: the one list of camera drivers, with their settings.

use vision_core::DriverRegistry;
use vision_driver_sim::Sim;

/// Every camera driver, by the name `VisionDriver` (and `mach-vision run --camera`) gives:
/// `Keyence`, and, given a simulated world, `Sim`, the simulator's camera on it. Each driver
/// registers its own settings table; [`DriverRegistry::params`] gives the parameters that know
/// them all, what a profile load starts from.
///
/// A real machine has no simulated world: its bridges pass `None`.
#[must_use]
pub fn cameras(sim: Option<&Sim>) -> DriverRegistry {
    let mut registry = DriverRegistry::new();
    if let Some(sim) = sim {
        sim.register(&mut registry);
    }
    vision_driver_keyence::register(&mut registry);
    registry
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_camera_is_listed_with_its_settings() {
        assert_eq!(cameras(None).names(), ["Keyence"]);
        let sim = Sim::new(vision_driver_sim::World::default_world()).expect("the built-in world");
        let registry = cameras(Some(&sim));
        assert_eq!(registry.names(), ["Sim", "Keyence"]);
        assert_eq!(registry.settings("keyence").map(|t| t.table), Some("keyence"));
        assert!(registry.params().get("VisionIP").is_ok(), "the Keyence settings are known by name");
    }
}
