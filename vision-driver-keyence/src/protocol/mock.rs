//! A scripted byte exchange in the embedded-hal-mock style: expected writes, scripted reads,
//! injected errors, and [`Script::done`] to check nothing was left over.

use std::collections::VecDeque;
use std::io::{self, Read, Write};

/// One step of the script.
#[derive(Debug)]
pub(crate) enum Step {
    /// The client must write exactly these bytes (possibly over several `write` calls).
    Write(Vec<u8>),
    /// The next reads return these bytes (as many per read as fit).
    Read(Vec<u8>),
    /// The next read fails.
    ReadErr(io::ErrorKind),
    /// The next write fails.
    WriteErr(io::ErrorKind),
}

impl Step {
    pub(crate) fn write(b: &[u8]) -> Step {
        Step::Write(b.to_vec())
    }
    pub(crate) fn read(b: &[u8]) -> Step {
        Step::Read(b.to_vec())
    }
}

/// One read step per byte.
pub(crate) fn bytewise(b: &[u8]) -> Vec<Step> {
    b.iter().map(|&x| Step::Read(vec![x])).collect()
}

/// The scripted stream. Reads past the end of the script see end of stream.
#[derive(Debug)]
pub(crate) struct Script {
    steps: VecDeque<Step>,
}

impl Script {
    pub(crate) fn new(steps: Vec<Step>) -> Script {
        Script { steps: steps.into() }
    }

    /// Panics unless every step was consumed.
    pub(crate) fn done(&self) {
        assert!(self.steps.is_empty(), "script left over: {:?}", self.steps);
    }
}

impl Read for Script {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        match self.steps.front_mut() {
            None => Ok(0),
            Some(Step::Read(data)) => {
                let n = data.len().min(buf.len());
                buf[..n].copy_from_slice(&data[..n]);
                data.drain(..n);
                if data.is_empty() {
                    self.steps.pop_front();
                }
                Ok(n)
            }
            Some(Step::ReadErr(kind)) => {
                let kind = *kind;
                self.steps.pop_front();
                Err(io::Error::new(kind, "scripted read error"))
            }
            Some(other) => panic!("the client read, the script expected {other:?}"),
        }
    }
}

impl Write for Script {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match self.steps.front_mut() {
            Some(Step::Write(want)) => {
                let n = want.len().min(buf.len());
                assert_eq!(
                    String::from_utf8_lossy(&buf[..n]),
                    String::from_utf8_lossy(&want[..n]),
                    "the client wrote other bytes than scripted"
                );
                want.drain(..n);
                if want.is_empty() {
                    self.steps.pop_front();
                }
                Ok(n)
            }
            Some(Step::WriteErr(kind)) => {
                let kind = *kind;
                self.steps.pop_front();
                Err(io::Error::new(kind, "scripted write error"))
            }
            other => panic!("the client wrote {:?}, the script expected {other:?}", String::from_utf8_lossy(buf)),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}
