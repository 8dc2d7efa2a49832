//! The controller's state read back: `$#`, `$G`, `$$`.

use std::time::Duration;

use super::{Sender, StreamError};
use crate::response::{MachineState, ParseError};
use crate::state::{parse_offsets, parse_parser_state, parse_settings, Offsets, ParserState};

fn bad_report(line: &str, e: &ParseError) -> StreamError {
    StreamError::ConnectionLost { reason: format!("unreadable answer to {line}: {e}"), reached: None }
}

impl Sender {
    /// `$#`: the work offsets, G28/G30, G92 and the tool length offset (report units: mm, or
    /// inches with `$13=1`). Finishes pushed lines and waits for the machine to stop first,
    /// since Grbl answers `$#` only in Idle or Alarm.
    pub fn offsets(&mut self) -> Result<Offsets, StreamError> {
        self.settle()?;
        let lines = self.command("$#")?;
        parse_offsets(&lines).map_err(|e| bad_report("$#", &e))
    }

    /// `$G`: the parser's modal state, as of the last line it read (report units).
    pub fn parser_state(&mut self) -> Result<ParserState, StreamError> {
        let lines = self.command("$G")?;
        parse_parser_state(&lines).map_err(|e| bad_report("$G", &e))
    }

    /// `$$`: every numeric setting as `(N, value)` in the controller's order. Finishes pushed
    /// lines and waits for the machine to stop first (Grbl refuses `$$` while moving).
    pub fn settings(&mut self) -> Result<Vec<(u16, f64)>, StreamError> {
        self.settle()?;
        let lines = self.command("$$")?;
        parse_settings(&lines).map_err(|e| bad_report("$$", &e))
    }

    /// Finishes pushed lines, then polls while the machine moves or waits for the operator
    /// (Run, Jog, Home, Hold, Door, Tool). Other states (Idle, Alarm; Check and Sleep, which
    /// `$#` and `$$` then refuse with `error:8`) end the wait.
    fn settle(&mut self) -> Result<(), StreamError> {
        if self.flight.in_flight() > 0 {
            self.finish()?;
        }
        loop {
            use MachineState::{Door, Hold, Home, Jog, Run, Tool};
            if !matches!(self.status()?.state, Some(Run | Jog | Home | Hold | Door | Tool)) {
                return Ok(());
            }
            std::thread::sleep(self.options.poll.saturating_sub(Duration::from_millis(20)));
        }
    }
}
