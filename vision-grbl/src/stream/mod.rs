//! The sender: streams lines to a Grbl controller the way Grbl's own `stream.py` does, by
//! character counting — as many lines in flight as fit the controller's receive buffer — and
//! send-response (one line, wait for its answer) for lines that write settings or EEPROM,
//! which Grbl refuses or stalls on while moving. Lines go one at a time as a program produces
//! them ([`Sender::push`], then [`Sender::finish`]) or all at once ([`Sender::stream`]).
//!
//! Status reports are polled with `?` at most every 200 ms (5 Hz); the work offset is kept
//! from the last report that carried `WCO`. The first `error:N` or `ALARM:N` stops streaming:
//! nothing more is sent, and the error names the line. grblHAL then answers the lines still in
//! flight with the same error (it latches errors); [`Sender::unlatch`] clears that and lets
//! pushing start again.
//!
//! ```
//! use vision_grbl::emulator::{Emulator, EmulatorConfig};
//! use vision_grbl::stream::{Sender, SenderOptions};
//!
//! let grbl = Emulator::bind("127.0.0.1:0", EmulatorConfig { time_scale: 50.0, ..Default::default() })?;
//! let mut sender = Sender::connect(&format!("tcp://{}", grbl.addr()), &SenderOptions::default())?;
//! let report = sender.stream(&["G21 G90", "G1 X1 F500", "G1 Y1"])?;
//! assert_eq!(report.lines_sent, 3);
//! // Line by line, as an interpreter produces them.
//! sender.push("G1 X2")?;
//! sender.push("G1 Y2")?;
//! assert_eq!(sender.finish()?.lines_sent, 5);
//! let status = sender.wait_idle(std::time::Duration::from_secs(10))?;
//! assert_eq!(status.mpos, Some([2.0, 2.0, 0.0]));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod connection;
mod queries;
mod streaming;

use std::io;
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

use thiserror::Error;

use crate::response::{parse_line, MachineState, Response, Status};
pub use crate::state::{Offsets, ParserState};
use connection::{Event, SharedWriter};
use streaming::Flight;

/// The fastest status polling (5 Hz).
pub const MIN_POLL: Duration = Duration::from_millis(200);

/// How to connect.
#[derive(Debug, Clone)]
pub struct SenderOptions {
    /// Serial baud rate (terminals only; ignored for TCP).
    pub baud: Option<u32>,
    /// Status polling interval, never below [`MIN_POLL`].
    pub poll: Duration,
    /// How long to wait for any answer before giving up.
    pub timeout: Duration,
}

impl Default for SenderOptions {
    fn default() -> Self {
        Self { baud: Some(115_200), poll: MIN_POLL, timeout: Duration::from_secs(10) }
    }
}

/// Why streaming stopped. Line indexes are 0-based: within the lines given to
/// [`Sender::stream`], or counted over every [`Sender::push`] since connect.
#[derive(Debug, Error)]
pub enum StreamError {
    /// The port could not be opened.
    #[error("cannot open {port}: {source}")]
    Open {
        /// The port as given.
        port: String,
        /// Why.
        source: io::Error,
    },
    /// The controller refused a line; nothing after it was sent.
    #[error("line {} ({text:?}): the controller answered error:{code}", index + 1)]
    Firmware {
        /// Index of the line.
        index: usize,
        /// The line as sent.
        text: String,
        /// Grbl's status code.
        code: u8,
        /// Lines that were already in the controller's buffer behind it.
        in_flight: usize,
    },
    /// The controller raised an alarm, or is locked in one.
    #[error("ALARM:{code} (last line answered: {reached:?})")]
    Alarm {
        /// Grbl's alarm code (0 when the controller reported the state without the message).
        code: u8,
        /// Index of the last line the controller answered, if any.
        reached: Option<usize>,
    },
    /// The link closed or failed.
    #[error("connection lost ({reason}); last line answered: {reached:?}")]
    ConnectionLost {
        /// What the link said.
        reason: String,
        /// Index of the last line the controller answered, if any.
        reached: Option<usize>,
    },
    /// A line cannot fit the controller's receive buffer.
    #[error("line {} is {len} bytes, more than the controller's {limit}-byte buffer", index + 1)]
    LineTooLong {
        /// Index of the line (0-based).
        index: usize,
        /// Its length with the line end (bytes).
        len: usize,
        /// The receive buffer (bytes).
        limit: usize,
    },
    /// No answer in time.
    #[error("no answer from the controller within {0:?}")]
    Timeout(Duration),
    /// Writing failed.
    #[error("cannot write to the controller: {0}")]
    Write(io::Error),
    /// An error, alarm or reset stopped streaming earlier; nothing more is sent until
    /// [`Sender::unlatch`].
    #[error("streaming stopped at line index {at} (an error, alarm or reset); nothing more is sent")]
    Stopped {
        /// Index of the line that was refused, or of the first line not answered (0-based).
        at: usize,
    },
    /// A line holds a byte Grbl acts on wherever it sees it: a line end, `?`, `!`, `~`, 0x18,
    /// or 0x80..=0xFF (overrides, so also any non-ASCII text). Nothing of it was sent.
    #[error("line {} holds byte 0x{byte:02x}, which the controller would act on at once", index + 1)]
    RealTimeByte {
        /// Index of the line (0-based).
        index: usize,
        /// The byte.
        byte: u8,
    },
}

