//! The emulator's threads: one accepting connections, one serving the client of the moment.

use std::collections::VecDeque;
use std::io::{self, Read, Write};
use std::net::{Shutdown, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

use socket2::SockRef;

use super::camera::{refusal, Answer, Camera};
use super::source::Shot;
use super::{EmulatorStats, Fault};
use crate::protocol::{CR, LF, MAX_COMMAND_LEN};

/// How often a waiting connection thread looks at the shutdown flag and its peer.
const POLL: Duration = Duration::from_millis(2);
/// How long an idle connection thread blocks in one read.
const IDLE_READ: Duration = Duration::from_millis(50);
/// Pause between the bytes of a [`Fault::ByteByByte`] reply.
const BYTE_GAP: Duration = Duration::from_millis(1);

/// State shared by the handle and the threads.
pub(crate) struct Shared {
    pub(crate) camera: Mutex<Camera>,
    pub(crate) faults: Mutex<VecDeque<Fault>>,
    pub(crate) stats: Mutex<EmulatorStats>,
    pub(crate) shutdown: AtomicBool,
    /// The connected client, to cut it off from the handle.
    pub(crate) client: Mutex<Option<TcpStream>>,
}

/// Locks, ignoring poisoning (a panicking test thread must not wedge the emulator).
pub(crate) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

impl Shared {
    fn stopping(&self) -> bool {
        self.shutdown.load(Ordering::SeqCst)
    }
}

/// Accepts clients one at a time until shutdown. A client that arrives while another is
/// connected waits up to the handover grace for it to leave, then is reset (like a camera whose
/// only command socket is taken).
///
/// Clients queued behind a waiting one share its grace window: once it has passed, each of
/// them is reset at once, so none waits out the graces of the clients ahead of it (and times
/// out instead of learning that the camera is taken). The window closes when the queue is
/// empty or a client gets the camera.
pub(crate) fn accept_loop(listener: TcpListener, shared: Arc<Shared>) {
    let mut current: Option<JoinHandle<()>> = None;
    let mut window: Option<Instant> = None;
    loop {
        let queued = if window.is_some() { accept_queued(&listener) } else { None };
        if queued.is_none() {
            window = None;
        }
        let conn = match queued {
            Some(stream) => Ok(stream),
            None => listener.accept().map(|(stream, _)| stream),
        };
        if shared.stopping() {
            break;
        }
        let Ok(stream) = conn else { continue };
        let grace = lock(&shared.camera).settings.handover_grace;
        if let Some(h) = &current {
            let until = *window.get_or_insert_with(|| Instant::now() + grace);
            while !h.is_finished() && Instant::now() < until {
                thread::sleep(POLL);
            }
        }
        if current.as_ref().is_some_and(|h| !h.is_finished()) {
            lock(&shared.stats).rejected += 1;
            let _ = SockRef::from(&stream).set_linger(Some(Duration::ZERO));
            drop(stream);
            continue;
        }
        if let Some(h) = current.take() {
            let _ = h.join();
        }
        window = None;
        lock(&shared.stats).connections += 1;
        *lock(&shared.client) = stream.try_clone().ok();
        let s = Arc::clone(&shared);
        current = Some(thread::spawn(move || Connection::new(stream, s).serve()));
    }
    if let Some(c) = lock(&shared.client).take() {
        let _ = c.shutdown(Shutdown::Both);
    }
    if let Some(h) = current {
        let _ = h.join();
    }
}

/// A connection already waiting in the listen queue, without blocking.
fn accept_queued(listener: &TcpListener) -> Option<TcpStream> {
    listener.set_nonblocking(true).ok()?;
    let got = listener.accept();
    let blocking = listener.set_nonblocking(false);
    let (stream, _) = got.ok()?;
    blocking.ok()?;
    stream.set_nonblocking(false).ok()?;
    Some(stream)
}

/// One client's connection.
struct Connection {
    stream: TcpStream,
    shared: Arc<Shared>,
    read_timeout: Option<Duration>,
}

impl Connection {
    fn new(stream: TcpStream, shared: Arc<Shared>) -> Connection {
        let _ = stream.set_nodelay(true);
        Connection { stream, shared, read_timeout: None }
    }

    /// Reads commands (CR, LF or CRLF terminated) and answers them until the client leaves.
    fn serve(mut self) {
        let mut pending: Vec<u8> = Vec::with_capacity(MAX_COMMAND_LEN);
        let mut started: Option<Instant> = None;
        let mut overflow = false;
        let mut after_cr = false;
        let mut buf = [0u8; 1024];
        let command_timeout = lock(&self.shared.camera).settings.command_timeout;
        while !self.shared.stopping() {
            let wait = started.map_or(IDLE_READ, |t| (t + command_timeout).saturating_duration_since(Instant::now()));
            if self.set_read_timeout(wait.clamp(Duration::from_millis(1), IDLE_READ)).is_err() {
                break;
            }
            match self.stream.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => {
                    for &b in &buf[..n] {
                        if after_cr && b == LF {
                            after_cr = false;
                            continue;
                        }
                        after_cr = b == CR;
                        if b == CR || b == LF {
                            started = None;
                            let keep_going = if std::mem::take(&mut overflow) {
                                self.write_line(&refusal(&pending, 2)).is_ok()
                            } else {
                                self.command(&pending)
                            };
                            pending.clear();
                            if !keep_going {
                                return;
                            }
                        } else {
                            started.get_or_insert_with(Instant::now);
                            if pending.len() + 1 < MAX_COMMAND_LEN {
                                pending.push(b);
                            } else {
                                overflow = true;
                            }
                        }
                    }
                }
                Err(e) if matches!(e.kind(), io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut) => {
                    if started.is_some_and(|t| t.elapsed() >= command_timeout) {
                        started = None;
                        overflow = false;
                        let reply = refusal(&pending, 7);
                        pending.clear();
                        if self.write_line(&reply).is_err() {
                            break;
                        }
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(_) => break,
            }
        }
    }

    fn set_read_timeout(&mut self, t: Duration) -> io::Result<()> {
        if self.read_timeout != Some(t) {
            self.stream.set_read_timeout(Some(t))?;
            self.read_timeout = Some(t);
        }
        Ok(())
    }

    /// Answers one command; false when the connection is to be closed.
    fn command(&mut self, command: &[u8]) -> bool {
        let answer = lock(&self.shared.camera).handle(command, Instant::now());
        if !command.is_empty() {
            lock(&self.shared.stats).commands += 1;
        }
        match answer {
            Answer::Nothing => true,
            Answer::Line(l) => self.write_line(&l).is_ok(),
            Answer::Trigger(shot) => {
                lock(&self.shared.stats).triggers += 1;
                let fault = lock(&self.shared.faults).pop_front();
                self.trigger(shot, fault).is_ok()
            }
        }
    }

    fn delimiter(&self) -> &'static [u8] {
        lock(&self.shared.camera).settings.delimiter.bytes()
    }

    fn write_line(&mut self, line: &str) -> io::Result<()> {
        let mut bytes = line.as_bytes().to_vec();
        bytes.extend_from_slice(self.delimiter());
        self.stream.write_all(&bytes)
    }

    /// Writes the answer to an accepted `TRG`, shaped by `fault`. `Err` closes the connection.
    fn trigger(&mut self, shot: Shot, fault: Option<Fault>) -> io::Result<()> {
        // Faults that replace the answer: `Reject` and `Silence` are the shots of the same name;
        // `Garbage` and `LongLine` send the echo and a data line of raw bytes (possibly not
        // text, which a `Shot::Line` cannot carry). The other faults shape the delivery below.
        let raw = match &fault {
            Some(Fault::Garbage(bytes)) => Some(bytes.clone()),
            Some(Fault::LongLine(n)) => Some(vec![b'7'; *n]),
            _ => None,
        };
        let shot = match &fault {
            Some(Fault::Reject(code)) => Shot::Reject(*code),
            Some(Fault::Silence) => Shot::Silent,
            _ => shot,
        };
        let echo = || b"TRG".to_vec();
        let (mut lines, inspection) = {
            let camera = lock(&self.shared.camera);
            let lines = match (shot, raw) {
                (_, Some(bytes)) => vec![echo(), bytes],
                (Shot::Reject(code), None) => vec![format!("ER,TRG,{code:02}").into_bytes()],
                (Shot::Silent, None) => vec![echo()],
                (Shot::Line(line), None) => vec![echo(), line.into_bytes()],
                (Shot::Reading(r), None) => vec![echo(), camera.settings.data_line(&r).into_bytes()],
            };
            (lines, camera.settings.inspection_time)
        };
        let mut delim = self.delimiter();
        match &fault {
            None
            | Some(
                Fault::ByteByByte
                | Fault::OneSegment
                | Fault::Dribble(_)
                | Fault::Garbage(_)
                | Fault::LongLine(_)
                | Fault::Silence
                | Fault::Reject(_),
            ) => {}
            Some(Fault::Delay(d)) => {
                if !self.wait(*d) {
                    return Err(closed());
                }
            }
            Some(Fault::LateReply(d)) => {
                // Written after `d`, or at once when the client has gone first: it then lands
                // in the dead connection.
                self.wait(*d);
            }
            Some(Fault::Close) => return Err(closed()),
            Some(Fault::CloseAfterEcho) => {
                self.send(&[echo()], delim)?;
                return Err(closed());
            }
            Some(Fault::ManyLines(n)) => {
                let mut many = vec![b"1,0,0".to_vec(); *n];
                many.append(&mut lines);
                lines = many;
            }
            Some(Fault::StrayLf) => delim = b"\r\n",
        }
        let mut wire: Vec<Vec<u8>> = lines
            .into_iter()
            .map(|mut l| {
                l.extend_from_slice(delim);
                l
            })
            .collect();
        match fault {
            Some(Fault::OneSegment) => {
                self.pause(inspection);
                self.stream.write_all(&wire.concat())
            }
            Some(Fault::ByteByByte) => self.trickle(&wire.concat(), BYTE_GAP),
            Some(Fault::Dribble(gap)) => self.trickle(&wire.concat(), gap),
            Some(Fault::StrayLf) => {
                wire.push(b"\n".to_vec());
                self.send(&wire, b"")
            }
            _ => {
                let data = wire.split_off(wire.len().min(1));
                self.stream.write_all(&wire.concat())?;
                if !data.is_empty() {
                    self.pause(inspection);
                    self.stream.write_all(&data.concat())?;
                }
                Ok(())
            }
        }
    }

    /// Writes each line in its own write.
    fn send(&mut self, lines: &[Vec<u8>], delim: &[u8]) -> io::Result<()> {
        for l in lines {
            let mut bytes = l.clone();
            bytes.extend_from_slice(delim);
            self.stream.write_all(&bytes)?;
        }
        Ok(())
    }

    /// Writes `bytes` one per write, `gap` apart, until the client leaves.
    fn trickle(&mut self, bytes: &[u8], gap: Duration) -> io::Result<()> {
        for (i, b) in bytes.iter().enumerate() {
            if i > 0 && !self.wait(gap) {
                return Err(closed());
            }
            self.stream.write_all(std::slice::from_ref(b))?;
        }
        Ok(())
    }

    fn pause(&mut self, d: Duration) {
        if !d.is_zero() {
            self.wait(d);
        }
    }

    /// Waits `d`, returning early on shutdown or when the client has gone (any reply is then
    /// already later than the client's timeout). Returns whether the client is still there.
    fn wait(&mut self, d: Duration) -> bool {
        let until = Instant::now() + d;
        loop {
            let now = Instant::now();
            if now >= until || self.shared.stopping() {
                return true;
            }
            thread::sleep(POLL.min(until - now));
            if self.peer_gone() {
                return false;
            }
        }
    }

    /// True when the client has closed or reset the connection.
    fn peer_gone(&mut self) -> bool {
        if self.stream.set_nonblocking(true).is_err() {
            return true;
        }
        let mut probe = [0u8; 1];
        let gone = match self.stream.peek(&mut probe) {
            Ok(0) => true,
            Ok(_) => false,
            Err(e) => e.kind() != io::ErrorKind::WouldBlock,
        };
        self.stream.set_nonblocking(false).is_err() || gone
    }
}

impl Drop for Connection {
    /// Closes the connection for good: the handle's clone of the stream would otherwise keep it
    /// open.
    fn drop(&mut self) {
        let _ = self.stream.shutdown(Shutdown::Both);
        lock(&self.shared.client).take();
    }
}

fn closed() -> io::Error {
    io::Error::new(io::ErrorKind::ConnectionAborted, "closed by a fault")
}
