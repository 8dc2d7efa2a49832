//! Character counting one line at a time: [`Sender::push`], [`Sender::finish`], and the reader
//! that matches every answer to the line it belongs to.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::{needs_idle, needs_sync, Sender, StreamError, StreamReport};
use crate::response::{MachineState, Response};

/// How long one wait for an answer lasts before the loop polls and checks its timeouts again.
const TICK: Duration = Duration::from_millis(10);

/// A line sent and not yet answered.
#[derive(Debug)]
struct Pending {
    index: usize,
    len: usize,
    sync: bool,
    /// A `$` line sent at rest: its answer does not mean motion.
    idle: bool,
    text: String,
}

/// The streaming state of one connection.
#[derive(Debug)]
pub(super) struct Flight {
    queue: VecDeque<Pending>,
    /// Bytes of the receive buffer the queued lines take.
    used: usize,
    pushed: usize,
    reached: Option<usize>,
    report: StreamReport,
    motion_started: bool,
    dry: bool,
    /// A fresh report showed the controller at rest with nothing queued.
    idle_seen: bool,
    /// The last answer, or the send that made the queue non-empty.
    answer_clock: Instant,
    /// The first status poll nothing has been heard since.
    pub(super) asked_since: Option<Instant>,
    /// The line index streaming stopped at.
    pub(super) stopped: Option<usize>,
}

impl Flight {
    pub(super) fn new() -> Self {
        Self {
            queue: VecDeque::new(),
            used: 0,
            pushed: 0,
            reached: None,
            report: StreamReport::default(),
            motion_started: false,
            dry: false,
            idle_seen: false,
            answer_clock: Instant::now(),
            asked_since: None,
            stopped: None,
        }
    }

    pub(super) fn pushed(&self) -> usize {
        self.pushed
    }

    pub(super) fn in_flight(&self) -> usize {
        self.queue.len()
    }

    /// Streaming stops: nothing queued is answered any more.
    fn stop(&mut self, at: usize) {
        self.stopped = Some(at);
        self.queue.clear();
        self.used = 0;
    }

    /// The first line not known to be done.
    fn after_reached(&self) -> usize {
        self.reached.map_or(0, |r| r + 1)
    }
}

/// The first byte of `text` that Grbl acts on wherever it sees it (a line end, `?`, `!`, `~`,
/// 0x18, or one of 0x80..=0xFF, the overrides).
fn real_time_byte(text: &str) -> Option<u8> {
    text.bytes().find(|&b| matches!(b, b'\n' | b'\r' | b'?' | b'!' | b'~' | 0x18 | 0x80..=0xFF))
}

impl Sender {
    /// Sends `line` once it fits the receive buffer (character counting; a line that writes
    /// settings or EEPROM goes alone, a `$` line that needs Idle waits for it), reading answers
    /// and polling status meanwhile. It times out only when the controller falls silent for
    /// [`SenderOptions::timeout`](super::SenderOptions::timeout), or reports `Idle` without
    /// answering a queued line for that long (a longer dwell needs a longer timeout); never
    /// while it reports `Hold`. After an `error:N`, `ALARM:N` or a reset nothing more is sent:
    /// every later push returns [`StreamError::Stopped`].
    pub fn push(&mut self, line: &str) -> Result<(), StreamError> {
        if let Some(at) = self.flight.stopped {
            return Err(StreamError::Stopped { at });
        }
        let index = self.flight.pushed;
        let text = line.trim_end();
        if let Some(byte) = real_time_byte(text) {
            return Err(StreamError::RealTimeByte { index, byte });
        }
        let len = text.len() + 1;
        if len > self.rx_buffer {
            return Err(StreamError::LineTooLong { index, len, limit: self.rx_buffer });
        }
        let (sync, idle) = (needs_sync(text), needs_idle(text));
        while self.pump(Duration::ZERO, true)?.is_some() {}
        let mut since = None;
        while self.blocked(len, sync, idle) {
            since.get_or_insert_with(Instant::now);
            self.poll_if_due()?;
            self.pump(TICK, true)?;
            self.check_stall()?;
        }
        self.poll_if_due()?;
        let f = &mut self.flight;
        if let Some(since) = since {
            f.report.longest_wait = f.report.longest_wait.max(since.elapsed());
        }
        let mut bytes = Vec::with_capacity(len);
        bytes.extend_from_slice(text.as_bytes());
        bytes.push(b'\n');
        if f.queue.is_empty() {
            f.answer_clock = Instant::now();
        }
        if idle {
            // The machine stopped for it on purpose: not the planner running dry.
            f.motion_started = false;
            f.dry = false;
        }
        f.queue.push_back(Pending { index, len, sync, idle, text: text.to_string() });
        f.used += len;
        f.pushed += 1;
        f.report.lines_sent += 1;
        f.report.bytes_sent += len;
        self.write(&bytes)
    }

    /// Waits until every pushed line is answered; returns the totals since connect. Motion may
    /// still be running. A stop the controller's planner makes after this (a camera capture
    /// before the next push) is not counted as running dry.
    pub fn finish(&mut self) -> Result<StreamReport, StreamError> {
        if let Some(at) = self.flight.stopped {
            return Err(StreamError::Stopped { at });
        }
        while !self.flight.queue.is_empty() {
            self.poll_if_due()?;
            self.pump(TICK, true)?;
            self.check_stall()?;
        }
        self.flight.motion_started = false;
        self.flight.dry = false;
        Ok(self.flight.report.clone())
    }

