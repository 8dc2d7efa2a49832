//! The command/reply state machine over any `Read + Write`.
//!
//! An [`Exchange`] sends one command, then reads lines until the command's answer:
//!
//! * empty lines are skipped;
//! * `ER,<cmd>,<nn>` for the command sent is the answer (a [`KeyenceError::Rejected`]);
//! * for `TRG` the answer is the line after the `TRG` echo; lines before the echo answer no
//!   command of ours (a stale data output, an error for another command) and are ignored;
//! * for other commands the answer is the first line whose first field is the command's name;
//! * at most [`Limits::max_lines`] lines are read, each at most [`Limits::max_line_len`] bytes.
//!
//! A device that answers in another protocol (a web server's `HTTP/1.1 400`, an SSH banner,
//! binary) is told from a camera by the first line it sent: when the exchange fails and that
//! line is none a camera sends (the echo, `ER,…`, a reply to a command, a data line), the
//! failure is [`KeyenceError::NotKeyence`] with the first bytes it sent, escaped.
//!
//! Time is the stream's business: a read or write that fails with `TimedOut` or `WouldBlock`
//! becomes [`KeyenceError::Timeout`] (the socket transport turns its per-exchange deadline into
//! exactly that). After any error other than [`KeyenceError::Rejected`] the exchange's stream is
//! in an unknown state and must be dropped.

use std::io::{self, Read, Write};
use std::time::Duration;

use vision_core::Reading;

use super::framing::{FrameError, Limits, LineReader, CR};
use super::reply::{parse_data_line, parse_error_reply, parse_program, parse_version, quote, quote_bytes};
use crate::error::{KeyenceError, FIRST_BYTES_SHOWN};

/// Longest command the camera accepts, bytes, delimiter included (SPEC §7).
pub(crate) const MAX_COMMAND_LEN: usize = 500;

/// Highest camera job number.
pub(crate) const MAX_JOB: u32 = 999;

/// The command that switches jobs: `PL` on the VS series, `PW` on CV-X and IV.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum JobCommand {
    /// `PL,d,nnn` (VS series: program load).
    Pl,
    /// `PW,d,nnn` (CV-X and IV series: program write).
    Pw,
}

impl JobCommand {
    /// The command's name on the wire.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            JobCommand::Pl => "PL",
            JobCommand::Pw => "PW",
        }
    }
}

/// The camera's current program (job), as `PR` reports it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Program {
    /// Memory device: 1 (internal memory / SD 1) or 2 (SD card / SD 2).
    pub device: u8,
    /// Job number 0–999.
    pub job: u32,
}

/// What ends an exchange.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Want {
    /// The echo of the command, then one data line (`TRG`).
    EchoThenData,
    /// One line whose first field is the command's name.
    Answer,
}

/// One conversation with a camera over `stream`: framing, replies and the command state
/// machine, with no knowledge of sockets or clocks.
///
/// ```
/// use std::io::{self, Read, Write};
/// use std::time::Duration;
/// use vision_driver_keyence::{Limits, Exchange};
///
/// /// A camera that answers every command with the echo and one data line.
/// struct Canned(io::Cursor<&'static [u8]>);
/// impl Read for Canned {
///     fn read(&mut self, b: &mut [u8]) -> io::Result<usize> { self.0.read(b) }
/// }
/// impl Write for Canned {
///     fn write(&mut self, b: &[u8]) -> io::Result<usize> { Ok(b.len()) }
///     fn flush(&mut self) -> io::Result<()> { Ok(()) }
/// }
///
/// let camera = Canned(io::Cursor::new(b"TRG\r1,812.5,903.25\r"));
/// let mut exchange = Exchange::new(camera, Limits::default(), Duration::from_secs(3));
/// let reading = exchange.trigger()?;
/// assert_eq!((reading.x_px, reading.y_px), (812.5, 903.25));
/// # Ok::<(), vision_driver_keyence::KeyenceError>(())
/// ```
#[derive(Debug)]
pub struct Exchange<S> {
    stream: S,
    reader: LineReader,
    limits: Limits,
    timeout: Duration,
    written: usize,
    /// The peer's address, for messages.
    peer: String,
    /// The first bytes received since the last command was sent, and whether more came.
    heard: Vec<u8>,
    heard_more: bool,
    /// Whether a line a camera may send ([`camera_line`]) came since the last command.
    heard_camera: bool,
}

/// The stream, keeping the first [`FIRST_BYTES_SHOWN`] bytes read in `heard`.
struct Heard<'a, S> {
    stream: &'a mut S,
    heard: &'a mut Vec<u8>,
    more: &'a mut bool,
}

