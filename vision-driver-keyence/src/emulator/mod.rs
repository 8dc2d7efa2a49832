//! A TCP server that behaves like a Keyence VS camera on its Non-Procedural command port, for
//! tests, benchmarks, demonstrations and (later) `mach-vision emulate`.
//!
//! The commands it answers, its errors and its one-client rule: `docs/keyence-driver.md`
//! (the emulator).
//!
//! **Faults** ([`Fault`]) are queued with [`EmulatorHandle::inject`] or
//! [`EmulatorBuilder::faults`]; each `TRG` consumes the next one.
//!
//! ```
//! use vision_core::Reading;
//! use vision_driver_keyence::emulator::{Emulator, ListSource};
//! use vision_driver_keyence::{KeyenceConfig, KeyenceDriver};
//!
//! let camera = Emulator::builder()
//!     .source(ListSource::readings([Reading::position(812.0, 903.5)]))
//!     .bind("127.0.0.1:0")?;
//! let mut driver = KeyenceDriver::new(KeyenceConfig::new("127.0.0.1", camera.addr().port()))?;
//! let reading = driver.measure()?;
//! assert_eq!((reading.x_px, reading.y_px), (812.0, 903.5));
//! camera.shutdown();
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod camera;
mod server;
mod settings;
mod source;

use std::io;
use std::net::{Ipv4Addr, Ipv6Addr, Shutdown, SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::{self, JoinHandle};
use std::time::Duration;

use vision_core::Reading;

pub use settings::{Delimiter, EmulatorSettings, JudgmentStyle, Mode, NumberStyle, OutputFormat, Series};
pub use source::{DriverSource, FnSource, ListSource, ResultSource, Shot};

use crate::protocol::Program;
use camera::Camera;
use server::{accept_loop, lock, Shared};

/// Where [`EmulatorBuilder::start`] listens: loopback, the Keyence port.
pub const DEFAULT_ADDR: &str = "127.0.0.1:8500";

/// A misbehaviour for one `TRG` reply.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum Fault {
    /// Reply only after this long; nothing is sent if the client leaves first.
    Delay(Duration),
    /// Close the connection on receiving `TRG`, without a reply.
    Close,
    /// Send the echo, then close the connection.
    CloseAfterEcho,
    /// Send the echo, then these bytes as the data line (like [`Shot::Line`], but any bytes,
    /// text or not).
    Garbage(Vec<u8>),
    /// Send every byte of the reply in its own write, 1 ms apart.
    ByteByByte,
    /// Send the echo and the data line in one write.
    OneSegment,
    /// End the lines with CRLF and send a lone LF after the reply, in its own write.
    StrayLf,
    /// Send the reply after this long, or as soon as the client has gone if it leaves first (a
    /// client that timed out and closed): unlike [`Fault::Delay`], the reply is written either
    /// way, into the dead connection in the second case.
    LateReply(Duration),
    /// Send the echo and no data line: [`Shot::Silent`] instead of the source's answer.
    Silence,
    /// Answer `ER,TRG,<code>`: [`Shot::Reject`] instead of the source's answer.
    Reject(u8),
    /// Send the reply one byte per interval.
    Dribble(Duration),
    /// Send the echo, then a data line of this many bytes.
    LongLine(usize),
    /// Send this many stale data lines before the echo.
    ManyLines(usize),
}

/// What the emulator has seen so far.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EmulatorStats {
    /// Client connections served.
    pub connections: u64,
    /// Client connections turned away because another client held the camera.
    pub rejected: u64,
    /// Complete non-empty commands received.
    pub commands: u64,
    /// `TRG` commands accepted (answered with an echo or a fault).
    pub triggers: u64,
}

/// Entry point: [`Emulator::builder`].
#[derive(Debug, Clone, Copy)]
pub struct Emulator;

impl Emulator {
    /// A builder with the default settings and a source that always reports a mark at the
    /// centre of a 1776 × 1776 image.
    #[must_use]
    pub fn builder() -> EmulatorBuilder {
        EmulatorBuilder { settings: EmulatorSettings::default(), source: None, faults: Vec::new() }
    }
}

/// Configures an emulator; [`EmulatorBuilder::bind`] starts it.
pub struct EmulatorBuilder {
    settings: EmulatorSettings,
    source: Option<Box<dyn ResultSource>>,
    faults: Vec<Fault>,
}

impl std::fmt::Debug for EmulatorBuilder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EmulatorBuilder").field("settings", &self.settings).field("faults", &self.faults).finish()
    }
}

impl EmulatorBuilder {
    /// Replaces all settings.
    #[must_use]
    pub fn settings(mut self, settings: EmulatorSettings) -> EmulatorBuilder {
        self.settings = settings;
        self
    }

    /// Where trigger results come from.
    #[must_use]
    pub fn source(mut self, source: impl ResultSource + 'static) -> EmulatorBuilder {
        self.source = Some(Box::new(source));
        self
    }

    /// Faults for the first `TRG` replies, in order.
    #[must_use]
    pub fn faults(mut self, faults: impl IntoIterator<Item = Fault>) -> EmulatorBuilder {
        self.faults.extend(faults);
        self
    }

    /// The Data Output fields.
    #[must_use]
    pub fn format(mut self, format: OutputFormat) -> EmulatorBuilder {
        self.settings.format = format;
        self
    }

    /// The number style.
    #[must_use]
    pub fn numbers(mut self, numbers: NumberStyle) -> EmulatorBuilder {
        self.settings.numbers = numbers;
        self
    }

    /// The judgment style.
    #[must_use]
    pub fn judgment(mut self, judgment: JudgmentStyle) -> EmulatorBuilder {
        self.settings.judgment = judgment;
        self
    }

