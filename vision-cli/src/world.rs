//! The simulated world and its emulated Keyence camera, shared by `run` and `emulate`.

use std::net::ToSocketAddrs;
use std::path::Path;

use vision_driver_keyence::emulator::{DriverSource, Emulator, EmulatorHandle, NumberStyle, OutputFormat};
use vision_driver_sim::{Sim, World};
use vision_path::Limits;

use crate::{read_text, Failure};

/// The world in `path`, or the built-in one.
pub(crate) fn load(path: Option<&Path>) -> Result<World, Failure> {
    match path {
        Some(path) => {
            let world = World::from_toml(&read_text(path, "world")?)
                .map_err(|e| Failure::Input(format!("{}: {e}", path.display())))?;
            check_motion_limits(&world).map_err(|e| Failure::Input(format!("{}: {e}", path.display())))?;
            Ok(world)
        }
        None => Ok(World::default_world()),
    }
}

/// The world's `machine.max_speed` / `max_accel` within the planner's physical range, so a
/// bad value is refused at load, naming the field, rather than planned for ever or to 0 s.
fn check_motion_limits(world: &World) -> Result<(), String> {
    use vision_math::show::number;
    let (speed, accel) = world.machine.motion_limits(world.unit);
    let u = world.length_unit().short_name();
    for (field, value, range) in
        [("machine.max_speed", speed, &Limits::SPEED_RANGE), ("machine.max_accel", accel, &Limits::ACCEL_RANGE)]
    {
        if !range.contains(&value) {
            return Err(format!(
                "{field} = {} is invalid: the path planner accepts {} to {} {u}/s{}",
                number(value),
                number(*range.start()),
                number(*range.end()),
                if field.ends_with("accel") { "²" } else { "" }
            ));
        }
    }
    Ok(())
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