impl<S: Read> Read for Heard<'_, S> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.stream.read(buf)?;
        let room = FIRST_BYTES_SHOWN.saturating_sub(self.heard.len());
        self.heard.extend_from_slice(&buf[..n.min(room)]);
        *self.more |= n > room;
        Ok(n)
    }
}

impl<S: Read + Write> Exchange<S> {
    /// An exchange over `stream`. `timeout` is only quoted in messages: the stream enforces it.
    /// Out-of-range `limits` are clamped to [`Limits::validate`]'s bounds.
    #[must_use]
    pub fn new(stream: S, limits: Limits, timeout: Duration) -> Exchange<S> {
        let limits = limits.clamped();
        Exchange {
            stream,
            reader: LineReader::new(limits.max_line_len),
            limits,
            timeout,
            written: 0,
            peer: "the camera's address".into(),
            heard: Vec::new(),
            heard_more: false,
            heard_camera: false,
        }
    }

    /// Names the peer (`host:port`) in messages.
    pub fn set_peer(&mut self, addr: String) {
        self.peer = addr;
    }

    /// The stream.
    pub fn get_ref(&self) -> &S {
        &self.stream
    }

    /// The stream, mutably (the transport sets deadlines through it).
    pub fn get_mut(&mut self) -> &mut S {
        &mut self.stream
    }

    /// Gives the stream back.
    pub fn into_inner(self) -> S {
        self.stream
    }

    /// Command bytes the stream accepted since the last [`Exchange::reset_bytes_written`]. Zero
    /// after a failure means no byte of any command can have reached the camera.
    #[must_use]
    pub fn bytes_written(&self) -> usize {
        self.written
    }

    /// Restarts the [`Exchange::bytes_written`] count (e.g. before an exchange whose failure a
    /// caller wants to judge: zero bytes then means the camera cannot have seen it).
    pub fn reset_bytes_written(&mut self) {
        self.written = 0;
    }

    /// `TRG`: triggers one inspection and reads its Data Output line.
    ///
    /// # Errors
    /// Any [`KeyenceError`] of an exchange; `Malformed` when the data line is not one of the
    /// three formats of [`parse_data_line`].
    pub fn trigger(&mut self) -> Result<Reading, KeyenceError> {
        self.exchange("TRG", Want::EchoThenData, parse_data_line)
    }

    /// `FVR`: the camera's firmware version (a connection test).
    ///
    /// # Errors
    /// As [`Exchange::trigger`].
    pub fn version(&mut self) -> Result<String, KeyenceError> {
        self.exchange("FVR", Want::Answer, parse_version)
    }

    /// `PR`: the program (job) the camera runs.
    ///
    /// # Errors
    /// As [`Exchange::trigger`].
    pub fn program(&mut self) -> Result<Program, KeyenceError> {
        self.exchange("PR", Want::Answer, parse_program).map(|(device, job)| Program { device, job })
    }

    /// `PL,d,nnn` or `PW,d,nnn`: loads job `job` from memory device `device`.
    ///
    /// # Errors
    /// [`KeyenceError::InvalidJob`] or [`KeyenceError::Config`] (device not 1 or 2) before
    /// anything is sent, else as [`Exchange::trigger`].
    pub fn load_program(&mut self, command: JobCommand, device: u8, job: u32) -> Result<(), KeyenceError> {
        if job > MAX_JOB {
            return Err(KeyenceError::InvalidJob { job });
        }
        if !(1..=2).contains(&device) {
            return Err(KeyenceError::Config { reason: format!("memory device {device} must be 1 or 2") });
        }
        let name = command.name();
        let text = format!("{name},{device},{job:03}");
        self.exchange(&text, Want::Answer, |line| {
            if line == name {
                Ok(())
            } else {
                Err(format!("expected the bare {name} acknowledgement"))
            }
        })
    }

