//! Line framing of untrusted bytes: CR, LF and CRLF each end one line; memory is fixed.

use std::io::{self, Read};
use std::ops::RangeInclusive;

/// Carriage return, the Keyence delimiter.
pub(crate) const CR: u8 = b'\r';
/// Line feed, accepted as a delimiter too.
pub(crate) const LF: u8 = b'\n';

/// Bounds on what a peer may send, so a broken or hostile camera cannot grow memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Longest accepted line, bytes, without its delimiter (default 512: a Keyence command is at
    /// most 500 bytes, a full 8-field data line in fixed-width numbers about 160).
    pub max_line_len: usize,
    /// Most lines read for one reply, empty and ignored lines included (default 8, as the
    /// manual's client did).
    pub max_lines: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Limits { max_line_len: 512, max_lines: 8 }
    }
}

/// Usable [`Limits::max_line_len`], bytes.
const LINE_LEN: RangeInclusive<usize> = 16..=65_536;
/// Usable [`Limits::max_lines`].
const LINES: RangeInclusive<usize> = 2..=64;

impl Limits {
    /// Checks the bounds are usable: a line of 16 to 65 536 bytes, 2 to 64 lines.
    ///
    /// # Errors
    /// The reason, as text.
    pub fn validate(&self) -> Result<(), String> {
        if !LINE_LEN.contains(&self.max_line_len) {
            return Err(format!("max_line_len {} must be {LINE_LEN:?} bytes", self.max_line_len));
        }
        if !LINES.contains(&self.max_lines) {
            return Err(format!("max_lines {} must be {LINES:?}", self.max_lines));
        }
        Ok(())
    }

    /// These limits with each bound brought into the range [`Limits::validate`] accepts.
    pub(crate) fn clamped(self) -> Limits {
        Limits {
            max_line_len: self.max_line_len.clamp(*LINE_LEN.start(), *LINE_LEN.end()),
            max_lines: self.max_lines.clamp(*LINES.start(), *LINES.end()),
        }
    }
}

/// Extra room beyond one line, so every read can fetch at least this many bytes.
const READ_ROOM: usize = 512;

/// Why no line could be framed.
#[derive(Debug)]
pub(crate) enum FrameError {
    /// The pending line exceeds [`Limits::max_line_len`].
    TooLong,
    /// The peer closed the stream.
    Eof,
    /// The stream failed (timeouts arrive here as `TimedOut`/`WouldBlock`).
    Io(io::Error),
}

/// Frames lines out of a byte stream into one fixed buffer, allocated once.
///
/// A lone LF straight after a CR (a CRLF pair, even split across reads) is part of that line
/// end, never a line of its own; other empty lines are returned empty and the caller skips them.
pub(crate) struct LineReader {
    buf: Box<[u8]>,
    start: usize,
    end: usize,
    after_cr: bool,
    max_line_len: usize,
}

impl std::fmt::Debug for LineReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LineReader")
            .field("buffered", &(self.end - self.start))
            .field("after_cr", &self.after_cr)
            .field("max_line_len", &self.max_line_len)
            .finish()
    }
}

impl LineReader {
    pub(crate) fn new(max_line_len: usize) -> LineReader {
        LineReader {
            buf: vec![0; max_line_len + 1 + READ_ROOM].into_boxed_slice(),
            start: 0,
            end: 0,
            after_cr: false,
            max_line_len,
        }
    }

    /// Bytes of buffer this reader holds (fixed for its life).
    #[cfg(test)]
    pub(crate) fn capacity(&self) -> usize {
        self.buf.len()
    }

    /// Forgets bytes received but not yet framed (stale: they answer no command).
    pub(crate) fn discard(&mut self) {
        self.start = 0;
        self.end = 0;
    }

