//! The byte link to a controller: TCP (`tcp://HOST:PORT`) or a serial device opened as a file
//! (raw mode and baud rate through termios on Unix), with a reader thread that splits lines.

use std::fs::File;
use std::io::{self, Read, Write};
use std::net::TcpStream;
use std::sync::mpsc::{self, Receiver};
use std::sync::{Arc, Mutex};
use std::thread;

/// What the reader thread hands over.
#[derive(Debug)]
pub(crate) enum Event {
    /// One line, without its line end.
    Line(Vec<u8>),
    /// The link closed or failed.
    Closed(String),
}

/// The writing half, shareable with another thread (feed hold from a Ctrl-C handler).
pub(crate) type SharedWriter = Arc<Mutex<Box<dyn Write + Send>>>;

/// The open link: the writing half, the reader thread's lines, and for TCP the socket, which
/// closing must shut down (the reader thread holds a clone of it, which would keep it open).
pub(crate) type Link = (SharedWriter, Receiver<Event>, Option<TcpStream>);

/// Opens `port`: `tcp://HOST:PORT`, or a device path. `baud` applies to terminals only.
pub(crate) fn open(port: &str, baud: Option<u32>) -> io::Result<Link> {
    let mut socket_kept = None;
    let (reader, writer): (Box<dyn Read + Send>, Box<dyn Write + Send>) =
        if let Some(addr) = port.strip_prefix("tcp://") {
            let socket = TcpStream::connect(addr)?;
            socket.set_nodelay(true)?;
            socket_kept = Some(socket.try_clone()?);
            (Box::new(socket.try_clone()?), Box::new(socket))
        } else {
            let file = File::options().read(true).write(true).open(port)?;
            configure_terminal(&file, baud)?;
            (Box::new(file.try_clone()?), Box::new(file))
        };
    let (tx, rx) = mpsc::channel();
    thread::spawn(move || {
        let mut reader = reader;
        let mut buf = [0u8; 4096];
        let mut line = Vec::new();
        loop {
            match reader.read(&mut buf) {
                Ok(0) => {
                    let _ = tx.send(Event::Closed("the controller closed the connection".into()));
                    return;
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => {
                    let _ = tx.send(Event::Closed(e.to_string()));
                    return;
                }
                Ok(n) => {
                    for &b in &buf[..n] {
                        if b == b'\n' || b == b'\r' {
                            if !line.is_empty() && tx.send(Event::Line(std::mem::take(&mut line))).is_err() {
                                return;
                            }
                        } else if line.len() < 4096 {
                            line.push(b);
                        }
                    }
                }
            }
        }
    });
    Ok((Arc::new(Mutex::new(writer)), rx, socket_kept))
}

#[cfg(unix)]
fn configure_terminal(file: &File, baud: Option<u32>) -> io::Result<()> {
    use std::os::fd::AsRawFd;
    // SAFETY: isatty only inspects the descriptor.
    if unsafe { libc::isatty(file.as_raw_fd()) } != 1 {
        return Ok(());
    }
    let speed = match baud {
        None => None,
        Some(9600) => Some(libc::B9600),
        Some(19200) => Some(libc::B19200),
        Some(38400) => Some(libc::B38400),
        Some(57600) => Some(libc::B57600),
        Some(115_200) => Some(libc::B115200),
        Some(230_400) => Some(libc::B230400),
        Some(other) => {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("baud rate {other} is not one of 9600, 19200, 38400, 57600, 115200, 230400"),
            ));
        }
    };
    crate::emulator::make_raw(file.as_raw_fd(), speed)
}

#[cfg(not(unix))]
fn configure_terminal(_file: &File, _baud: Option<u32>) -> io::Result<()> {
    Ok(())
}

/// Writes all of `bytes`.
pub(crate) fn send(writer: &SharedWriter, bytes: &[u8]) -> io::Result<()> {
    let mut w = writer.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    w.write_all(bytes)?;
    w.flush()
}
