//! Character counting: the loop behind [`Sender::stream`].

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::{needs_idle, needs_sync, Sender, StreamError, StreamReport};
use crate::response::{MachineState, Response};

pub(super) fn stream_lines<S: AsRef<str>>(sender: &mut Sender, lines: &[S]) -> Result<StreamReport, StreamError> {
    let mut report = StreamReport::default();
    // (index, bytes, sync) of each line sent and not yet answered.
    let mut in_flight: VecDeque<(usize, usize, bool)> = VecDeque::new();
    let mut used = 0usize;
    let mut next = 0usize;
    let mut reached: Option<usize> = None;
    let mut waiting_since: Option<Instant> = None;
    let mut last_answer = Instant::now();
    let mut motion_started = false;
    let mut dry = false;
    // An `Idle` report read since the last answer, with nothing in flight.
    let mut idle_seen = false;
    loop {
        // Send every line that fits.
        while next < lines.len() {
            let text = lines[next].as_ref().trim_end();
            let len = text.len() + 1;
            if len > sender.rx_buffer {
                return Err(StreamError::LineTooLong { index: next, len, limit: sender.rx_buffer });
            }
            let sync = needs_sync(text);
            let blocked = in_flight.back().is_some_and(|&(_, _, s)| s)
                || (sync && !in_flight.is_empty())
                || (needs_idle(text) && !(in_flight.is_empty() && idle_seen))
                || used + len > sender.rx_buffer;
            if blocked {
                waiting_since.get_or_insert_with(Instant::now);
                break;
            }
            if let Some(since) = waiting_since.take() {
                report.longest_wait = report.longest_wait.max(since.elapsed());
            }
            let mut bytes = Vec::with_capacity(len);
            bytes.extend_from_slice(text.as_bytes());
            bytes.push(b'\n');
            sender.write(&bytes)?;
            in_flight.push_back((next, len, sync));
            used += len;
            report.lines_sent += 1;
            report.bytes_sent += len;
            next += 1;
        }
        if next == lines.len() && in_flight.is_empty() {
            return Ok(report);
        }
        sender.poll_if_due()?;
        let event = sender.next(Duration::from_millis(10)).map_err(|e| match e {
            StreamError::ConnectionLost { reason, .. } => StreamError::ConnectionLost { reason, reached },
            other => other,
        })?;
        match event {
            Some(Response::Ok) => {
                last_answer = Instant::now();
                idle_seen = false;
                if let Some((index, len, _)) = in_flight.pop_front() {
                    used -= len;
                    reached = Some(index);
                    motion_started = true;
                }
            }
            Some(Response::Error(code)) => {
                let (index, _, _) = in_flight.pop_front().unwrap_or((next.saturating_sub(1), 0, false));
                let text = lines.get(index).map(|l| l.as_ref().trim_end().to_string()).unwrap_or_default();
                let behind = in_flight.len();
                drain(sender, behind);
                return Err(StreamError::Firmware { index, text, code, in_flight: behind });
            }
            Some(Response::Alarm(code)) => return Err(StreamError::Alarm { code, reached }),
            Some(Response::Status(s)) => {
                report.status_reports += 1;
                let empty_planner = match (s.buffer, sender.planner_blocks) {
                    (Some((free, _)), Some(total)) => free >= total,
                    _ => false,
                };
                let now_dry = motion_started && (s.state == Some(MachineState::Idle) || empty_planner);
                if now_dry && !dry {
                    report.planner_dry += 1;
                }
                dry = now_dry;
                // Only a report asked for after the last answer shows the state after it.
                let fresh = sender.last_poll.is_some_and(|p| p > last_answer);
                idle_seen = fresh && in_flight.is_empty() && s.state == Some(MachineState::Idle);
                sender.note_status(s);
            }
            Some(Response::Welcome { .. }) => {
                // A reset behind our back: the buffer is gone.
                return Err(StreamError::ConnectionLost { reason: "the controller was reset".into(), reached });
            }
            Some(_) => {}
            None => {
                let holding = sender.last_status.as_ref().is_some_and(|s| s.state == Some(MachineState::Hold));
                if !holding && !in_flight.is_empty() && last_answer.elapsed() > sender.options.timeout {
                    return Err(StreamError::Timeout(sender.options.timeout));
                }
            }
        }
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
