//! Shared pieces of the Keyence benchmarks: the emulated camera, a raw client, and an
//! in-memory camera for the protocol cost alone.

use std::io::{self, Read, Write};

use vision_core::{Judgment, Reading};
use vision_driver_keyence::emulator::{Emulator, EmulatorHandle, ListSource};

/// [`FULL_LINE`] as a literal, so [`REPLY`] is built from the same text at compile time.
macro_rules! full_line {
    () => {
        "+0000000001.000000,+0000000001.000000,+0000000812.125000,+0000000903.500000,\
         +0000000040.250000,+0000000039.750000,-0000000012.500000,+0000000097.250000"
    };
}

/// The Data Output line the benchmarks' camera sends: the recommended 8-field format in
/// Keyence fixed-width numbers (the longest common line).
pub const FULL_LINE: &str = full_line!();

/// The reading [`FULL_LINE`] encodes.
#[must_use]
pub fn mark() -> Reading {
    Reading {
        judgment: Judgment::Ok,
        count: Some(1),
        x_px: 812.125,
        y_px: 903.5,
        width_px: 40.25,
        height_px: 39.75,
        angle_deg: -12.5,
        score: 97.25,
    }
}

/// An emulated VS camera on a free loopback port answering every `TRG` with [`mark`] in the
/// full fixed-width format (echo and data line in two writes, as a camera sends them).
///
/// # Panics
/// When no loopback port can be bound.
#[must_use]
pub fn camera() -> EmulatorHandle {
    Emulator::builder()
        .source(ListSource::readings([mark()]))
        .numbers(vision_driver_keyence::emulator::NumberStyle::FixedWidth)
        .bind("127.0.0.1:0")
        .expect("bind 127.0.0.1:0")
}

/// A raw client's trigger: writes `TRG\r`, reads until two CR-terminated lines (echo and data)
/// have arrived; returns the bytes read. No parsing, no deadline, no checks.
///
/// # Errors
/// The socket's.
pub fn raw_trigger(stream: &mut (impl Read + Write), buf: &mut [u8]) -> io::Result<usize> {
    stream.write_all(b"TRG\r")?;
    let mut got = 0;
    let mut lines = 0;
    while lines < 2 {
        let n = stream.read(&mut buf[got..])?;
        if n == 0 {
            return Err(io::ErrorKind::UnexpectedEof.into());
        }
        lines += buf[got..got + n].iter().filter(|&&b| b == b'\r').count();
        got += n;
    }
    Ok(got)
}

/// A camera in memory: every command written is answered with `TRG\r` and [`FULL_LINE`].
#[derive(Debug, Default)]
pub struct InMemoryCamera {
    /// Replies owed, in bytes still to read from the current one.
    owed: usize,
    at: usize,
}

/// What [`InMemoryCamera`] answers to each command: the echo, then [`FULL_LINE`].
const REPLY: &[u8] = concat!("TRG\r", full_line!(), "\r").as_bytes();

impl Read for InMemoryCamera {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if self.owed == 0 {
            return Err(io::ErrorKind::WouldBlock.into());
        }
        let n = buf.len().min(REPLY.len() - self.at);
        buf[..n].copy_from_slice(&REPLY[self.at..self.at + n]);
        self.at += n;
        if self.at == REPLY.len() {
            self.at = 0;
            self.owed -= 1;
        }
        Ok(n)
    }
}

impl Write for InMemoryCamera {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.owed += buf.iter().filter(|&&b| b == b'\r').count();
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}
