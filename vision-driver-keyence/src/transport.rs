//! The socket edge: connect with socket2 (timeout, TCP_NODELAY, keepalive) and a stream whose
//! reads and writes fail with `TimedOut` once the call's deadline has passed.

use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::time::{Duration, Instant};

use socket2::{Domain, Protocol, Socket, TcpKeepalive, Type};

use crate::config::KeyenceConfig;
use crate::error::KeyenceError;

/// How far past the deadline one blocking read or write may run before its socket timeout is
/// set again (saves a system call per read on the fast path).
const SLACK: Duration = Duration::from_millis(5);
/// Stale bytes drained from an idle connection before it is given up as a flood.
const MAX_DRAIN: usize = 64 * 1024;

/// A connected camera socket with a per-call deadline.
#[derive(Debug)]
pub(crate) struct TcpLink {
    stream: TcpStream,
    deadline: Instant,
    /// The read and write timeouts currently set on the socket.
    timeouts: [Option<Duration>; 2],
}

impl TcpLink {
    /// Connects to the camera, trying each address `config.ip` resolves to, until `deadline`.
    pub(crate) fn connect(config: &KeyenceConfig, deadline: Instant) -> Result<TcpLink, KeyenceError> {
        let resolve = |reason: String| KeyenceError::Resolve { host: config.ip.clone(), port: config.port, reason };
        let addrs: Vec<SocketAddr> =
            (config.ip.as_str(), config.port).to_socket_addrs().map_err(|e| resolve(e.to_string()))?.collect();
        if addrs.is_empty() {
            return Err(resolve("no address".into()));
        }
        let mut last = None;
        for addr in addrs {
            let remaining = deadline.saturating_duration_since(Instant::now());
            if remaining.is_zero() {
                break;
            }
            match connect_one(addr, remaining, config) {
                Ok(stream) => return Ok(TcpLink { stream, deadline, timeouts: [None; 2] }),
                Err(e) => last = Some(e),
            }
        }
        Err(last.unwrap_or(KeyenceError::ConnectTimeout { addr: config.address(), timeout: config.timeout }))
    }

    /// Every read and write from now on must finish by `deadline`.
    ///
    /// The socket timeouts already set are kept: a later deadline only means a socket timeout
    /// may fire early, which [`Read::read`] treats as "wait again", so a steady stream of calls
    /// with the same timeout costs no system call for it.
    pub(crate) fn set_deadline(&mut self, deadline: Instant) {
        self.deadline = deadline;
    }

    /// Checks an idle connection before reuse: drains stale bytes (they answer no command) and
    /// returns false when the camera has closed or reset it, so the call can reconnect before
    /// anything is sent.
    pub(crate) fn idle_check(&mut self) -> bool {
        if self.stream.set_nonblocking(true).is_err() {
            return false;
        }
        let mut scratch = [0u8; 512];
        let mut drained = 0;
        let alive = loop {
            match self.stream.read(&mut scratch) {
                Ok(0) => break false,
                Ok(n) => {
                    drained += n;
                    if drained > MAX_DRAIN {
                        break false;
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break true,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(_) => break false,
            }
        };
        self.stream.set_nonblocking(false).is_ok() && alive
    }

    /// Time left before the deadline, or `TimedOut`.
    fn remaining(&self) -> io::Result<Duration> {
        let left = self.deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            Err(io::Error::new(io::ErrorKind::TimedOut, "the call's deadline has passed"))
        } else {
            Ok(left)
        }
    }
}

/// The socket timeout to set for an operation with `left` before the deadline, or `None` when
/// the one already set (`current`) cannot overrun the deadline by more than [`SLACK`].
fn timeout_update(current: Option<Duration>, left: Duration) -> Option<Duration> {
    match current {
        Some(t) if t <= left + SLACK => None,
        _ => Some(left.max(Duration::from_millis(1))),
    }
}

/// Which way a socket operation goes (indexes [`TcpLink::timeouts`]).
#[derive(Clone, Copy)]
enum Way {
    Read = 0,
    Write = 1,
}

impl TcpLink {
    /// Runs one blocking socket operation so that it ends by the deadline: sets the socket's
    /// timeout for `way` when the one in place could overrun it, and treats a socket timeout
    /// that fires early (set for an earlier deadline) as "wait again".
    fn bounded<T>(&mut self, way: Way, mut op: impl FnMut(&mut TcpStream) -> io::Result<T>) -> io::Result<T> {
        loop {
            let left = self.remaining()?;
            if let Some(t) = timeout_update(self.timeouts[way as usize], left) {
                match way {
                    Way::Read => self.stream.set_read_timeout(Some(t))?,
                    Way::Write => self.stream.set_write_timeout(Some(t))?,
                }
                self.timeouts[way as usize] = Some(t);
            }
            match op(&mut self.stream) {
                Err(e) if matches!(e.kind(), io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut) => {
                    self.remaining()?;
                    self.timeouts[way as usize] = None;
                }
                other => return other,
            }
        }
    }
}

impl Read for TcpLink {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        self.bounded(Way::Read, |s| s.read(buf))
    }
}

