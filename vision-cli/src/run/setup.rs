//! A run's set-up: the world, the camera (simulated, emulated on loopback, or real), the
//! profile and the Vision session.

use vision_core::{DriverRegistry, Params, ProfileStore, VisionModule};
use vision_driver_camera::server::{Encoding, SnapshotServer};
use vision_driver_camera::FrameSource;
use vision_driver_sim::{ControllerName, Sim, SimMachine};
use vision_host::{fixed_clock, system_clock};
use vision_host::{ProgramHandler, Session, SimFrames};

use super::panel::RunPanel;
use super::{kept, CameraWrap, RunArgs, Runner, CAMERA, KEYENCE};
use crate::terminal::Progress;
use crate::{world, Failure};

fn set(params: &mut Params, name: &str, value: impl Into<vision_core::ParamValue>) -> Result<(), Failure> {
    params.set(name, value).map_err(|e| Failure::Input(e.to_string()))
}

impl Runner {
    /// Sets up the world, the camera, the profile and the session `args` ask for.
    pub(crate) fn new(args: &RunArgs, progress: Progress, wrap: Option<CameraWrap>) -> Result<Runner, Failure> {
        // The panel's address and token are checked first: a refusal costs no camera.
        let panel = RunPanel::start(args)?;
        let wrap = match (&panel, wrap) {
            (None, wrap) => wrap,
            (Some(p), None) => Some(p.wrap()),
            (Some(p), Some(host)) => {
                let published = p.wrap();
                Some(Box::new(move |driver| published(host(driver))) as CameraWrap)
            }
        };
        let mut world = world::load(args.world.as_deref())?;
        if let Some(dialect) = args.dialect {
            world.machine.controller = ControllerName(dialect.0);
        }
        let sim = Sim::new(world).map_err(|e| Failure::Input(e.to_string()))?;
        let camera_tool = i64::from(sim.world().machine.camera_tool);
        let mut registry = vision_host::cameras(Some(&sim));
        if let Some(wrap) = wrap {
            registry.wrap_drivers(wrap);
        }
        let driver = camera_name(&registry, &args.camera)?;

        let mut params = match &args.profile {
            Some(path) if path.exists() => ProfileStore::new(path)
                .with_defaults(registry.params())
                .load()
                .map_err(|e| Failure::Input(e.to_string()))?,
            Some(_) => {
                let mut p = registry.params();
                set(&mut p, "VisionEnabled", true)?;
                set(&mut p, "VisionCameraToolNumber", camera_tool)?;
                p
            }
            None => sim.calibrated_params(&registry.params()).map_err(|e| Failure::Input(e.to_string()))?,
        };

        let profile_camera = match &args.profile {
            Some(path) if path.exists() => Some(ProfileCamera::of(&params)?),
            _ => None,
        };

        // The camera choices below are for this session: the profile keeps the file's (or,
        // for a new profile, the defaults), as do the settings of the CLI's own loopback
        // snapshot server.
        let mut session_only = vec!["VisionDriver", "VisionIP", "VisionPort"];
        if driver == CAMERA && args.source.is_none() {
            session_only.extend(LOOPBACK_CAMERA_SETTINGS);
        }
        let file_values = session_only
            .into_iter()
            .map(|name| params.get(name).map(|v| (name, v)).map_err(|e| Failure::Input(e.to_string())))
            .collect::<Result<Vec<_>, _>>()?;
        let mut snapshots = None;
        let (camera, emulator) = match (driver.as_str(), &args.ip) {
            ("Sim", _) => {
                set(&mut params, "VisionDriver", "Sim")?;
                ("simulated camera".to_string(), None)
            }
            (CAMERA, _) => {
                set(&mut params, "VisionDriver", CAMERA)?;
                match &args.source {
                    Some(source) => {
                        set(&mut params, "VisionCameraSource", source.as_str())?;
                        (format!("Camera driver -> {}", vision_core::text::printable_line(source, 120)), None)
                    }
                    None => {
                        let server = serve_frames(&sim, &mut params)?;
                        let text = format!(
                            "Camera driver -> HTTP snapshots at {} (the simulated camera's rendered frames)",
                            server.url("/snapshot")
                        );
                        snapshots = Some(server);
                        (text, None)
                    }
                }
            }
            (KEYENCE, Some(ip)) => {
                set(&mut params, "VisionDriver", "Keyence")?;
                set(&mut params, "VisionIP", ip.as_str())?;
                set(&mut params, "VisionPort", i64::from(args.port))?;
                (format!("Keyence VS at {ip}:{}", args.port), None)
            }
            (KEYENCE, None) => {
                let emulator = world::serve_camera(&sim, "127.0.0.1:0")
                    .map_err(|e| Failure::Input(format!("cannot start the loopback camera emulator: {e}")))?;
                set(&mut params, "VisionDriver", "Keyence")?;
                set(&mut params, "VisionIP", "127.0.0.1")?;
                set(&mut params, "VisionPort", i64::from(emulator.addr().port()))?;
                (
                    format!("Keyence driver -> emulated VS camera at {} (the simulated camera)", emulator.addr()),
                    Some(emulator),
                )
            }
            (other, _) => {
                set(&mut params, "VisionDriver", other)?;
                (format!("{other} camera"), None)
            }
        };

        // Another driver, or the profile's driver pointed at the CLI's own loopback camera.
        let other_camera = |f: &ProfileCamera| {
            !f.driver.eq_ignore_ascii_case(&driver)
                || (driver == KEYENCE && args.ip.is_none())
                || (driver == CAMERA && args.source.is_none())
        };
        if let Some(file) = profile_camera.filter(other_camera) {
            crate::terminal::show(&file.note(&camera, &args.camera));
        }

        let mut module = VisionModule::from_registry(params, &registry).map_err(|e| Failure::Input(e.to_string()))?;
        if progress.on() {
            module.set_progress_sink(Some(Box::new(|p| crate::terminal::show(&format!("              {p}")))));
        }
        if let Some(path) = &args.profile {
            let mut store = ProfileStore::new(path).with_defaults(registry.params());
            for (name, value) in file_values {
                store = store.keep(name, value);
            }
            // Found before any motion, not when M283/M284 saves after it.
            store.check_writable().map_err(|e| Failure::Input(e.to_string()))?;
            module = module.with_profile(store);
        }
        let mut machine = SimMachine::new(&sim).map_err(|e| Failure::Input(e.to_string()))?;
        if let Some(path) = &args.profile {
            kept::restore(path, &mut machine)?;
        }
        let clock = args.clock.map_or_else(system_clock, |s| fixed_clock(vision_core::Timestamp::from_unix(s, 0)));
        let handler = ProgramHandler::new(Session::new(module), sim.world().machine.controller(), clock);
        if let Some(p) = &panel {
            p.set_source(&camera);
        }
        Ok(Runner { sim, machine, handler, camera, _emulator: emulator, _snapshots: snapshots, panel })
    }
}