    /// The delimiter the camera writes.
    #[must_use]
    pub fn delimiter(mut self, delimiter: Delimiter) -> EmulatorBuilder {
        self.settings.delimiter = delimiter;
        self
    }

    /// The job-command series (`PL` or `PW`).
    #[must_use]
    pub fn series(mut self, series: Series) -> EmulatorBuilder {
        self.settings.series = series;
        self
    }

    /// The mode at start.
    #[must_use]
    pub fn mode(mut self, mode: Mode) -> EmulatorBuilder {
        self.settings.mode = mode;
        self
    }

    /// The unfinished-command timeout (`07`), 3 s by default.
    #[must_use]
    pub fn command_timeout(mut self, timeout: Duration) -> EmulatorBuilder {
        self.settings.command_timeout = timeout;
        self
    }

    /// Time between the echo and the data line.
    #[must_use]
    pub fn inspection_time(mut self, time: Duration) -> EmulatorBuilder {
        self.settings.inspection_time = time;
        self
    }

    /// Time a job switch keeps the camera busy (`05`).
    #[must_use]
    pub fn load_time(mut self, time: Duration) -> EmulatorBuilder {
        self.settings.load_time = time;
        self
    }

    /// Starts serving on [`DEFAULT_ADDR`] (127.0.0.1:8500).
    ///
    /// # Errors
    /// As [`EmulatorBuilder::bind`].
    pub fn start(self) -> io::Result<EmulatorHandle> {
        self.bind(DEFAULT_ADDR)
    }

    /// Starts serving on `addr` (use `127.0.0.1:0` for a free port; see
    /// [`EmulatorHandle::addr`]).
    ///
    /// # Errors
    /// The address cannot be bound, or the version text is not printable ASCII
    /// (`InvalidInput`).
    pub fn bind(self, addr: impl ToSocketAddrs) -> io::Result<EmulatorHandle> {
        let s = &self.settings;
        if s.version.is_empty() || !s.version.bytes().all(|b| (0x20..0x7f).contains(&b)) {
            return Err(io::Error::new(io::ErrorKind::InvalidInput, "the FVR version must be printable ASCII"));
        }
        if !(1..=2).contains(&s.program.0) || s.program.1 > s.max_job || s.max_job > 999 {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                "the start program must be a device 1–2 and a job ≤ max_job ≤ 999",
            ));
        }
        let listener = TcpListener::bind(addr)?;
        let addr = listener.local_addr()?;
        let source = self.source.unwrap_or_else(|| Box::new(ListSource::readings([Reading::position(888.0, 888.0)])));
        let shared = Arc::new(Shared {
            camera: Mutex::new(Camera::new(self.settings, source)),
            faults: Mutex::new(self.faults.into()),
            stats: Mutex::new(EmulatorStats::default()),
            shutdown: AtomicBool::new(false),
            client: Mutex::new(None),
        });
        let s = Arc::clone(&shared);
        let thread = thread::Builder::new().name("keyence-emulator".into()).spawn(move || accept_loop(listener, s))?;
        Ok(EmulatorHandle { addr, shared, thread: Some(thread) })
    }
}

/// A running emulator. Dropping it (or [`EmulatorHandle::shutdown`]) stops its threads and
/// closes its sockets.
pub struct EmulatorHandle {
    addr: SocketAddr,
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl std::fmt::Debug for EmulatorHandle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EmulatorHandle").field("addr", &self.addr).field("stats", &self.stats()).finish()
    }
}

impl EmulatorHandle {
    /// The address it listens on.
    #[must_use]
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Queues `fault` for the next `TRG` reply that has none.
    pub fn inject(&self, fault: Fault) {
        lock(&self.shared.faults).push_back(fault);
    }

    /// Faults still queued.
    #[must_use]
    pub fn pending_faults(&self) -> Vec<Fault> {
        lock(&self.shared.faults).iter().cloned().collect()
    }

    /// Counters so far.
    #[must_use]
    pub fn stats(&self) -> EmulatorStats {
        *lock(&self.shared.stats)
    }

    /// The camera's mode.
    #[must_use]
    pub fn mode(&self) -> Mode {
        lock(&self.shared.camera).mode
    }

    /// Switches the camera's mode (as its front panel would).
    pub fn set_mode(&self, mode: Mode) {
        lock(&self.shared.camera).mode = mode;
    }

    /// The job the camera runs.
    #[must_use]
    pub fn program(&self) -> Program {
        lock(&self.shared.camera).program
    }

    /// Closes the current client's connection from the camera side, as a camera that drops an
    /// idle link would.
    pub fn disconnect_client(&self) {
        if let Some(c) = lock(&self.shared.client).take() {
            let _ = c.shutdown(Shutdown::Both);
        }
    }

    /// Stops the emulator and waits for its threads.
    pub fn shutdown(mut self) {
        self.stop();
    }

    fn stop(&mut self) {
        self.shared.shutdown.store(true, Ordering::SeqCst);
        self.disconnect_client();
        let wake = match self.addr {
            SocketAddr::V4(a) if a.ip().is_unspecified() => SocketAddr::new(Ipv4Addr::LOCALHOST.into(), a.port()),
            SocketAddr::V6(a) if a.ip().is_unspecified() => SocketAddr::new(Ipv6Addr::LOCALHOST.into(), a.port()),
            a => a,
        };
        let _ = TcpStream::connect_timeout(&wake, Duration::from_secs(1));
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for EmulatorHandle {
    fn drop(&mut self) {
        self.stop();
    }
}
