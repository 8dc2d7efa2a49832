//! The `$` lines (system.c, `system_execute_line`).

use super::gcode::Op;
use super::gcode::{read_float, GcState};
use super::machine::{Machine, Step};
use super::settings::Settings;
use super::{report, status as st};

impl Machine {
    /// Runs one `$` line; its text goes out before the status. Returns the status code.
    pub(crate) fn system_line(&mut self, line: &[u8]) -> u8 {
        let rest = &line[1..];
        match rest.first() {
            None => {
                self.text("[HLP:$$ $# $G $I $N $x=val $Nx=line $J=line $SLP $C $X $H ~ ! ? ctrl-x]\r\n");
                0
            }
            Some(b'$' | b'G' | b'C' | b'X') if rest.len() > 1 => st::INVALID_STATEMENT,
            Some(b'$') => {
                if matches!(self.state_name(), "Run") || self.state_name().starts_with("Hold") {
                    return st::IDLE_ERROR;
                }
                let r = self.settings.report();
                self.text(&r);
                0
            }
            Some(b'G') => {
                let r = report::gcode_modes(&self.gc);
                self.text(&r);
                0
            }
            Some(b'C') => {
                if self.check_mode {
                    // system.c: leaving check mode resets the controller.
                    self.check_mode = false;
                    self.gc = GcState::new(self.motion.position(), &self.stored);
                    self.text("[MSG:Disabled]\r\n");
                } else {
                    if self.state_name() != "Idle" {
                        return st::IDLE_ERROR;
                    }
                    self.check_mode = true;
                    self.text("[MSG:Enabled]\r\n");
                }
                0
            }
            Some(b'X') => {
                if self.alarm {
                    self.alarm = false;
                    self.text("[MSG:Caution: Unlocked]\r\n");
                }
                0
            }
            Some(_) if !self.idle_or_alarm() => st::IDLE_ERROR,
            Some(b'#') => {
                if rest.len() > 1 {
                    return st::INVALID_STATEMENT;
                }
                let r = report::ngc_parameters(&self.gc, &self.stored);
                self.text(&r);
                0
            }
            Some(b'H') => {
                if self.settings.get(22) == 0.0 {
                    return st::SETTING_DISABLED;
                }
                if rest.len() > 1 {
                    return st::INVALID_STATEMENT;
                }
                // The emulated homing cycle: a seek to machine zero at `$25`, which becomes home.
                let seek = self.settings.get(25).max(1.0);
                self.steps.extend([
                    Step::HomeStart,
                    Step::Op(Op::Line([0.0; 3], Some(seek))),
                    Step::Op(Op::Sync),
                    Step::HomeEnd,
                ]);
                0
            }
            Some(b'I') => {
                if rest.len() == 1 {
                    let blocks = self.config.planner_blocks();
                    let r = report::build_info(self.config.flavour, self.config.m7, blocks, self.config.rx_buffer());
                    self.text(&r);
                }
                0
            }
            Some(b'N') => {
                // Startup lines are accepted but not stored or run.
                if rest.len() == 1 {
                    self.text("$N0=\r\n$N1=\r\n");
                }
                0
            }
            Some(b'R') => {
                if rest.len() != 5 || &rest[..4] != b"RST=" || !matches!(rest[4], b'$' | b'#' | b'*') {
                    return st::INVALID_STATEMENT;
                }
                if rest[4] != b'#' {
                    self.settings = Settings::default();
                }
                if rest[4] != b'$' {
                    self.stored = Default::default();
                }
                self.text("[MSG:Restoring defaults]\r\n");
                0
            }
            // Jogging and sleep are not emulated.
            Some(b'J' | b'S') => st::INVALID_STATEMENT,
            Some(_) => {
                let Some((param, used)) = read_float(rest) else { return st::BAD_NUMBER_FORMAT };
                if rest.get(used) != Some(&b'=') {
                    return st::INVALID_STATEMENT;
                }
                let after = &rest[used + 1..];
                let Some((value, used)) = read_float(after) else { return st::BAD_NUMBER_FORMAT };
                if used != after.len() {
                    return st::INVALID_STATEMENT;
                }
                match self.settings.store(param, value) {
                    Ok(()) => 0,
                    Err(code) => code,
                }
            }
        }
    }

    fn text(&mut self, s: &str) {
        self.steps.push_back(Step::Text(s.to_string()));
    }
}