    /// Switches to job `job` on device `device` with `known` when the series' job command is
    /// already known, else `PL` first and `PW` when the camera answers `ER,PL,01`. Returns the
    /// command that worked, to pass as `known` next time.
    ///
    /// # Errors
    /// As [`Exchange::load_program`]; when both commands are unknown, the `PW` refusal with the
    /// `PL` one in [`KeyenceError::Rejected::previous`].
    pub fn select_job(&mut self, known: Option<JobCommand>, device: u8, job: u32) -> Result<JobCommand, KeyenceError> {
        if let Some(c) = known {
            return self.load_program(c, device, job).map(|()| c);
        }
        match self.load_program(JobCommand::Pl, device, job) {
            Ok(()) => Ok(JobCommand::Pl),
            Err(KeyenceError::Rejected { code, reply, .. }) if code == "01" => {
                match self.load_program(JobCommand::Pw, device, job) {
                    Ok(()) => Ok(JobCommand::Pw),
                    Err(KeyenceError::Rejected { command, code, reply: pw_reply, mut previous }) => {
                        previous.insert(0, reply);
                        Err(KeyenceError::Rejected { command, code, reply: pw_reply, previous })
                    }
                    Err(e) => Err(e),
                }
            }
            Err(e) => Err(e),
        }
    }

    /// Sends `command` and reads lines until its answer; a failure after a first line no
    /// camera sends is [`KeyenceError::NotKeyence`].
    fn exchange<T>(
        &mut self,
        command: &str,
        want: Want,
        accept: impl FnMut(&str) -> Result<T, String>,
    ) -> Result<T, KeyenceError> {
        let name = command.split(',').next().unwrap_or(command);
        self.exchange_lines(command, name, want, accept).map_err(|e| match e {
            // Not `TooManyLines`: a camera's stray lines may fill the bound before its echo.
            KeyenceError::Malformed { .. }
            | KeyenceError::Closed { .. }
            | KeyenceError::Timeout { .. }
            | KeyenceError::LineTooLong { .. }
                if !self.heard_camera && is_foreign(&self.heard) =>
            {
                let mut answered = quote_bytes(&self.heard);
                if self.heard_more {
                    answered.push('…');
                }
                KeyenceError::NotKeyence { addr: self.peer.clone(), command: name.to_string(), answered }
            }
            e => e,
        })
    }

    fn exchange_lines<T>(
        &mut self,
        command: &str,
        name: &str,
        want: Want,
        mut accept: impl FnMut(&str) -> Result<T, String>,
    ) -> Result<T, KeyenceError> {
        self.send(command, name)?;
        let mut echoed = false;
        let mut ignored: Option<String> = None;
        for _ in 0..self.limits.max_lines {
            let waiting = Waiting { name, want, echoed };
            let mut heard = Heard { stream: &mut self.stream, heard: &mut self.heard, more: &mut self.heard_more };
            let line = match self.reader.next_line(&mut heard) {
                Ok(l) => l,
                Err(e) => return Err(frame_error(e, waiting, self.timeout, self.limits, ignored)),
            };
            if line.is_empty() {
                continue;
            }
            let text = std::str::from_utf8(line);
            self.heard_camera |= text.is_ok_and(camera_line);
            let Ok(text) = text else {
                if want == Want::EchoThenData && echoed {
                    return Err(malformed(name, quote_bytes(line), "not text".into()));
                }
                ignored = Some(quote_bytes(line));
                continue;
            };
            match parse_error_reply(text) {
                Some(Ok(er)) if er.command == name => {
                    return Err(KeyenceError::Rejected {
                        command: name.to_string(),
                        code: er.code.to_string(),
                        reply: text.to_string(),
                        previous: Vec::new(),
                    });
                }
                Some(Err(reason)) if want == Want::Answer || echoed => {
                    return Err(malformed(name, quote(text), reason));
                }
                Some(_) => {
                    ignored = Some(quote(text));
                    continue;
                }
                None => {}
            }
            let ours = match want {
                Want::EchoThenData if !echoed => {
                    echoed = text == name;
                    false
                }
                Want::EchoThenData => true,
                Want::Answer => text.split(',').next() == Some(name),
            };
            if ours {
                return accept(text).map_err(|reason| malformed(name, quote(text), reason));
            }
            if !echoed {
                ignored = Some(quote(text));
            }
        }
        Err(KeyenceError::TooManyLines { command: name.to_string(), limit: self.limits.max_lines })
    }

