//! `mach-vision panel`: a local web page showing what the camera sees (`vision-panel`). Each
//! look is one trigger of the camera driver, as M281 takes it: the frame, searched within the
//! search radius with the profile's mark settings (or, for `simimage`, the ones the simulated
//! operator sets); the page draws the located mark over it. With `--profile` and no
//! `--camera`, it shows the profile's panel folder instead ([`folder`]). Runs until Ctrl-C; the
//! profile is read, never written.

mod folder;

use std::io::Write as _;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Args;
use vision_core::{Params, ProfileStore};
use vision_driver_camera::{FrameDriver, FrameSource};
use vision_driver_sim::Sim;
use vision_host::{SimFrames, SIM_IMAGE};
use vision_panel::{observe, Panel};

use crate::{world, Failure};

/// The shortest time between two looks (at most 5 frames a second).
const LOOK_PERIOD: Duration = Duration::from_millis(200);

/// Arguments of `mach-vision panel`.
#[derive(Debug, Args)]
pub(crate) struct PanelArgs {
    /// The camera: `simimage` (the frames the world's simulated camera sees, rendered) or
    /// `camera` (a USB, network or file camera: `--source`, or the profile's
    /// VisionCameraSource), in any case. Default: with `--profile`, what the controller's
    /// session publishes in the profile's panel folder (`P.panel`); without, `simimage`.
    #[arg(long, value_name = "NAME")]
    camera: Option<String>,
    /// Frame source for `--camera camera`: a V4L2 device, an `http://` snapshot URL, or an
    /// image file or folder.
    #[arg(long, value_name = "DEVICE|URL|PATH")]
    source: Option<String>,
    /// The simulated world (TOML) `simimage` renders; default: the built-in world.
    #[arg(long, value_name = "W.toml")]
    world: Option<PathBuf>,
    /// The Vision profile whose camera settings and calibration (K, for the offset in machine
    /// units) the panel uses; read only. Default: for `simimage`, the profile a perfect
    /// calibration of the world would leave; for `camera`, the defaults.
    #[arg(long, value_name = "P.toml")]
    profile: Option<PathBuf>,
    /// Where to serve the page. An address other than loopback needs `--token`.
    #[arg(long, default_value = "127.0.0.1:8090", value_name = "ADDRESS:PORT")]
    listen: SocketAddr,
    /// A secret every request must give (`?token=…` in the page's address): 1 to 256 of
    /// A-Z a-z 0-9 - . _ ~.
    #[arg(long)]
    token: Option<String>,
}

pub(crate) fn run(args: &PanelArgs) -> Result<String, Failure> {
    // The address and token are checked first: a refusal costs no camera.
    let panel = Panel::bind(args.listen, args.token.as_deref()).map_err(|e| Failure::Input(e.to_string()))?;
    if let (None, Some(profile)) = (&args.camera, &args.profile) {
        return watch_folder(&panel, args, profile);
    }
    let (mut driver, params) = camera(args)?;
    let page = match &args.token {
        Some(t) => format!("{}?token={t}", panel.url()),
        None => panel.url(),
    };
    let mut out = std::io::stdout();
    let _ = writeln!(out, "panel at {page} ({}); Ctrl-C stops", driver.source().describe());
    let _ = out.flush();
    let handle = panel.handle();
    loop {
        let start = Instant::now();
        handle.publish(observe(&mut driver, &params));
        std::thread::sleep(LOOK_PERIOD.saturating_sub(start.elapsed()));
    }
}

/// `--profile P` without `--camera`: the session's panel folder, `P.panel`.
fn watch_folder(panel: &Panel, args: &PanelArgs, profile: &std::path::Path) -> Result<String, Failure> {
    let input = |e: &dyn std::fmt::Display| Failure::Input(e.to_string());
    if args.source.is_some() {
        return Err(Failure::Input("--source is for --camera camera".into()));
    }
    if !profile.is_file() {
        return Err(Failure::Input(format!("no profile {}: the panel reads one", profile.display())));
    }
    let sim = Sim::new(world::load(args.world.as_deref())?).map_err(|e| input(&e))?;
    let registry = vision_host::cameras(Some(&sim));
    let params = ProfileStore::new(profile).with_defaults(registry.params()).load().map_err(|e| input(&e))?;
    let dir = vision_host::panel::panel_dir(profile);
    let page = match &args.token {
        Some(t) => format!("{}?token={t}", panel.url()),
        None => panel.url(),
    };
    let mut out = std::io::stdout();
    let _ = writeln!(out, "panel at {page} (the panel folder {}); Ctrl-C stops", dir.display());
    let _ = out.flush();
    folder::watch(&panel.handle(), &dir, &params)
}

/// The driver `--camera` names, and the parameters its looks are described with.
fn camera(args: &PanelArgs) -> Result<(FrameDriver, Params), Failure> {
    let input = |e: &dyn std::fmt::Display| Failure::Input(e.to_string());
    let sim = Sim::new(world::load(args.world.as_deref())?).map_err(|e| input(&e))?;
    let registry = vision_host::cameras(Some(&sim));
    let name = crate::run::camera_name(&registry, args.camera.as_deref().unwrap_or(SIM_IMAGE))?;
    let mut params = match &args.profile {
        Some(path) if path.is_file() => {
            ProfileStore::new(path).with_defaults(registry.params()).load().map_err(|e| input(&e))?
        }
        Some(path) => return Err(Failure::Input(format!("no profile {}: the panel reads one", path.display()))),
        None if name == SIM_IMAGE => sim.calibrated_params(&registry.params()).map_err(|e| input(&e))?,
        None => registry.params(),
    };
    if args.source.is_some() && name != vision_driver_camera::DRIVER_NAME {
        return Err(Failure::Input("--source is for --camera camera".into()));
    }
    let driver = if name == SIM_IMAGE {
        let config = vision_host::sim_image_config(&sim, &params).map_err(|e| input(&e))?;
        FrameDriver::new(config, Box::new(SimFrames(sim)) as Box<dyn FrameSource>).map_err(|e| input(&e))?
    } else if name == vision_driver_camera::DRIVER_NAME {
        if let Some(source) = &args.source {
            params.set("VisionCameraSource", source.as_str()).map_err(|e| input(&e))?;
        }
        FrameDriver::from_params(&params).map_err(|e| input(&e))?
    } else {
        return Err(Failure::Input(format!(
            "--camera {}: the panel shows frames, from `simimage` or `camera` (with --source)",
            vision_core::text::printable_line(args.camera.as_deref().unwrap_or(SIM_IMAGE), 64)
        )));
    };
    Ok((driver, params))
}
