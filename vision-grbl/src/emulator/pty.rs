//! The emulator on a pseudo-terminal, so a sender opens it like a USB serial port.

use std::ffi::CStr;
use std::fs::File;
use std::io;
use std::os::fd::{FromRawFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::thread::{self, JoinHandle};

use super::{serve, EmulatorConfig};

/// An emulator behind a pseudo-terminal; one controller for as long as it lives.
#[derive(Debug)]
pub struct PtyEmulator {
    path: PathBuf,
    // Holding the terminal side open keeps the pty usable across clients (no EIO between them).
    _slave: File,
    _thread: JoinHandle<()>,
}

fn check(rc: libc::c_int) -> io::Result<libc::c_int> {
    if rc < 0 {
        Err(io::Error::last_os_error())
    } else {
        Ok(rc)
    }
}

/// Puts a terminal in raw mode: no echo, no line editing, no CR/LF translation.
pub(crate) fn make_raw(fd: libc::c_int, baud: Option<libc::speed_t>) -> io::Result<()> {
    // SAFETY: `termios` is plain data; tcgetattr fills it before any use.
    let mut t: libc::termios = unsafe { std::mem::zeroed() };
    // SAFETY: `fd` is an open descriptor owned by the caller; `t` is a valid termios.
    unsafe {
        check(libc::tcgetattr(fd, &mut t))?;
        libc::cfmakeraw(&mut t);
        if let Some(b) = baud {
            check(libc::cfsetispeed(&mut t, b))?;
            check(libc::cfsetospeed(&mut t, b))?;
        }
        check(libc::tcsetattr(fd, libc::TCSANOW, &t))?;
    }
    Ok(())
}

impl PtyEmulator {
    /// Opens a pseudo-terminal and serves the controller on it in a background thread.
    pub fn open(config: EmulatorConfig) -> io::Result<Self> {
        // SAFETY: plain libc calls on the descriptor posix_openpt returned; ptsname_r writes a
        // NUL-terminated path into `buf`, within its length.
        let (master, path) = unsafe {
            let fd = check(libc::posix_openpt(libc::O_RDWR | libc::O_NOCTTY))?;
            let master = OwnedFd::from_raw_fd(fd);
            check(libc::grantpt(fd))?;
            check(libc::unlockpt(fd))?;
            let mut buf = [0 as libc::c_char; 128];
            let rc = libc::ptsname_r(fd, buf.as_mut_ptr(), buf.len());
            if rc != 0 {
                return Err(io::Error::from_raw_os_error(rc));
            }
            let path = PathBuf::from(CStr::from_ptr(buf.as_ptr()).to_string_lossy().into_owned());
            (File::from(master), path)
        };
        let slave = File::options().read(true).write(true).open(&path)?;
        {
            use std::os::fd::AsRawFd;
            make_raw(slave.as_raw_fd(), None)?;
        }
        let reader = master.try_clone()?;
        let mut writer = master;
        let stop = Arc::new(AtomicBool::new(false));
        let thread = thread::spawn(move || {
            let _ = serve(reader, &mut writer, config, &stop);
        });
        Ok(Self { path, _slave: slave, _thread: thread })
    }

    /// The terminal device a sender opens, e.g. `/dev/pts/3`.
    pub fn path(&self) -> &Path {
        &self.path
    }
}
