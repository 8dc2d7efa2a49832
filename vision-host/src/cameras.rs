//! [`cameras`]: the one list of camera drivers, with their settings.

use vision_core::{CameraDriver, DriverError, DriverRegistry, Params};
use vision_driver_camera::{CameraConfig, CameraError, Frame, FrameDriver, FrameSource, Polarity};
use vision_driver_sim::Sim;

/// The image-mode simulated camera's registry name: the simulator's rendered frames searched
/// by the `Camera` driver.
pub const SIM_IMAGE: &str = "SimImage";

/// Every camera driver, by the name `VisionDriver` (and `mach-vision run --camera`) gives:
/// `Keyence`; `Camera`, any USB, network or file camera whose frames mach-vision searches
/// itself; and, given a simulated world, `Sim`, the simulator's camera reporting the mark's
/// pixel (reading mode), and `SimImage`, the frames that camera would see, rendered and
/// searched by the `Camera` driver (image mode). Each driver registers its own settings table;
/// [`DriverRegistry::params`] gives the parameters that know them all, what a profile load
/// starts from.
///
/// A real machine has no simulated world: its bridges pass `None`.
#[must_use]
pub fn cameras(sim: Option<&Sim>) -> DriverRegistry {
    let mut registry = DriverRegistry::new();
    if let Some(sim) = sim {
        sim.register(&mut registry);
        register_sim_image(sim, &mut registry);
    }
    vision_driver_keyence::register(&mut registry);
    vision_driver_camera::register(&mut registry);
    registry
}

/// The simulator's rendered frames as a frame source.
#[derive(Debug)]
pub struct SimFrames(pub Sim);

impl FrameSource for SimFrames {
    fn frame(&mut self) -> Result<Frame, CameraError> {
        let frame = self
            .0
            .render_frame()
            .map_err(|e| CameraError::Io { from: "the simulator".into(), reason: e.to_string() })?;
        let (w, h) = (frame.image.width(), frame.image.height());
        let bad = || CameraError::Decode { from: "the simulator".into(), reason: format!("a {w}×{h} frame") };
        Frame::new(u32::try_from(w).map_err(|_| bad())?, u32::try_from(h).map_err(|_| bad())?, frame.gray8().to_vec())
            .ok_or_else(bad)
    }

    fn describe(&self) -> String {
        "the simulated camera's rendered frames".into()
    }

    /// A rendered frame shows the head where it is now: never stale.
    fn is_live(&self) -> bool {
        false
    }

    /// The world's camera jobs, as the reading-mode camera knows them.
    fn has_jobs(&self) -> bool {
        true
    }

    /// Switches the simulated camera's job as the reading-mode camera does (the world's jobs;
    /// any job 1–999 when it lists none). Image mode renders and searches the same for every
    /// job: a job's reading noise is a reading-mode setting, and the finder has one method.
    fn select_job(&mut self, job: u32) -> Result<(), CameraError> {
        vision_core::CameraDriver::select_job(&mut self.0.camera(), job)
            .map_err(|e| CameraError::Job { job, reason: e.to_string() })
    }
}

/// The mark settings the simulated operator sets for `sim`'s world: the shape and contrast
/// printed; unless the profile gives one, the diameter the marks image at; and a search radius
/// no larger than the one that leaves every neighbouring mark outside while the camera is
/// centred on a mark ([`Sim::clear_radius_px`]), as an operator sets a camera's search window.
///
/// # Errors
/// As [`CameraConfig::from_params`].
pub fn sim_image_config(sim: &Sim, params: &Params) -> Result<CameraConfig, CameraError> {
    let mut config = CameraConfig::from_params(params)?;
    let look = sim.image_look();
    config.mark.kind = look.mark;
    config.mark.polarity = if look.ink < look.ground { Polarity::Dark } else { Polarity::Light };
    let explicit = params.get("VisionCameraMarkDiameterPx").ok().and_then(|v| v.as_f64()).is_some_and(|d| d > 0.0);
    if !explicit {
        config.mark.diameter_px = sim.mark_diameter_px().or(config.mark.diameter_px);
    }
    if let Some(clear) = sim.clear_radius_px() {
        let res = sim.optics().resolution();
        let pct = clear / (res.x.min(res.y) / 2.0) * 100.0;
        config.mark.search_radius_pct = config.mark.search_radius_pct.min(pct.clamp(5.0, 100.0));
    }
    config.flush_frames = 0;
    Ok(config)
}

fn register_sim_image(sim: &Sim, registry: &mut DriverRegistry) {
    let sim = sim.clone();
    registry.register_with_settings(SIM_IMAGE, &vision_driver_camera::settings::SETTINGS, move |params: &Params| {
        let config = sim_image_config(&sim, params).map_err(DriverError::from)?;
        let driver = FrameDriver::new(config, SimFrames(sim.clone())).map_err(DriverError::from)?;
        Ok(Box::new(driver) as Box<dyn CameraDriver>)
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_camera_is_listed_with_its_settings() {
        assert_eq!(cameras(None).names(), ["Keyence", "Camera"]);
        let sim = Sim::new(vision_driver_sim::World::default_world()).expect("the built-in world");
        let registry = cameras(Some(&sim));
        assert_eq!(registry.names(), ["Sim", "SimImage", "Keyence", "Camera"]);
        assert_eq!(registry.settings("keyence").map(|t| t.table), Some("keyence"));
        assert_eq!(registry.settings("simimage").map(|t| t.table), Some("camera"));
        let params = registry.params();
        assert!(params.get("VisionIP").is_ok(), "the Keyence settings are known by name");
        assert!(params.get("VisionCameraSource").is_ok(), "the camera settings are known by name");
    }

    #[test]
    fn the_image_mode_camera_finds_the_mark_the_reading_mode_camera_reports() {
        let mut world = vision_driver_sim::World::default_world();
        world.camera.noise_px = 0.0;
        let sim = Sim::new(world).expect("world");
        let registry = cameras(Some(&sim));
        let params = registry.params();
        let mut image = registry.create(SIM_IMAGE, &params).expect("driver");
        let mut reading = registry.create("Sim", &params).expect("driver");
        let (a, b) = (image.trigger().expect("image"), reading.trigger().expect("reading"));
        assert!(a.found() && b.found(), "{a:?} {b:?}");
        assert!((a.x_px - b.x_px).hypot(a.y_px - b.y_px) < 0.05, "{a:?} vs {b:?}");
        assert!((a.width_px - b.width_px).abs() < 1.0, "{a:?} vs {b:?}");
    }
}
