//! A Grbl 1.1 controller (or grblHAL, [`Flavour::GrblHal`]) on loopback TCP or a
//! pseudo-terminal, for tests, benchmarks and demonstrations.
//!
//! It follows Grbl's source (gnea/grbl `serial.c`, `protocol.c`, `gcode.c`, `report.c`,
//! `system.c`): a 128-byte receive buffer whose overflow bytes are lost, 15 planner blocks,
//! `ok`/`error:N` per line with the parser's checks in Grbl's order, status reports with `WCO`
//! every 10 (idle) or 30 (busy) reports or after a change, `$G`, `$#`, `$I`, `$$`, `$X`, `$H`,
//! `$C`, and the real-time bytes `?`, `!`, `~` and 0x18 (`ALARM:3` after a reset in motion).
//! As grblHAL it also runs the drilling cycles G81/G82 (the `canned` module).
//! Motion is timed from `$110`–`$112` and `$120`–`$122`: see the `motion` module for the
//! planner it keeps. Time runs [`EmulatorConfig::time_scale`] times faster than real time.
//!
//! Not emulated: probing (G38.x answers `error:20`), jogging (`$J=`), sleep, limits, overrides
//! (the bytes are swallowed), startup lines (accepted, not run). Each TCP connection gets a
//! freshly powered-up controller, as a USB Grbl resets when a sender opens the port; its
//! EEPROM offsets and position come from [`EmulatorConfig::work_offsets`] and
//! [`EmulatorConfig::start`].
//!
//! ```
//! use std::io::{BufRead, BufReader, Write};
//! use vision_grbl::emulator::{Emulator, EmulatorConfig};
//!
//! let grbl = Emulator::bind("127.0.0.1:0", EmulatorConfig::default())?;
//! let mut socket = std::net::TcpStream::connect(grbl.addr())?;
//! socket.write_all(b"G68\n")?;
//! let lines: Vec<String> = BufReader::new(socket).lines().take(3).collect::<Result<_, _>>()?;
//! assert_eq!(lines, ["", "Grbl 1.1h ['$' for help]", "error:20"]);
//! # Ok::<(), std::io::Error>(())
//! ```

mod block;
mod canned;
mod gcode;
mod machine;
mod motion;
#[cfg(unix)]
mod pty;
mod report;
mod settings;
mod status;
mod system;

use std::io::{self, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

pub use machine::Machine;
#[cfg(unix)]
pub(crate) use pty::make_raw;
#[cfg(unix)]
pub use pty::PtyEmulator;

/// Which firmware the emulator answers as.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Flavour {
    /// Grbl 1.1h: 128-byte receive buffer, 15 planner blocks.
    #[default]
    Grbl,
    /// grblHAL: 1024-byte buffer, 100 blocks, errors latched, G50/G51 scaling.
    GrblHal,
}

/// How the emulated controller is built and how fast its clock runs.
#[derive(Debug, Clone)]
pub struct EmulatorConfig {
    /// The firmware.
    pub flavour: Flavour,
    /// Simulated seconds per real second; above 1 motion finishes sooner (tests, benches).
    pub time_scale: f64,
    /// Grbl built with `ENABLE_M7` (mist coolant), which `[OPT:]` then shows as `M`. grblHAL
    /// always has it.
    pub m7: bool,
    /// `$N=value` settings applied at power-up, e.g. `(110, 5000.0)` (Grbl's units).
    pub settings: Vec<(u16, f64)>,
    /// G54..G59 as stored in EEPROM at power-up (mm): each TCP connection powers up a fresh
    /// controller, so this is what persists between connections. Non-finite values read as 0.
    pub work_offsets: [[f64; 3]; 6],
    /// The machine position at power-up (mm). Non-finite values read as 0.
    pub start: [f64; 3],
}

impl Default for EmulatorConfig {
    fn default() -> Self {
        Self {
            flavour: Flavour::Grbl,
            time_scale: 1.0,
            m7: true,
            settings: Vec::new(),
            work_offsets: [[0.0; 3]; 6],
            start: [0.0; 3],
        }
    }
}

impl EmulatorConfig {
    /// The receive buffer (bytes).
    pub fn rx_buffer(&self) -> usize {
        match self.flavour {
            Flavour::Grbl => 128,
            Flavour::GrblHal => 1024,
        }
    }