    /// Writes `command` and its CR, counting accepted bytes, then flushes. Bytes received but
    /// not yet read as lines are forgotten first: they answer no command of ours.
    fn send(&mut self, command: &str, name: &str) -> Result<(), KeyenceError> {
        self.reader.discard();
        self.heard.clear();
        self.heard_more = false;
        self.heard_camera = false;
        let mut buf = [0u8; MAX_COMMAND_LEN];
        let len = command.len() + 1;
        if len > MAX_COMMAND_LEN {
            return Err(KeyenceError::Config {
                reason: format!("command {name} is {len} bytes; the camera accepts at most {MAX_COMMAND_LEN}"),
            });
        }
        buf[..command.len()].copy_from_slice(command.as_bytes());
        buf[command.len()] = CR;
        let mut off = 0;
        let sending = "the camera to accept the command";
        while off < len {
            match self.stream.write(&buf[off..len]) {
                Ok(0) => {
                    return Err(KeyenceError::Closed { command: name.to_string(), waiting_for: sending.into() });
                }
                Ok(n) => {
                    let n = n.min(len - off);
                    off += n;
                    self.written += n;
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(io_error(e, name, sending.into(), false, self.timeout, None)),
            }
        }
        self.stream.flush().map_err(|e| io_error(e, name, sending.into(), false, self.timeout, None))
    }
}

/// True for a line a camera may send: its echo of a command, an `ER,…` refusal, a reply or a
/// data output (comma-separated fields, or one number).
fn camera_line(text: &str) -> bool {
    let commands = ["TRG", "FVR", "PR", "PL", "PW", "ER"];
    let field = text.split(',').next().unwrap_or_default();
    commands.contains(&field) || text.contains(',') || text.trim().parse::<f64>().is_ok()
}

/// True when the first line in `heard` (complete or not) is none a camera sends. Nothing heard
/// is not foreign: a silent peer may be a camera.
fn is_foreign(heard: &[u8]) -> bool {
    let first = heard.split(|&b| b == CR || b == b'\n').find(|line| !line.is_empty());
    let Some(first) = first else { return false };
    std::str::from_utf8(first).map_or(true, |text| !camera_line(text))
}

/// Where an exchange stood, for messages.
#[derive(Clone, Copy)]
struct Waiting<'a> {
    name: &'a str,
    want: Want,
    echoed: bool,
}

impl Waiting<'_> {
    fn describe(self) -> String {
        match (self.want, self.echoed) {
            (Want::EchoThenData, false) => format!("the {} echo", self.name),
            (Want::EchoThenData, true) => format!("the data line (the {} echo arrived)", self.name),
            (Want::Answer, _) => format!("the {} reply", self.name),
        }
    }
}

fn malformed(name: &str, line: String, reason: String) -> KeyenceError {
    KeyenceError::Malformed { command: name.to_string(), line, reason }
}

fn frame_error(
    e: FrameError,
    at: Waiting<'_>,
    timeout: Duration,
    limits: Limits,
    ignored: Option<String>,
) -> KeyenceError {
    match e {
        FrameError::TooLong => KeyenceError::LineTooLong { command: at.name.to_string(), limit: limits.max_line_len },
        FrameError::Eof => closed(at.name, at.describe(), at.echoed, ignored),
        FrameError::Io(e) => io_error(e, at.name, at.describe(), at.echoed, timeout, ignored),
    }
}

/// The camera closed the connection while `waiting_for`. When, before any echo, it had sent a
/// line that answered nothing (`ER,TRG,6`, `TRG,<payload>` in place of the echo), that line is
/// the cause, quoted: a camera that closes after a reply it should not have sent is not one
/// another client holds. (A stray line before an echo that did come is only a stale output.)
fn closed(name: &str, waiting_for: String, echoed: bool, ignored: Option<String>) -> KeyenceError {
    match ignored.filter(|_| !echoed) {
        Some(line) => malformed(name, line, format!("then the camera closed the connection; {waiting_for} never came")),
        None => KeyenceError::Closed { command: name.to_string(), waiting_for },
    }
}