/// What streaming did since connect (every push and stream added up).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StreamReport {
    /// Lines sent.
    pub lines_sent: usize,
    /// Bytes sent, line ends included.
    pub bytes_sent: usize,
    /// The longest a line waited for room in the receive buffer (or for a sync).
    pub longest_wait: Duration,
    /// How often the planner ran dry while lines were still to come: a status report read in
    /// push or finish that showed `Idle`, or `Bf:` with every block free, after motion had
    /// started and before the last pushed line was answered.
    pub planner_dry: usize,
    /// Status reports read in push and finish.
    pub status_reports: usize,
}

/// `$` lines Grbl runs only when idle (system.c: settings, `$#`, `$H`, `$I`, `$N`, `$RST`):
/// the sender waits for an `Idle` report before sending them.
pub fn needs_idle(line: &str) -> bool {
    let upper = line.trim().to_ascii_uppercase();
    upper.starts_with('$') && !matches!(upper.as_str(), "$" | "$G" | "$X" | "$C" | "$$")
}

/// Lines Grbl stores in EEPROM or that change settings: sent alone (send-response).
pub fn needs_sync(line: &str) -> bool {
    let upper: String = line.chars().filter(|c| !c.is_whitespace()).collect::<String>().to_ascii_uppercase();
    if upper.starts_with('$') {
        return true;
    }
    let words = code_words(&upper);
    words
        .iter()
        .any(|w| matches!(w.as_str(), "G10" | "G28.1" | "G30.1" | "G54" | "G55" | "G56" | "G57" | "G58" | "G59"))
}

/// The G words of a line, comments dropped, leading zeros removed (`G01` → `G1`).
fn code_words(upper: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut depth = false;
    let bytes = upper.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        if c == b';' {
            break;
        }
        if c == b'(' {
            depth = true;
        } else if c == b')' {
            depth = false;
        } else if !depth && c == b'G' {
            let start = i + 1;
            let mut j = start;
            while j < bytes.len() && (bytes[j].is_ascii_digit() || bytes[j] == b'.') {
                j += 1;
            }
            let num = upper[start..j].trim_start_matches('0');
            out.push(format!(
                "G{}",
                if num.is_empty() || num.starts_with('.') { format!("0{num}") } else { num.to_string() }
            ));
            i = j;
            continue;
        }
        i += 1;
    }
    out
}

/// A connection to one controller.
pub struct Sender {
    writer: SharedWriter,
    events: Receiver<Event>,
    /// A TCP link's socket, shut down when the sender goes (the controller then sees the
    /// client leave, as when a serial port closes).
    socket: Option<std::net::TcpStream>,
    options: SenderOptions,
    rx_buffer: usize,
    planner_blocks: Option<u32>,
    grblhal: bool,
    last_status: Option<Status>,
    wco: [f64; 3],
    last_poll: Option<Instant>,
    waiting_status: bool,
    last_alarm: Option<u8>,
    flight: Flight,
}

impl Drop for Sender {
    fn drop(&mut self) {
        if let Some(socket) = &self.socket {
            let _ = socket.shutdown(std::net::Shutdown::Both);
        }
    }
}

impl std::fmt::Debug for Sender {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Sender").field("rx_buffer", &self.rx_buffer).field("grblhal", &self.grblhal).finish()
    }
}

/// Sends real-time bytes from another thread (a Ctrl-C handler).
#[derive(Clone)]
pub struct Control {
    writer: SharedWriter,
}

impl std::fmt::Debug for Control {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Control")
    }
}