/// The camera a profile file names, to tell the user when `--camera` picked another.
struct ProfileCamera {
    /// `VisionDriver`.
    driver: String,
    /// The options that pick it: `--camera keyence --ip … --port …`, `--camera camera --source …`.
    options: String,
}

impl ProfileCamera {
    fn of(params: &Params) -> Result<ProfileCamera, Failure> {
        let text = |name: &str| -> Result<String, Failure> {
            let value = params.get(name).map_err(|e| Failure::Input(e.to_string()))?;
            Ok(match value {
                vision_core::ParamValue::Text(t) => t,
                other => other.to_string(),
            })
        };
        let driver = text("VisionDriver")?;
        let quoted = |v: &str| {
            let v = vision_core::text::printable_line(v, 200);
            if v.is_empty() || v.contains(char::is_whitespace) {
                format!("'{v}'")
            } else {
                v
            }
        };
        let options = if driver.eq_ignore_ascii_case(KEYENCE) {
            format!("--camera keyence --ip {} --port {}", quoted(&text("VisionIP")?), text("VisionPort")?)
        } else if driver.eq_ignore_ascii_case(CAMERA) {
            format!("--camera camera --source {}", quoted(&text("VisionCameraSource")?))
        } else {
            format!("--camera {}", quoted(&driver.to_ascii_lowercase()))
        };
        Ok(ProfileCamera { driver, options })
    }