impl Write for TcpLink {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.bounded(Way::Write, |s| s.write(buf))
    }

    fn flush(&mut self) -> io::Result<()> {
        self.stream.flush()
    }
}

fn connect_one(addr: SocketAddr, timeout: Duration, config: &KeyenceConfig) -> Result<TcpStream, KeyenceError> {
    let at = addr.to_string();
    let io = |e: io::Error| KeyenceError::Io { command: "connect".into(), kind: e.kind(), message: e.to_string() };
    let socket = Socket::new(Domain::for_address(addr), Type::STREAM, Some(Protocol::TCP)).map_err(io)?;
    socket.set_nodelay(true).map_err(io)?;
    if let Some(idle) = config.keepalive {
        let keepalive = TcpKeepalive::new().with_time(idle);
        #[cfg(any(target_os = "linux", target_os = "macos", target_os = "windows"))]
        let keepalive = keepalive.with_interval(Duration::from_secs(2));
        #[cfg(any(target_os = "linux", target_os = "macos"))]
        let keepalive = keepalive.with_retries(3);
        socket.set_tcp_keepalive(&keepalive).map_err(io)?;
    }
    socket.connect_timeout(&addr.into(), timeout).map_err(|e| connect_error(&e, at, config.timeout))?;
    Ok(socket.into())
}

/// What a failed connect means: nothing listening, nothing answering, or — a reset — a camera
/// that took the connection and closed it (another client holds its only command socket).
fn connect_error(e: &io::Error, addr: String, timeout: Duration) -> KeyenceError {
    match e.kind() {
        io::ErrorKind::ConnectionRefused => KeyenceError::Refused { addr, reason: e.to_string() },
        io::ErrorKind::TimedOut | io::ErrorKind::WouldBlock => KeyenceError::ConnectTimeout { addr, timeout },
        io::ErrorKind::ConnectionReset | io::ErrorKind::ConnectionAborted | io::ErrorKind::UnexpectedEof => {
            KeyenceError::Closed { command: "connect".into(), waiting_for: addr }
        }
        _ => KeyenceError::Unreachable { addr, reason: e.to_string() },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn socket_timeouts_are_set_only_when_they_could_overrun() {
        let ms = Duration::from_millis;
        assert_eq!(timeout_update(None, ms(300)), Some(ms(300)));
        assert_eq!(timeout_update(Some(ms(300)), ms(299)), None);
        assert_eq!(timeout_update(Some(ms(300)), ms(290)), Some(ms(290)));
        assert_eq!(timeout_update(None, Duration::from_micros(10)), Some(ms(1)));
    }

    #[test]
    fn a_reset_while_connecting_is_a_closed_connection() {
        let at = || "127.0.0.1:8500".to_string();
        let t = Duration::from_secs(3);
        for kind in [io::ErrorKind::ConnectionReset, io::ErrorKind::ConnectionAborted] {
            let e = connect_error(&io::Error::from(kind), at(), t);
            assert!(matches!(e, KeyenceError::Closed { .. }), "{kind:?}: {e:?}");
            assert!(e.to_string().contains("another client probably holds"), "{e}");
        }
        let refused = connect_error(&io::Error::from(io::ErrorKind::ConnectionRefused), at(), t);
        assert!(matches!(refused, KeyenceError::Refused { .. }), "{refused:?}");
        let silent = connect_error(&io::Error::from(io::ErrorKind::TimedOut), at(), t);
        assert_eq!(silent, KeyenceError::ConnectTimeout { addr: at(), timeout: t });
    }
}