fn io_error(
    e: io::Error,
    name: &str,
    waiting_for: String,
    echoed: bool,
    timeout: Duration,
    ignored: Option<String>,
) -> KeyenceError {
    use io::ErrorKind as K;
    match e.kind() {
        K::TimedOut | K::WouldBlock => {
            KeyenceError::Timeout { command: name.to_string(), timeout, waiting_for, echoed, ignored }
        }
        K::ConnectionReset | K::ConnectionAborted | K::BrokenPipe | K::UnexpectedEof | K::NotConnected => {
            closed(name, waiting_for, echoed, ignored)
        }
        kind => KeyenceError::Io { command: name.to_string(), kind, message: e.to_string() },
    }
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::super::generate::{data_line, DataLine};
    use super::super::mock::{bytewise, Script, Step};
    use super::*;
    use proptest::prelude::*;
    use vision_core::Judgment;

    const T: Duration = Duration::from_millis(300);

    fn exchange(steps: Vec<Step>) -> Exchange<Script> {
        Exchange::new(Script::new(steps), Limits::default(), T)
    }

    fn trg(reply: &[u8]) -> Vec<Step> {
        vec![Step::write(b"TRG\r"), Step::read(reply)]
    }

    #[test]
    fn trigger_in_every_format() {
        for (reply, judgment, count, x, y) in [
            (&b"TRG\r150.0,75.5\r"[..], Judgment::Unknown, None, 150.0, 75.5),
            (b"TRG\r1,150,75\r", Judgment::Ok, None, 150.0, 75.0),
            (b"TRG\rOK,150,75\r", Judgment::Ok, None, 150.0, 75.0),
            (b"TRG\rNG,150,75\r", Judgment::Ng, None, 150.0, 75.0),
            (b"TRG\r0,150,75\r", Judgment::Ng, None, 150.0, 75.0),
            (b"TRG\r1,1,888.123,-12.5,40,40,0,99\r", Judgment::Ok, Some(1), 888.123, -12.5),
            (b"TRG\r1,0,0,0,0,0,0,0\r", Judgment::Ok, Some(0), 0.0, 0.0),
            (
                b"TRG\r+0000000001.000000,+0000000002.000000,+0000000888.123000,-0000000012.500000,\
                  +0000000040.000000,+0000000040.000000,+0000000000.000000,+0000000099.000000\r",
                Judgment::Ok,
                Some(2),
                888.123,
                -12.5,
            ),
            (b"TRG\r\n1,150,75\r\n", Judgment::Ok, None, 150.0, 75.0),
            (b"TRG\n1,150,75\n", Judgment::Ok, None, 150.0, 75.0),
        ] {
            let mut s = exchange(trg(reply));
            let r = s.trigger().expect("reading");
            assert_eq!((r.judgment, r.count, r.x_px, r.y_px), (judgment, count, x, y));
            assert_eq!(s.bytes_written(), 4);
            s.into_inner().done();
        }
    }

    #[test]
    fn echo_and_data_split_any_way() {
        let mut steps = vec![Step::write(b"TRG\r")];
        steps.extend(bytewise(b"TRG\r1,2.5,3.5\r"));
        let mut s = exchange(steps);
        assert_eq!(s.trigger().expect("bytewise").x_px, 2.5);
        s.into_inner().done();
    }

    #[test]
    fn lines_before_the_echo_answer_nothing() {
        // A stale data output and an error for another command arrive before our echo.
        let mut s = exchange(trg(b"1,9,9\rER,PL,03\r\rTRG\r1,2,3\r"));
        let r = s.trigger().expect("reading");
        assert_eq!((r.x_px, r.y_px), (2.0, 3.0));
        s.into_inner().done();
    }

    #[test]
    fn rejection_is_typed_and_keeps_the_raw_reply() {
        for code in ["01", "02", "03", "04", "05", "06", "07"] {
            let reply = format!("ER,TRG,{code}\r");
            let mut s = exchange(trg(reply.as_bytes()));
            let e = s.trigger().expect_err("rejected");
            assert_eq!(
                e,
                KeyenceError::Rejected {
                    command: "TRG".into(),
                    code: code.into(),
                    reply: format!("ER,TRG,{code}"),
                    previous: Vec::new(),
                }
            );
            s.into_inner().done();
        }
        let mut s = exchange(trg(b"TRG\rER,TRG,07\r"));
        assert_eq!(s.trigger().expect_err("after echo").code(), Some("07"));
    }

    #[test]
    fn timeout_says_what_was_missing() {
        let mut s = exchange(vec![Step::write(b"TRG\r"), Step::ReadErr(io::ErrorKind::WouldBlock)]);
        match s.trigger() {
            Err(KeyenceError::Timeout { waiting_for, timeout, echoed, .. }) => {
                assert_eq!(waiting_for, "the TRG echo");
                assert!(!echoed);
                assert_eq!(timeout, T);
            }
            other => panic!("{other:?}"),
        }
        let mut s =
            exchange(vec![Step::write(b"TRG\r"), Step::read(b"7,7\rTRG\r"), Step::ReadErr(io::ErrorKind::TimedOut)]);
        match s.trigger() {
            Err(KeyenceError::Timeout { waiting_for, ignored, echoed, .. }) => {
                assert_eq!(waiting_for, "the data line (the TRG echo arrived)");
                assert!(echoed);
                assert_eq!(ignored.as_deref(), Some("7,7"));
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn closed_reset_and_other_io() {
        let mut s = exchange(trg(b"TRG\r"));
        assert!(matches!(s.trigger(), Err(KeyenceError::Closed { .. })));
        let mut s = exchange(vec![Step::write(b"TRG\r"), Step::ReadErr(io::ErrorKind::ConnectionReset)]);
        assert!(matches!(s.trigger(), Err(KeyenceError::Closed { .. })));
        let mut s = exchange(vec![Step::write(b"TRG\r"), Step::ReadErr(io::ErrorKind::PermissionDenied)]);
        assert!(matches!(s.trigger(), Err(KeyenceError::Io { kind: io::ErrorKind::PermissionDenied, .. })));
    }

    /// A line that answers nothing, then a close: the line is the cause, quoted, in the
    /// manual's words (not "another client holds the socket").
    #[test]
    fn a_malformed_reply_then_a_close_quotes_the_reply() {
        for (reply, end) in [
            (&b"ER,TRG,6\r"[..], None),
            (&b"TRG,1,2,3\r"[..], None),
            (&b"RT,xyz\r"[..], Some(io::ErrorKind::ConnectionReset)),
        ] {
            let mut steps = trg(reply);
            if let Some(kind) = end {
                steps.push(Step::ReadErr(kind));
            }
            let mut s = exchange(steps);
            let e = s.trigger().expect_err("closed");
            let KeyenceError::Malformed { line, .. } = &e else { panic!("{e:?}") };
            assert_eq!(line.as_bytes(), &reply[..reply.len() - 1]);
            let text = e.to_string();
            assert!(text.starts_with("Malformed response: reply to TRG not understood"), "{text}");
            assert!(text.contains("then the camera closed the connection") && text.contains(line.as_str()), "{text}");
            assert!(!text.contains("another client"), "{text}");
        }
    }

    #[test]
    fn write_failures_count_bytes() {
        let mut s = exchange(vec![Step::WriteErr(io::ErrorKind::BrokenPipe)]);
        assert!(matches!(s.trigger(), Err(KeyenceError::Closed { .. })));
        assert_eq!(s.bytes_written(), 0);
        s.into_inner().done();
        let mut s = exchange(vec![Step::write(b"TR"), Step::WriteErr(io::ErrorKind::TimedOut)]);
        assert!(matches!(s.trigger(), Err(KeyenceError::Timeout { .. })));
        assert_eq!(s.bytes_written(), 2);
    }

    #[test]
    fn garbage_data_line_is_malformed() {
        let mut s = exchange(trg(b"TRG\r#garbage#\r"));
        match s.trigger() {
            Err(KeyenceError::Malformed { command, line, .. }) => {
                assert_eq!((command.as_str(), line.as_str()), ("TRG", "#garbage#"));
            }
            other => panic!("{other:?}"),
        }
        let mut s = exchange(trg(b"TRG\r\xff\xfe\r"));
        assert!(matches!(s.trigger(), Err(KeyenceError::Malformed { line, .. }) if line == "\\xff\\xfe"));
        let mut s = exchange(trg(b"TRG\rER,TRG\r"));
        assert!(matches!(s.trigger(), Err(KeyenceError::Malformed { .. })));
    }

    #[test]
    fn hostile_peers_hit_the_bounds() {
        let mut s = exchange(trg(&[b'7'; 2000]));
        assert_eq!(s.trigger(), Err(KeyenceError::LineTooLong { command: "TRG".into(), limit: 512 }));
        let mut s = exchange(trg(b"x\rx\rx\rx\rx\rx\rx\rx\rTRG\r1,2\r"));
        assert_eq!(s.trigger(), Err(KeyenceError::TooManyLines { command: "TRG".into(), limit: 8 }));
        let mut s = exchange(trg(b"\r\r\r\r\r\r\r\r\r\r\r\r"));
        assert!(matches!(s.trigger(), Err(KeyenceError::TooManyLines { .. })));
    }

    #[test]
    fn a_stray_lf_never_shifts_replies() {
        // The first reply's CRLF is split: the LF arrives only with the second reply.
        let mut steps = trg(b"TRG\r1,1,1\r");
        steps.extend([
            Step::write(b"TRG\r"),
            Step::read(b"\nTRG\r\n1,2,2\r\n"),
            Step::write(b"TRG\r"),
            Step::read(b"\n\nTRG\r1,3,3\r"),
        ]);
        let mut s = exchange(steps);
        for want in [1.0, 2.0, 3.0] {
            assert_eq!(s.trigger().expect("reading").x_px, want);
        }
        s.into_inner().done();
    }

    #[test]
    fn leftover_bytes_are_stale() {
        let mut steps = trg(b"TRG\r1,1,1\r9,9");
        steps.extend(trg(b"TRG\r1,2,2\r"));
        let mut s = exchange(steps);
        assert_eq!(s.trigger().expect("first").x_px, 1.0);
        assert_eq!(s.trigger().expect("second").x_px, 2.0);
        s.into_inner().done();
    }

    #[test]
    fn version_and_program() {
        let mut s = exchange(vec![
            Step::write(b"FVR\r"),
            Step::read(b"FVR,1.20.0001\r"),
            Step::write(b"PR\r"),
            Step::read(b"TRG\rPR,2,017\r"),
        ]);
        assert_eq!(s.version().expect("version"), "1.20.0001");
        assert_eq!(s.program().expect("program"), Program { device: 2, job: 17 });
        s.into_inner().done();
        let mut s = exchange(vec![Step::write(b"FVR\r"), Step::read(b"FVR\r")]);
        assert!(matches!(s.version(), Err(KeyenceError::Malformed { .. })));
    }

    #[test]
    fn an_unreadable_job_reply_speaks_of_job_switching() {
        let mut s = exchange(vec![Step::write(b"PR\r"), Step::read(b"PR,9\r")]);
        let e = s.program().expect_err("not PR,<device>,<job>");
        assert!(matches!(e, KeyenceError::Malformed { .. }), "{e:?}");
        let text = e.to_string();
        assert!(text.contains("job switching (M284)") && !text.contains("Data Output"), "{text}");
        let mut s = exchange(vec![Step::write(b"PL,1,005\r"), Step::read(b"PL,1\r")]);
        let text = s.load_program(JobCommand::Pl, 1, 5).expect_err("not a bare PL").to_string();
        assert!(text.contains("job switching (M284)") && !text.contains("Data Output"), "{text}");
        // A bare NG after the echo is a reading, not a broken reply.
        let mut s = exchange(trg(b"TRG\r0\r"));
        assert_eq!(s.trigger().expect("NG").judgment, Judgment::Ng);
    }

    #[test]
    fn job_switch_falls_back_from_pl_to_pw() {
        let mut s = exchange(vec![Step::write(b"PL,1,005\r"), Step::read(b"PL\r")]);
        assert_eq!(s.select_job(None, 1, 5), Ok(JobCommand::Pl));
        s.into_inner().done();

        let mut s = exchange(vec![
            Step::write(b"PL,2,042\r"),
            Step::read(b"ER,PL,01\r"),
            Step::write(b"PW,2,042\r"),
            Step::read(b"PW\r"),
            Step::write(b"PW,2,043\r"),
            Step::read(b"PW\r"),
        ]);
        assert_eq!(s.select_job(None, 2, 42), Ok(JobCommand::Pw));
        assert_eq!(s.select_job(Some(JobCommand::Pw), 2, 43), Ok(JobCommand::Pw));
        s.into_inner().done();

        let mut s = exchange(vec![
            Step::write(b"PL,1,005\r"),
            Step::read(b"ER,PL,01\r"),
            Step::write(b"PW,1,005\r"),
            Step::read(b"ER,PW,01\r"),
        ]);
        let e = s.select_job(None, 1, 5).expect_err("neither");
        assert_eq!(
            e,
            KeyenceError::Rejected {
                command: "PW".into(),
                code: "01".into(),
                reply: "ER,PW,01".into(),
                previous: vec!["ER,PL,01".into()],
            }
        );
        s.into_inner().done();

        // Any other refusal of PL is final: no PW is sent.
        let mut s = exchange(vec![Step::write(b"PL,1,999\r"), Step::read(b"ER,PL,03\r")]);
        assert_eq!(s.select_job(None, 1, 999).expect_err("range").code(), Some("03"));
        s.into_inner().done();
    }

    #[test]
    fn arguments_are_checked_before_sending() {
        let mut s = exchange(Vec::new());
        assert_eq!(s.select_job(None, 1, 1000), Err(KeyenceError::InvalidJob { job: 1000 }));
        assert!(matches!(s.load_program(JobCommand::Pl, 3, 1), Err(KeyenceError::Config { .. })));
        assert_eq!(s.bytes_written(), 0);
        s.into_inner().done();
    }

    /// What the camera sends after the lines that answer nothing.
    #[derive(Debug, Clone)]
    enum Answer {
        /// The echo, then a data line.
        Data(DataLine),
        /// `ER,TRG,<nn>` instead of the echo.
        Reject(u8),
        /// The echo, then the connection closes.
        EchoThenClose,
        /// Arbitrary bytes, after the echo or not.
        Bytes(bool, Vec<u8>),
    }

    fn answer() -> impl Strategy<Value = Answer> {
        let byte = prop_oneof![Just(b'\r'), Just(b'\n'), Just(b','), any::<u8>(), b'0'..=b'9'];
        prop_oneof![
            6 => data_line().prop_map(Answer::Data),
            1 => (1u8..=99).prop_map(Answer::Reject),
            1 => Just(Answer::EchoThenClose),
            2 => (any::<bool>(), proptest::collection::vec(byte, 0..1500)).prop_map(|(e, b)| Answer::Bytes(e, b)),
        ]
    }

    /// A line before the echo that answers no command of ours: empty, a stale data output, a
    /// reply to another command, a broken `ER`, or any printable text that is not `TRG`'s.
    fn stray_line() -> impl Strategy<Value = String> {
        prop_oneof![
            Just(String::new()),
            Just("1,9,9".to_string()),
            Just("ER,PL,03".to_string()),
            Just("PR,1,005".to_string()),
            Just("ER,TRG".to_string()),
            "[ -~]{1,40}".prop_filter("answers TRG", |l| l != "TRG" && !l.starts_with("ER,TRG,")),
        ]
    }

    fn delimiter() -> impl Strategy<Value = &'static [u8]> {
        prop_oneof![Just(&b"\r"[..]), Just(&b"\n"[..]), Just(&b"\r\n"[..])]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(400))]

        /// Stray lines, then the camera's answer, each line with any delimiter, delivered in
        /// arbitrary pieces: the exchange returns exactly what the answer says — the data line's
        /// reading (or its refusal), the rejection, the closed connection — or `TooManyLines`
        /// when the answer lies past the 8-line bound; arbitrary bytes never panic and anything
        /// accepted from them is finite. (Memory is bounded by construction: tests/alloc_bound.rs.)
        #[test]
        fn replies_read_as_the_camera_meant_them(
            strays in proptest::collection::vec((stray_line(), delimiter()), 0..9),
            answer in answer(),
            delims in (delimiter(), delimiter()),
            piece in 1usize..64,
        ) {
            let mut bytes = Vec::new();
            for (line, delim) in &strays {
                bytes.extend_from_slice(line.as_bytes());
                // An empty line ends in CR: a bare LF straight after a CR is part of that line end.
                bytes.extend_from_slice(if line.is_empty() { b"\r" } else { delim });
            }
            let mut line = |text: &[u8], delim: &[u8]| {
                bytes.extend_from_slice(text);
                bytes.extend_from_slice(delim);
            };
            match &answer {
                Answer::Data(data) => {
                    line(b"TRG", delims.0);
                    line(data.text.as_bytes(), delims.1);
                }
                Answer::Reject(code) => line(format!("ER,TRG,{code:02}").as_bytes(), delims.0),
                Answer::EchoThenClose => line(b"TRG", delims.0),
                Answer::Bytes(echo, tail) => {
                    if *echo {
                        line(b"TRG", delims.0);
                    }
                    line(tail, b"");
                }
            }
            let mut steps = vec![Step::write(b"TRG\r")];
            steps.extend(bytes.chunks(piece).map(Step::read));
            let got = exchange(steps).trigger();
            // Lines read when the answer is complete: the strays, then the echo and the data
            // line, the rejection, or the echo and the end of the stream.
            let needed = strays.len() + if matches!(answer, Answer::Reject(_)) { 1 } else { 2 };
            let too_many = KeyenceError::TooManyLines { command: "TRG".into(), limit: 8 };
            match (&answer, &got) {
                (Answer::Bytes(..), Ok(r)) => {
                    for v in [r.x_px, r.y_px, r.width_px, r.height_px, r.angle_deg, r.score] {
                        prop_assert!(v.is_finite());
                    }
                }
                (Answer::Bytes(..), Err(e)) => prop_assert!(e.to_string().len() < 1200, "{e}"),
                (_, got) if needed > 8 => prop_assert_eq!(got, &Err(too_many)),
                (Answer::Data(data), got) => match (&data.expected, got) {
                    (Some(want), Ok(r)) => prop_assert_eq!(r, want),
                    (None, Err(KeyenceError::Malformed { .. })) => {}
                    (want, got) => prop_assert!(false, "{}: got {got:?}, want {want:?}", data.text),
                },
                (Answer::Reject(code), Err(KeyenceError::Rejected { code: c, .. })) => {
                    prop_assert_eq!(c, &format!("{code:02}"));
                }
                (Answer::EchoThenClose, Err(KeyenceError::Closed { .. })) => {}
                (answer, got) => prop_assert!(false, "{answer:?}: got {got:?}"),
            }
        }
    }
}
