//! The simulated world and its emulated Keyence camera, shared by `run` and `emulate`.

use std::net::ToSocketAddrs;
use std::path::Path;

use vision_driver_keyence::emulator::{DriverSource, Emulator, EmulatorHandle, NumberStyle, OutputFormat};
use vision_driver_sim::{Sim, World};

use crate::{read_text, Failure};

/// The world in `path`, or the built-in one.
pub(crate) fn load(path: Option<&Path>) -> Result<World, Failure> {
    match path {
        Some(path) => {
            World::from_toml(&read_text(path, "world")?).map_err(|e| Failure::Input(format!("{}: {e}", path.display())))
        }
        None => Ok(World::default_world()),
    }
}

/// A Keyence VS emulator at `addr` whose results come from `sim`'s camera, in the recommended
/// 8-field format with fixed-width numbers (6 decimals of a pixel).
pub(crate) fn serve_camera(sim: &Sim, addr: impl ToSocketAddrs) -> std::io::Result<EmulatorHandle> {
    Emulator::builder()
        .source(DriverSource(Box::new(sim.camera())))
        .format(OutputFormat::Full)
        .numbers(NumberStyle::FixedWidth)
        .bind(addr)
}