    /// The note: which camera the run uses, and how to use the profile's.
    fn note(&self, camera: &str, option: &str) -> String {
        format!(
            "mach-vision: the profile names camera driver {}, but this run uses the {camera} (--camera {}); to use \
             the profile's camera, give {}",
            vision_core::text::printable_line(&self.driver, 64),
            vision_core::text::printable_line(option, 64),
            self.options
        )
    }
}

/// The camera driver's settings [`serve_frames`] sets for the loopback snapshot server: its
/// URL (which dies with the run), timeout and flush count, and the mark settings the simulated
/// operator would set. They are the session's: a profile saved by the run keeps the file's
/// values (the defaults for a new profile).
const LOOPBACK_CAMERA_SETTINGS: [&str; 7] = [
    "VisionCameraSource",
    "VisionCameraTimeout",
    "VisionCameraFlushFrames",
    "VisionCameraSearchRadius",
    "VisionCameraMarkDiameterPx",
    "VisionCameraMark",
    "VisionCameraPolarity",
];

/// Serves the simulated camera's rendered frames as PNG snapshots on a loopback port, and
/// points the camera driver's settings at it with the mark settings the simulated operator
/// would set ([`vision_host::sim_image_config`]); no frame is flushed (each is rendered at the
/// request, so none is stale), and the timeout is 60 s (a frame is rendered at each request).
fn serve_frames(sim: &Sim, params: &mut Params) -> Result<SnapshotServer, Failure> {
    let config = vision_host::sim_image_config(sim, params).map_err(|e| Failure::Input(e.to_string()))?;
    let mark = config.mark;
    if let Some(d) = mark.diameter_px {
        set(params, "VisionCameraMarkDiameterPx", d)?;
    }
    set(params, "VisionCameraSearchRadius", mark.search_radius_pct)?;
    let kind = match mark.kind {
        vision_driver_camera::MarkKind::Dot => "dot",
        vision_driver_camera::MarkKind::Ring => "ring",
        vision_driver_camera::MarkKind::Cross => "cross",
    };
    set(params, "VisionCameraMark", kind)?;
    let polarity = if mark.polarity == vision_driver_camera::Polarity::Dark { "dark" } else { "light" };
    set(params, "VisionCameraPolarity", polarity)?;
    set(params, "VisionCameraFlushFrames", 0_i64)?;
    // Rendering a frame takes a fraction of a second in a release build, seconds in a debug one.
    set(params, "VisionCameraTimeout", 60.0)?;
    let mut frames = SimFrames(sim.clone());
    let server = SnapshotServer::bind("127.0.0.1:0", Encoding::Png, move || frames.frame().map_err(|e| e.to_string()))
        .map_err(|e| Failure::Input(format!("cannot start the loopback snapshot server: {e}")))?;
    set(params, "VisionCameraSource", server.url("/snapshot").as_str())?;
    Ok(server)
}

/// The registered name `--camera` gives (any case).
///
/// # Errors
/// [`Failure::Input`] naming the cameras there are, for a name none is registered under.
pub(crate) fn camera_name(registry: &DriverRegistry, camera: &str) -> Result<String, Failure> {
    registry.name(camera).map(str::to_string).ok_or_else(|| {
        Failure::Input(format!(
            "--camera {}: no such camera — the cameras are {} (any case)",
            vision_core::text::printable_line(camera, 64),
            registry.names().join(", ").to_ascii_lowercase()
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_loopback_server_sets_only_the_settings_kept_out_of_the_profile() {
        let sim = Sim::new(vision_driver_sim::World::default_world()).expect("world");
        let registry = vision_host::cameras(Some(&sim));
        let before = registry.params();
        let mut after = before.clone();
        let _server = serve_frames(&sim, &mut after).expect("served");
        let changed: Vec<&str> = after
            .config_values()
            .into_iter()
            .filter(|(name, value)| before.get(name).ok().as_ref() != Some(value))
            .map(|(name, _)| name)
            .collect();
        assert!(changed.contains(&"VisionCameraSource"), "{changed:?}");
        for name in changed {
            assert!(LOOPBACK_CAMERA_SETTINGS.contains(&name), "{name} is set for the loopback server but saved");
        }
    }
}