impl Control {
    /// `!`: feed hold, the machine brakes to a stop on its path.
    pub fn feed_hold(&self) -> io::Result<()> {
        connection::send(&self.writer, b"!")
    }

    /// `~`: resume after a feed hold or M0.
    pub fn resume(&self) -> io::Result<()> {
        connection::send(&self.writer, b"~")
    }

    /// 0x18: soft reset; in motion the controller raises `ALARM:3` and loses its position.
    pub fn soft_reset(&self) -> io::Result<()> {
        connection::send(&self.writer, &[0x18])
    }
}

impl Sender {
    /// Connects and asks `$I` for the receive buffer (128 bytes when the firmware does not say).
    pub fn connect(port: &str, options: &SenderOptions) -> Result<Self, StreamError> {
        let (writer, events, socket) = connection::open(port, options.baud)
            .map_err(|source| StreamError::Open { port: port.to_string(), source })?;
        let mut sender = Self {
            writer,
            events,
            socket,
            options: SenderOptions { poll: options.poll.max(MIN_POLL), ..options.clone() },
            rx_buffer: 128,
            planner_blocks: None,
            grblhal: false,
            last_status: None,
            wco: [0.0; 3],
            last_poll: None,
            waiting_status: false,
            last_alarm: None,
            flight: Flight::new(),
        };
        // A controller that has just been reset greets us; wait briefly for that before asking.
        let deadline = Instant::now() + Duration::from_millis(300);
        while let Some(left) = deadline.checked_duration_since(Instant::now()) {
            match sender.events.recv_timeout(left) {
                Ok(Event::Line(l)) => {
                    if let Ok(Response::Welcome { grblhal, .. }) = parse_line(&l) {
                        sender.grblhal = grblhal;
                        break;
                    }
                }
                Ok(Event::Closed(reason)) => return Err(StreamError::ConnectionLost { reason, reached: None }),
                Err(_) => break,
            }
        }
        for text in sender.command("$I")? {
            if let Some(opt) = text.strip_prefix("OPT:") {
                let fields: Vec<&str> = opt.split(',').collect();
                if let Some(rx) = fields.get(2).and_then(|s| s.parse::<usize>().ok()).filter(|&n| n >= 16) {
                    sender.rx_buffer = rx;
                }
                sender.planner_blocks = fields.get(1).and_then(|s| s.parse().ok());
            }
            if text == "FIRMWARE:grblHAL" {
                sender.grblhal = true;
            }
        }
        if sender.grblhal {
            // grblHAL's receive ring keeps one slot free: it holds one byte less than `$I`
            // says (its `Bf:` shows 1023 of 1024), and a byte that finds it full is lost.
            sender.rx_buffer -= 1;
        }
        Ok(sender)
    }

    /// The controller's receive buffer (bytes) used for character counting: as `$I` reports
    /// it, one less on grblHAL.
    pub fn rx_buffer(&self) -> usize {
        self.rx_buffer
    }

    /// Planner blocks as `$I` reported them, if it did.
    pub fn planner_blocks(&self) -> Option<u32> {
        self.planner_blocks
    }

    /// Whether the controller is grblHAL.
    pub fn is_grblhal(&self) -> bool {
        self.grblhal
    }

    /// A handle for real-time bytes from another thread.
    pub fn control(&self) -> Control {
        Control { writer: self.writer.clone() }
    }

    /// The work offset from the last report that carried `WCO` (mm).
    pub fn wco(&self) -> [f64; 3] {
        self.wco
    }

    /// The code of the last `ALARM:N` the controller printed, if any.
    pub fn last_alarm(&self) -> Option<u8> {
        self.last_alarm
    }

    /// The last status report read.
    pub fn last_status(&self) -> Option<&Status> {
        self.last_status.as_ref()
    }

    fn write(&self, bytes: &[u8]) -> Result<(), StreamError> {
        connection::send(&self.writer, bytes).map_err(StreamError::Write)
    }

    fn poll_if_due(&mut self) -> Result<(), StreamError> {
        let due = self.last_poll.is_none_or(|t| t.elapsed() >= self.options.poll);
        if due && !self.waiting_status {
            self.write(b"?")?;
            let now = Instant::now();
            self.last_poll = Some(now);
            self.flight.asked_since.get_or_insert(now);
            self.waiting_status = true;
        } else if self.waiting_status && self.last_poll.is_some_and(|t| t.elapsed() >= self.options.poll * 5) {
            // A report lost to a reset: ask again.
            self.waiting_status = false;
        }
        Ok(())
    }