    /// The next line, without its delimiter.
    pub(crate) fn next_line<R: Read + ?Sized>(&mut self, r: &mut R) -> Result<&[u8], FrameError> {
        loop {
            if self.after_cr && self.start < self.end {
                if self.buf[self.start] == LF {
                    self.start += 1;
                }
                self.after_cr = false;
            }
            let pending = &self.buf[self.start..self.end];
            if let Some(pos) = pending.iter().position(|&b| b == CR || b == LF) {
                if pos > self.max_line_len {
                    self.discard();
                    return Err(FrameError::TooLong);
                }
                let line = self.start..self.start + pos;
                self.after_cr = self.buf[self.start + pos] == CR;
                self.start += pos + 1;
                return Ok(&self.buf[line]);
            }
            if pending.len() > self.max_line_len {
                self.discard();
                return Err(FrameError::TooLong);
            }
            if self.start > 0 {
                self.buf.copy_within(self.start..self.end, 0);
                self.end -= self.start;
                self.start = 0;
            }
            match r.read(&mut self.buf[self.end..]) {
                Ok(0) => return Err(FrameError::Eof),
                Ok(n) => self.end += n.min(self.buf.len() - self.end),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(FrameError::Io(e)),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hands out `data` in the given chunk sizes, then EOF.
    struct Chunks<'a> {
        data: &'a [u8],
        sizes: std::iter::Cycle<std::vec::IntoIter<usize>>,
    }

    impl Read for Chunks<'_> {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            let n = self.sizes.next().unwrap_or(1).max(1).min(self.data.len()).min(buf.len());
            buf[..n].copy_from_slice(&self.data[..n]);
            self.data = &self.data[n..];
            Ok(n)
        }
    }

    fn lines(data: &[u8], sizes: Vec<usize>) -> (Vec<String>, Option<FrameError>) {
        let mut r = Chunks { data, sizes: sizes.into_iter().cycle() };
        let mut lr = LineReader::new(16);
        let mut out = Vec::new();
        loop {
            match lr.next_line(&mut r) {
                Ok(l) => out.push(String::from_utf8_lossy(l).into_owned()),
                Err(e) => return (out, Some(e)),
            }
        }
    }

    #[test]
    fn cr_lf_and_crlf_each_end_one_line_whatever_the_split() {
        let data = b"TRG\r1,2\r\nA\nB\r\rC\r\n\n";
        for sizes in [vec![1], vec![2], vec![3, 1], vec![64]] {
            let (got, end) = lines(data, sizes.clone());
            assert_eq!(got, ["TRG", "1,2", "A", "B", "", "C", ""], "{sizes:?}");
            assert!(matches!(end, Some(FrameError::Eof)));
        }
    }

    #[test]
    fn a_line_past_the_bound_is_refused_without_growing() {
        let (got, end) = lines(b"0123456789abcdef\rx0123456789abcdefg\r", vec![5]);
        assert_eq!(got, ["0123456789abcdef"]);
        assert!(matches!(end, Some(FrameError::TooLong)));
        let (got, end) = lines(&[b'x'; 10_000], vec![700]);
        assert!(got.is_empty());
        assert!(matches!(end, Some(FrameError::TooLong)));
        assert_eq!(LineReader::new(16).capacity(), 16 + 1 + READ_ROOM);
    }

    #[test]
    fn limits_are_checked() {
        assert_eq!(Limits::default().validate(), Ok(()));
        assert!(Limits { max_line_len: 8, max_lines: 8 }.validate().is_err());
        assert!(Limits { max_line_len: 512, max_lines: 1 }.validate().is_err());
        assert_eq!(
            Limits { max_line_len: 8, max_lines: 1 }.validate(),
            Err("max_line_len 8 must be 16..=65536 bytes".into())
        );
        assert_eq!(Limits { max_line_len: 512, max_lines: 65 }.validate(), Err("max_lines 65 must be 2..=64".into()));
        // Clamping lands exactly on what validate accepts, and leaves usable limits alone.
        for (len, lines) in [(0, 0), (8, 1), (15, 2), (16, 64), (65_537, 65), (usize::MAX, usize::MAX)] {
            let clamped = Limits { max_line_len: len, max_lines: lines }.clamped();
            assert_eq!(clamped.validate(), Ok(()), "{clamped:?}");
        }
        assert_eq!(Limits { max_line_len: 1, max_lines: 100 }.clamped(), Limits { max_line_len: 16, max_lines: 64 });
        assert_eq!(Limits::default().clamped(), Limits::default());
    }
}