    /// The bytes the receive buffer holds: grblHAL's ring keeps one slot free, so one less
    /// than [`rx_buffer`](Self::rx_buffer) (its `Bf:` shows 1023 when empty).
    pub fn rx_capacity(&self) -> usize {
        match self.flavour {
            Flavour::Grbl => 128,
            Flavour::GrblHal => 1023,
        }
    }

    /// The planner's blocks.
    pub fn planner_blocks(&self) -> usize {
        match self.flavour {
            Flavour::Grbl => 15,
            Flavour::GrblHal => 100,
        }
    }
}

/// An emulator serving TCP clients one at a time; stops when dropped.
#[derive(Debug)]
pub struct Emulator {
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    current: Arc<Mutex<Option<TcpStream>>>,
    thread: Option<JoinHandle<()>>,
}

impl Emulator {
    /// Listens on `addr` (port 0 picks a free one) and serves in a background thread.
    pub fn bind(addr: impl ToSocketAddrs, config: EmulatorConfig) -> io::Result<Self> {
        let listener = TcpListener::bind(addr)?;
        listener.set_nonblocking(true)?;
        let addr = listener.local_addr()?;
        let stop = Arc::new(AtomicBool::new(false));
        let current: Arc<Mutex<Option<TcpStream>>> = Arc::new(Mutex::new(None));
        let (stop2, current2) = (Arc::clone(&stop), Arc::clone(&current));
        let thread = thread::spawn(move || {
            while !stop2.load(Ordering::Relaxed) {
                match listener.accept() {
                    Ok((socket, _)) => {
                        let _ = socket.set_nonblocking(false);
                        let _ = socket.set_nodelay(true);
                        let (Ok(reader), Ok(keep)) = (socket.try_clone(), socket.try_clone()) else { continue };
                        *current2.lock().unwrap_or_else(std::sync::PoisonError::into_inner) = Some(keep);
                        let mut writer = socket;
                        let _ = serve(reader, &mut writer, config.clone(), &stop2);
                        let _ = writer.shutdown(Shutdown::Both);
                        *current2.lock().unwrap_or_else(std::sync::PoisonError::into_inner) = None;
                    }
                    Err(e) if e.kind() == io::ErrorKind::WouldBlock => thread::sleep(Duration::from_millis(2)),
                    Err(_) => thread::sleep(Duration::from_millis(2)),
                }
            }
        });
        Ok(Self { addr, stop, current, thread: Some(thread) })
    }

    /// Where it listens.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Drops the current client's connection, as a cable pulled out would.
    pub fn disconnect(&self) {
        if let Some(s) = self.current.lock().unwrap_or_else(std::sync::PoisonError::into_inner).take() {
            let _ = s.shutdown(Shutdown::Both);
        }
    }

    /// Stops serving and waits for the server thread.
    pub fn shutdown(mut self) {
        self.stop_now();
    }

    fn stop_now(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        self.disconnect();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for Emulator {
    fn drop(&mut self) {
        self.stop_now();
    }
}

/// Runs one controller over a byte stream until the stream closes or `stop` is set: a thread
/// reads, this loop advances the clock every millisecond and writes what the controller sends.
pub fn serve<R: Read + Send + 'static>(
    mut reader: R,
    writer: &mut dyn Write,
    config: EmulatorConfig,
    stop: &AtomicBool,
) -> io::Result<()> {
    let (tx, rx) = mpsc::channel::<Vec<u8>>();
    thread::spawn(move || {
        let mut buf = [0u8; 4096];
        loop {
            match reader.read(&mut buf) {
                Ok(0) | Err(_) => break,
                Ok(n) => {
                    if tx.send(buf[..n].to_vec()).is_err() {
                        break;
                    }
                }
            }
        }
    });
    let scale = if config.time_scale.is_finite() && config.time_scale > 0.0 { config.time_scale } else { 1.0 };
    let mut machine = Machine::new(config);
    let mut last = Instant::now();
    loop {
        if stop.load(Ordering::Relaxed) {
            return Ok(());
        }
        match rx.recv_timeout(Duration::from_millis(1)) {
            Ok(bytes) => machine.receive(&bytes),
            Err(mpsc::RecvTimeoutError::Timeout) => {}
            Err(mpsc::RecvTimeoutError::Disconnected) => return Ok(()),
        }
        let now = Instant::now();
        machine.advance(now.duration_since(last).as_secs_f64() * scale);
        last = now;
        let out = machine.take_output();
        if !out.is_empty() {
            writer.write_all(&out)?;
            writer.flush()?;
        }
    }
}