    /// Lines pushed since connect; the next push gets this index.
    pub fn lines_pushed(&self) -> usize {
        self.flight.pushed
    }

    fn blocked(&self, len: usize, sync: bool, idle: bool) -> bool {
        let f = &self.flight;
        f.queue.back().is_some_and(|p| p.sync)
            || (sync && !f.queue.is_empty())
            || (idle && !(f.queue.is_empty() && f.idle_seen))
            || f.used + len > self.rx_buffer
    }

    fn check_stall(&self) -> Result<(), StreamError> {
        let t = self.options.timeout;
        let silent = self.flight.asked_since.is_some_and(|a| a.elapsed() > t);
        let idle = self.last_status.as_ref().is_some_and(|s| s.state == Some(MachineState::Idle));
        let stuck = idle && !self.flight.queue.is_empty() && self.flight.answer_clock.elapsed() > t;
        if silent || stuck {
            return Err(StreamError::Timeout(t));
        }
        Ok(())
    }

    /// Reads one line (waiting up to `wait`) and accounts for it: an answer completes the
    /// oldest queued line, an error or alarm stops streaming. `counting`: inside push/finish,
    /// where status reports count in the [`StreamReport`].
    pub(super) fn pump(&mut self, wait: Duration, counting: bool) -> Result<Option<Response>, StreamError> {
        let response = match self.next(wait) {
            Ok(Some(r)) => r,
            Ok(None) => return Ok(None),
            Err(StreamError::ConnectionLost { reason, .. }) => {
                let reached = self.flight.reached;
                self.flight.stop(self.flight.after_reached());
                return Err(StreamError::ConnectionLost { reason, reached });
            }
            Err(other) => return Err(other),
        };
        let f = &mut self.flight;
        match &response {
            Response::Ok => {
                if let Some(p) = f.queue.pop_front() {
                    f.used -= p.len;
                    f.reached = Some(p.index);
                    f.motion_started |= !p.idle;
                    f.answer_clock = Instant::now();
                    f.idle_seen = false;
                }
            }
            Response::Error(code) => {
                if let Some(p) = f.queue.pop_front() {
                    let behind = f.queue.len();
                    f.stop(p.index);
                    drain(self, behind);
                    return Err(StreamError::Firmware { index: p.index, text: p.text, code: *code, in_flight: behind });
                }
            }
            Response::Alarm(code) => {
                let reached = f.reached;
                f.stop(f.after_reached());
                return Err(StreamError::Alarm { code: *code, reached });
            }
            Response::Status(s) => {
                if counting {
                    f.report.status_reports += 1;
                    let empty_planner = match (s.buffer, self.planner_blocks) {
                        (Some((free, _)), Some(total)) => free >= total,
                        _ => false,
                    };
                    let now_dry = f.motion_started
                        && !f.queue.is_empty()
                        && (s.state == Some(MachineState::Idle) || empty_planner);
                    if now_dry && !f.dry {
                        f.report.planner_dry += 1;
                    }
                    f.dry = now_dry;
                }
                // Only a report asked for after the last answer shows the state after it.
                let fresh = self.last_poll.is_some_and(|p| p > f.answer_clock);
                let still = matches!(s.state, Some(MachineState::Idle | MachineState::Alarm));
                f.idle_seen = fresh && f.queue.is_empty() && still;
                self.note_status(s.clone());
            }
            Response::Welcome { .. } => {
                if !f.queue.is_empty() {
                    // A reset behind our back: the buffer is gone.
                    let reached = f.reached;
                    f.stop(f.after_reached());
                    return Err(StreamError::ConnectionLost { reason: "the controller was reset".into(), reached });
                }
            }
            Response::Feedback(_) | Response::Other(_) => {}
        }
        Ok(Some(response))
    }
}

/// Reads the answers to the lines still in flight after an error, so the link is clean.
fn drain(sender: &mut Sender, mut count: usize) {
    let deadline = Instant::now() + Duration::from_secs(2);
    while count > 0 && Instant::now() < deadline {
        match sender.next(Duration::from_millis(20)) {
            Ok(Some(Response::Ok | Response::Error(_))) => count -= 1,
            Ok(Some(Response::Status(s))) => sender.note_status(s),
            Ok(_) => {}
            Err(_) => return,
        }
    }
}

/// An error from lines pushed since connect, with its indexes counted from `base` instead.
pub(super) fn rebase(e: StreamError, base: usize) -> StreamError {
    let re = |r: Option<usize>| r.and_then(|r| r.checked_sub(base));
    match e {
        StreamError::Firmware { index, text, code, in_flight } => {
            StreamError::Firmware { index: index.saturating_sub(base), text, code, in_flight }
        }
        StreamError::Alarm { code, reached } => StreamError::Alarm { code, reached: re(reached) },
        StreamError::ConnectionLost { reason, reached } => StreamError::ConnectionLost { reason, reached: re(reached) },
        StreamError::LineTooLong { index, len, limit } => {
            StreamError::LineTooLong { index: index.saturating_sub(base), len, limit }
        }
        StreamError::RealTimeByte { index, byte } => {
            StreamError::RealTimeByte { index: index.saturating_sub(base), byte }
        }
        StreamError::Stopped { at } => StreamError::Stopped { at: at.saturating_sub(base) },
        other => other,
    }
}
