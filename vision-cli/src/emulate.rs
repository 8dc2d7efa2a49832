//! `mach-vision emulate [keyence|grbl]`: a Keyence VS camera backed by the simulated camera
//! (the default), or a Grbl 1.1 / grblHAL controller on loopback TCP or a pseudo-terminal.

use std::io::Write as _;
use std::net::SocketAddr;
use std::path::PathBuf;

use clap::{Args, ValueEnum};
use vision_driver_sim::Sim;
use vision_grbl::emulator::{Emulator, EmulatorConfig, Flavour};

use crate::{world, Failure};

/// What `emulate` serves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Kind {
    /// A Keyence VS camera (the simulated camera) over TCP.
    Keyence,
    /// A Grbl 1.1 controller (or grblHAL with --flavour grblhal).
    Grbl,
}

/// The firmware `emulate grbl` answers as.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum FlavourArg {
    /// Grbl 1.1h: 128-byte receive buffer, 15 planner blocks.
    Grbl,
    /// grblHAL: 1024-byte buffer, 100 blocks, errors latched, G51 accepted.
    Grblhal,
}

/// Arguments of `mach-vision emulate`.
#[derive(Debug, Args)]
pub(crate) struct EmulateArgs {
    /// What to emulate.
    #[arg(value_enum, default_value_t = Kind::Keyence)]
    kind: Kind,
    /// The simulated world (TOML); default: the built-in world. keyence: the head stays at the
    /// world's start position, so the camera sees what lies there. grbl: the controller is the
    /// world's machine — its G54 is the world's `machine.work_offset` and it powers up at
    /// `machine.start` (in mm), so `send --camera sim` sees the world's parts where the
    /// program expects them.
    #[arg(long, value_name = "W.toml")]
    world: Option<PathBuf>,
    /// keyence: TCP port on 127.0.0.1 (0 picks a free one); default 8500.
    #[arg(long, allow_negative_numbers = true)]
    port: Option<u16>,
    /// grbl: the loopback address to listen on (port 0 picks a free one); default
    /// 127.0.0.1:0 unless --pty is given.
    #[arg(long, value_name = "HOST:PORT")]
    listen: Option<SocketAddr>,
    /// grbl: also serve on a pseudo-terminal, whose path is printed.
    #[arg(long)]
    pty: bool,
    /// grbl: the firmware.
    #[arg(long, value_enum)]
    flavour: Option<FlavourArg>,
    /// grbl: simulated seconds per real second (motion runs this much faster).
    #[arg(long, value_name = "FACTOR")]
    time_scale: Option<f64>,
}

/// Serves until the process is stopped (Ctrl-C). Prints one line per endpoint first.
pub(crate) fn run(args: &EmulateArgs) -> Result<String, Failure> {
    match args.kind {
        Kind::Keyence => {
            if args.listen.is_some() || args.pty || args.flavour.is_some() || args.time_scale.is_some() {
                return Err(Failure::Input(
                    "--listen, --pty, --flavour and --time-scale are for `emulate grbl`".into(),
                ));
            }
            keyence(args)
        }
        Kind::Grbl => {
            if args.port.is_some() {
                return Err(Failure::Input(
                    "--port is for `emulate keyence`; `emulate grbl` takes --listen HOST:PORT".into(),
                ));
            }
            grbl(args)
        }
    }
}

fn keyence(args: &EmulateArgs) -> Result<String, Failure> {
    let port = args.port.unwrap_or(8500);
    let sim = Sim::new(world::load(args.world.as_deref())?).map_err(|e| Failure::Input(e.to_string()))?;
    let emulator = world::serve_camera(&sim, ("127.0.0.1", port))
        .map_err(|e| Failure::Input(format!("cannot listen on 127.0.0.1:{port}: {e}")))?;
    let mut out = std::io::stdout();
    let _ = writeln!(out, "emulating a Keyence VS camera at {} (the simulated camera); Ctrl-C stops", emulator.addr());
    let _ = out.flush();
    loop {
        std::thread::park();
    }
}

fn grbl(args: &EmulateArgs) -> Result<String, Failure> {
    let time_scale = args.time_scale.unwrap_or(1.0);
    if !(time_scale.is_finite() && time_scale > 0.0 && time_scale <= 1000.0) {
        return Err(Failure::Input(format!("--time-scale {time_scale} is not in (0, 1000]")));
    }
    let flavour = match args.flavour {
        Some(FlavourArg::Grblhal) => Flavour::GrblHal,
        _ => Flavour::Grbl,
    };
    let name = match flavour {
        Flavour::Grbl => "Grbl 1.1h",
        Flavour::GrblHal => "grblHAL",
    };
    let world = world::load(args.world.as_deref())?;
    let config = EmulatorConfig { flavour, time_scale, ..grbl_config(&world) };
    let listen = match (args.listen, args.pty) {
        (Some(addr), _) => Some(addr),
        (None, false) => Some(SocketAddr::from(([127, 0, 0, 1], 0))),
        (None, true) => None,
    };
    let mut out = std::io::stdout();
    let mut _tcp = None;
    if let Some(addr) = listen {
        if !addr.ip().is_loopback() {
            return Err(Failure::Input(format!("--listen {addr}: the emulator serves loopback addresses only")));
        }
        let emulator = Emulator::bind(addr, config.clone())
            .map_err(|e| Failure::Input(format!("cannot listen on {addr}: {e}")))?;
        let _ = writeln!(out, "emulating {name} at tcp://{}; Ctrl-C stops", emulator.addr());
        _tcp = Some(emulator);
    }
    let mut _pty = None;
    if args.pty {
        let pty = open_pty(config)?;
        let _ = writeln!(out, "emulating {name} on {}; Ctrl-C stops", pty.0);
        _pty = Some(pty.1);
    }
    let _ = out.flush();
    loop {
        std::thread::park();
    }
}

#[cfg(unix)]
fn open_pty(config: EmulatorConfig) -> Result<(String, vision_grbl::emulator::PtyEmulator), Failure> {
    let pty = vision_grbl::emulator::PtyEmulator::open(config)
        .map_err(|e| Failure::Input(format!("cannot open a pseudo-terminal: {e}")))?;
    Ok((pty.path().display().to_string(), pty))
}

#[cfg(not(unix))]
fn open_pty(_config: EmulatorConfig) -> Result<(String, ()), Failure> {
    Err(Failure::Input("--pty needs a Unix system; use --listen".into()))
}

/// A Grbl controller that is `world`'s machine: G54 = `machine.work_offset`, powered up at
/// `machine.start`, both in mm as Grbl keeps them.
fn grbl_config(world: &vision_driver_sim::World) -> EmulatorConfig {
    let mm = world.length_unit().factor_to(vision_math::LengthUnit::Millimetre);
    let mut work_offsets = [[0.0; 3]; 6];
    work_offsets[0] = world.machine.work_offset.map(|v| v * mm);
    EmulatorConfig { work_offsets, start: world.machine.start.map(|v| v * mm), ..EmulatorConfig::default() }
}
