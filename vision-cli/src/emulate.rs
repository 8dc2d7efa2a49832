//! `mach-vision emulate`: a Keyence VS camera on loopback, backed by the simulated camera.

use std::io::Write as _;
use std::path::PathBuf;

use clap::Args;
use vision_driver_sim::Sim;

use crate::{world, Failure};

/// Arguments of `mach-vision emulate`.
#[derive(Debug, Args)]
pub(crate) struct EmulateArgs {
    /// The simulated world (TOML); default: the built-in world. The head stays at the world's
    /// start position, so the camera sees what lies there.
    #[arg(long, value_name = "W.toml")]
    world: Option<PathBuf>,
    /// TCP port on 127.0.0.1 (0 picks a free one).
    #[arg(long, default_value_t = 8500, allow_negative_numbers = true)]
    port: u16,
}

/// Serves until the process is stopped (Ctrl-C). Prints one line with the address first.
pub(crate) fn run(args: &EmulateArgs) -> Result<String, Failure> {
    let sim = Sim::new(world::load(args.world.as_deref())?).map_err(|e| Failure::Input(e.to_string()))?;
    let emulator = world::serve_camera(&sim, ("127.0.0.1", args.port))
        .map_err(|e| Failure::Input(format!("cannot listen on 127.0.0.1:{}: {e}", args.port)))?;
    let mut out = std::io::stdout();
    let _ = writeln!(out, "emulating a Keyence VS camera at {} (the simulated camera); Ctrl-C stops", emulator.addr());
    let _ = out.flush();
    loop {
        std::thread::park();
    }
}