    fn note_status(&mut self, status: Status) {
        if let Some(w) = status.wco {
            self.wco = w;
        }
        self.waiting_status = false;
        self.last_status = Some(status);
    }

    /// Waits for the next line; `Ok(None)` on timeout.
    fn next(&mut self, wait: Duration) -> Result<Option<Response>, StreamError> {
        match self.events.recv_timeout(wait) {
            Ok(Event::Line(l)) => {
                self.flight.asked_since = None;
                let r = parse_line(&l).ok();
                if let Some(Response::Alarm(code)) = r {
                    self.last_alarm = Some(code);
                }
                Ok(r)
            }
            Ok(Event::Closed(reason)) => Err(StreamError::ConnectionLost { reason, reached: None }),
            Err(RecvTimeoutError::Timeout) => Ok(None),
            Err(RecvTimeoutError::Disconnected) => {
                Err(StreamError::ConnectionLost { reason: "reader stopped".into(), reached: None })
            }
        }
    }

    /// Sends one line and waits for its `ok`; returns the feedback lines (`[…]` contents and
    /// others) it printed first. Lines pushed before are finished first.
    pub fn command(&mut self, line: &str) -> Result<Vec<String>, StreamError> {
        if self.flight.in_flight() > 0 {
            self.finish()?;
        }
        self.write(format!("{}\n", line.trim_end()).as_bytes())?;
        let deadline = Instant::now() + self.options.timeout;
        let mut text = Vec::new();
        loop {
            let left =
                deadline.checked_duration_since(Instant::now()).ok_or(StreamError::Timeout(self.options.timeout))?;
            match self.next(left.min(Duration::from_millis(50)))? {
                Some(Response::Ok) => return Ok(text),
                Some(Response::Error(code)) => {
                    return Err(StreamError::Firmware { index: 0, text: line.to_string(), code, in_flight: 0 })
                }
                Some(Response::Alarm(code)) => return Err(StreamError::Alarm { code, reached: None }),
                Some(Response::Status(s)) => self.note_status(s),
                Some(Response::Feedback(f)) => text.push(f),
                Some(Response::Other(o)) => text.push(o),
                Some(Response::Welcome { grblhal, .. }) => self.grblhal = grblhal,
                None => {}
            }
        }
    }

    /// grblHAL: clears a latched error (an empty line answers `ok` and resets it). On any
    /// controller it also ends a stop, so pushing can start again.
    pub fn unlatch(&mut self) -> Result<(), StreamError> {
        self.command("")?;
        self.flight.stopped = None;
        Ok(())
    }

    /// Polls until a status report arrives. Answers to pushed lines read meanwhile are
    /// accounted for, so it may return their error.
    pub fn status(&mut self) -> Result<Status, StreamError> {
        // Reports already on their way answer an earlier poll: read past them.
        while self.pump(Duration::ZERO, false)?.is_some() {}
        self.waiting_status = false;
        self.last_poll = None;
        let deadline = Instant::now() + self.options.timeout;
        loop {
            self.poll_if_due()?;
            let left =
                deadline.checked_duration_since(Instant::now()).ok_or(StreamError::Timeout(self.options.timeout))?;
            if let Some(Response::Status(s)) = self.pump(left.min(Duration::from_millis(20)), false)? {
                return Ok(s);
            }
        }
    }

    /// Polls at 5 Hz until the controller reports `Idle`.
    pub fn wait_idle(&mut self, timeout: Duration) -> Result<Status, StreamError> {
        let deadline = Instant::now() + timeout;
        loop {
            let s = self.status()?;
            if s.state == Some(MachineState::Idle) {
                return Ok(s);
            }
            if s.state == Some(MachineState::Alarm) {
                return Err(StreamError::Alarm { code: self.last_alarm.unwrap_or(0), reached: None });
            }
            if Instant::now() >= deadline {
                return Err(StreamError::Timeout(timeout));
            }
            std::thread::sleep(self.options.poll.saturating_sub(Duration::from_millis(20)));
        }
    }

    /// Pushes every line and finishes: a whole program, so it first ends an earlier stop.
    /// Indexes in its errors count within `lines`; the report holds the totals since connect.
    pub fn stream<S: AsRef<str>>(&mut self, lines: &[S]) -> Result<StreamReport, StreamError> {
        self.flight.stopped = None;
        let base = self.flight.pushed();
        for line in lines {
            self.push(line.as_ref()).map_err(|e| streaming::rebase(e, base))?;
        }
        self.finish().map_err(|e| streaming::rebase(e, base))
    }
}
