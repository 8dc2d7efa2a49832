//! The controller between the serial bytes and the planner: the receive buffer and real-time
//! bytes (serial.c), line assembly and dispatch (protocol.c), status reports (report.c).
//! Free of sockets and clocks: [`Machine::receive`] takes bytes, [`Machine::advance`] takes
//! simulated time, [`Machine::take_output`] gives what the controller sent.

use std::collections::VecDeque;

use super::gcode::{self, GcState, Op, Stored};
use super::motion::{Limits, Motion, STEP_S};
use super::settings::Settings;
use super::{report, status as st, EmulatorConfig, Flavour};

/// protocol.h: `LINE_BUFFER_SIZE`, the longest line is one less.
const LINE_BUFFER_SIZE: usize = 80;

/// grblHAL's protocol.h: `LINE_BUFFER_SIZE`; its line keeps comments and inner spaces.
const HAL_LINE_BUFFER_SIZE: usize = 257;

/// What the protocol still has to do for the line it read last, in order.
#[derive(Debug)]
pub(crate) enum Step {
    Op(Op),
    Text(String),
    Reply(u8),
    HomeStart,
    HomeEnd,
}

/// The emulated controller.
#[derive(Debug)]
pub struct Machine {
    pub(crate) config: EmulatorConfig,
    pub(crate) settings: Settings,
    pub(crate) gc: GcState,
    pub(crate) stored: Stored,
    pub(crate) motion: Motion,
    rx: VecDeque<u8>,
    line: Vec<u8>,
    /// grblHAL: the characters its line buffer holds so far (comments and inner spaces too).
    hal_len: usize,
    overflow: bool,
    comment_paren: bool,
    comment_semi: bool,
    last_eol: Option<u8>,
    pub(crate) steps: VecDeque<Step>,
    pub(crate) alarm: bool,
    pub(crate) homing: bool,
    pub(crate) check_mode: bool,
    hold: bool,
    latched: u8,
    dwell_until: Option<f64>,
    time: f64,
    pending: f64,
    wco_counter: u8,
    ovr_counter: u8,
    out: Vec<u8>,
}

impl Machine {
    /// A controller just powered up: the welcome line is already in the output.
    pub fn new(config: EmulatorConfig) -> Self {
        let mut settings = Settings::default();
        for &(n, v) in &config.settings {
            let _ = settings.store(f64::from(n), v);
        }
        let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
        let stored = Stored { coords: config.work_offsets.map(|c| c.map(finite)), ..Stored::default() };
        let start = config.start.map(finite);
        let mut m = Self {
            gc: GcState::new(start, &stored),
            stored,
            motion: Motion::new(config.planner_blocks(), start),
            settings,
            config,
            rx: VecDeque::new(),
            line: Vec::new(),
            hal_len: 0,
            overflow: false,
            comment_paren: false,
            comment_semi: false,
            last_eol: None,
            steps: VecDeque::new(),
            alarm: false,
            homing: false,
            check_mode: false,
            hold: false,
            latched: 0,
            dwell_until: None,
            time: 0.0,
            pending: 0.0,
            wco_counter: 0,
            ovr_counter: 0,
            out: Vec::new(),
        };
        // main.c, HOMING_INIT_LOCK: with homing enabled the machine starts locked.
        m.alarm = m.settings.get(22) != 0.0;
        m.greet();
        m
    }

    fn greet(&mut self) {
        self.out.extend_from_slice(report::welcome(self.config.flavour).as_bytes());
        if self.alarm {
            self.out.extend_from_slice(b"[MSG:'$H'|'$X' to unlock]\r\n");
        }
    }

    /// Bytes from the host, as the serial interrupt takes them (serial.c): real-time bytes act
    /// at once, others go into the receive buffer, and bytes that find it full are lost.
    pub fn receive(&mut self, bytes: &[u8]) {
        for &b in bytes {
            match b {
                0x18 => self.reset(),
                b'?' => {
                    let r = self.status_report();
                    self.out.extend_from_slice(r.as_bytes());
                }
                b'!' => {
                    if !self.alarm && !self.homing {
                        self.hold = true;
                        self.motion.hold();
                    }
                }
                b'~' => {
                    if self.hold {
                        self.hold = false;
                        self.motion.resume();
                    }
                }
                0x80..=0xFF => {} // Overrides and the rest of the extended set: not stored.
                _ => {
                    if self.rx.len() < self.config.rx_capacity() {
                        self.rx.push_back(b);
                    }
                }
            }
        }
    }

    /// Runs the controller for `dt` seconds of simulated time.
    pub fn advance(&mut self, dt: f64) {
        self.pending += dt.clamp(0.0, 60.0);
        self.protocol();
        while self.pending >= STEP_S {
            self.pending -= STEP_S;
            self.time += STEP_S;
            self.motion.step();
            self.protocol();
        }
    }

    /// Everything the controller has sent since the last call.
    pub fn take_output(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.out)
    }

    /// Whether the machine is moving or holding motion.
    pub fn in_motion(&self) -> bool {
        !self.motion.is_empty() || self.homing
    }

    /// 0x18 (mc_reset, then main.c's re-initialisation). A reset raises `ALARM:3` while the
    /// steppers may be moving; once a feed hold has stopped them, Grbl and grblHAL clear the
    /// hold's step control and keep the position.
    fn reset(&mut self) {
        let stopped = self.hold && self.motion.hold_complete();
        if self.homing || (!self.motion.is_empty() && !stopped) {
            self.alarm = true;
            self.out.extend_from_slice(format!("ALARM:{}\r\n", st::ALARM_ABORT_CYCLE).as_bytes());
        }
        self.motion.kill();
        self.steps.clear();
        self.rx.clear();
        self.line.clear();
        self.hal_len = 0;
        self.overflow = false;
        self.comment_paren = false;
        self.comment_semi = false;
        self.homing = false;
        self.check_mode = false;
        self.hold = false;
        self.latched = 0;
        self.dwell_until = None;
        self.wco_counter = 0;
        self.ovr_counter = 0;
        self.gc = GcState::new(self.motion.position(), &self.stored);
        self.greet();
    }

    fn limits(&self) -> Limits {
        let s = &self.settings;
        Limits {
            max_rate: [s.get(110), s.get(111), s.get(112)].map(|v| v.max(1.0)),
            accel: [s.get(120), s.get(121), s.get(122)].map(|v| v.max(0.001)),
            junction_deviation: s.get(11),
        }
    }

    /// Runs pending steps, then reads lines until one has to wait.
    fn protocol(&mut self) {
        loop {
            while let Some(step) = self.steps.front() {
                let done = match step {
                    Step::Op(Op::Sync) => self.check_mode || self.motion.is_empty(),
                    Step::Op(Op::Line(target, rate)) => {
                        if self.check_mode {
                            true
                        } else {
                            let spm = self.settings.steps_per_mm();
                            let t = std::array::from_fn(|i| (target[i] * spm[i]).round() / spm[i]);
                            let limits = self.limits();
                            self.motion.push(t, *rate, &limits)
                        }
                    }
                    Step::Op(Op::Dwell(d)) => {
                        let until = *self.dwell_until.get_or_insert(self.time + d);
                        if self.check_mode || self.time + 1e-9 >= until {
                            self.dwell_until = None;
                            true
                        } else {
                            false
                        }
                    }
                    Step::Op(Op::Pause) => {
                        if !self.check_mode {
                            self.hold = true;
                            self.motion.hold();
                        }
                        true
                    }
                    Step::Op(Op::WcoChanged) => {
                        self.wco_counter = 0;
                        true
                    }
                    Step::Op(Op::Message(m)) => {
                        self.out.extend_from_slice(format!("[MSG:{m}]\r\n").as_bytes());
                        true
                    }
                    Step::Text(t) => {
                        self.out.extend_from_slice(t.as_bytes());
                        true
                    }
                    Step::Reply(0) => {
                        self.out.extend_from_slice(b"ok\r\n");
                        true
                    }
                    Step::Reply(code) => {
                        self.out.extend_from_slice(format!("error:{code}\r\n").as_bytes());
                        true
                    }
                    Step::HomeStart => {
                        self.homing = true;
                        true
                    }
                    Step::HomeEnd => {
                        self.homing = false;
                        self.alarm = false;
                        self.motion.set_position([0.0; 3]);
                        self.gc.position = [0.0; 3];
                        true
                    }
                };
                if !done {
                    return;
                }
                self.steps.pop_front();
            }
            let Some(c) = self.rx.pop_front() else { return };
            self.take_char(c);
        }
    }

    /// protocol_main_loop: strips spaces, comments and block delete, upcases, catches overflow.
    fn take_char(&mut self, c: u8) {
        if c == b'\n' || c == b'\r' {
            // grblHAL takes CRLF (or LFCR) as one end of line; Grbl answers the empty second.
            if self.config.flavour == Flavour::GrblHal {
                if self.line.is_empty() && !self.overflow && self.last_eol.is_some_and(|e| e != c) {
                    self.last_eol = None;
                    return;
                }
                self.last_eol = Some(c);
            }
            let line = std::mem::take(&mut self.line);
            self.hal_len = 0;
            let overflow = std::mem::replace(&mut self.overflow, false);
            self.comment_paren = false;
            self.comment_semi = false;
            self.execute_line(&line, overflow);
            return;
        }
        let hal = self.config.flavour == Flavour::GrblHal;
        // grblHAL stores every character but control ones and leading spaces.
        if hal && (c > b' ' || (c == b' ' && self.hal_len > 0)) {
            if self.hal_len >= HAL_LINE_BUFFER_SIZE - 1 {
                self.overflow = true;
            } else {
                self.hal_len += 1;
            }
        }
        if self.overflow || self.comment_paren || self.comment_semi {
            if c == b')' {
                self.comment_paren = false;
            }
            return;
        }
        match c {
            0..=b' ' | b'/' => {}
            b'(' => self.comment_paren = true,
            b';' => self.comment_semi = true,
            _ if !hal && self.line.len() >= LINE_BUFFER_SIZE - 1 => self.overflow = true,
            _ => self.line.push(c.to_ascii_uppercase()),
        }
    }

    fn execute_line(&mut self, line: &[u8], overflow: bool) {
        let hal = self.config.flavour == Flavour::GrblHal;
        let status = if overflow {
            st::OVERFLOW
        } else if line.is_empty() {
            0
        } else if line[0] == b'$' {
            self.system_line(line)
        } else if self.alarm || self.homing {
            st::SYSTEM_GC_LOCK
        } else if hal && self.latched != 0 {
            // grblHAL protocol.c (COMPATIBILITY_LEVEL 0): after an error, G-code lines are
            // not parsed and answer the same error until a `$` line, an empty line or a reset.
            self.latched
        } else {
            let m7 = self.config.m7 || hal;
            match gcode::execute(line, &mut self.gc, &mut self.stored, self.config.flavour, m7, self.settings.get(12)) {
                Ok(ops) => {
                    self.steps.extend(ops.into_iter().map(Step::Op));
                    0
                }
                Err(code) => code,
            }
        };
        if hal {
            self.latched = status;
        }
        self.steps.push_back(Step::Reply(status));
    }

    /// The state word of a status report.
    pub fn state_name(&self) -> &'static str {
        if self.alarm {
            "Alarm"
        } else if self.homing {
            "Home"
        } else if self.hold {
            if self.motion.is_empty() || self.motion.hold_complete() {
                "Hold:0"
            } else {
                "Hold:1"
            }
        } else if self.check_mode {
            "Check"
        } else if !self.motion.is_empty() {
            "Run"
        } else {
            "Idle"
        }
    }

    /// The tool's machine position as the steppers have it (mm, rounded to whole steps).
    pub fn machine_position(&self) -> [f64; 3] {
        let spm = self.settings.steps_per_mm();
        let p = self.motion.position();
        std::array::from_fn(|i| (p[i] * spm[i]).round() / spm[i])
    }

    /// report_realtime_status (report.c), with its WCO and override counters.
    #[expect(
        clippy::cast_possible_truncation,
        clippy::cast_sign_loss,
        reason = "$10 is a mask of at most 255, checked when set"
    )]
    fn status_report(&mut self) -> String {
        let mask = self.settings.get(10) as u8;
        let busy = matches!(self.state_name(), "Run" | "Home") || self.hold;
        let wco = self.gc.wco();
        let mut pos = self.machine_position();
        let mut out = format!("<{}", self.state_name());
        if mask & 1 == 0 {
            pos = std::array::from_fn(|i| pos[i] - wco[i]);
            out.push_str("|WPos:");
        } else {
            out.push_str("|MPos:");
        }
        out.push_str(&report::axes(pos));
        if mask & 2 != 0 {
            let rx_free = self.config.rx_capacity() - self.rx.len();
            out.push_str(&format!("|Bf:{},{}", self.motion.available(), rx_free));
        }
        let spindle = if self.gc.spindle == 5 { 0.0 } else { self.gc.speed };
        out.push_str(&format!("|FS:{},{}", report::num(self.motion.rate_mm_per_min(), 0), report::num(spindle, 0)));
        if self.wco_counter > 0 {
            self.wco_counter -= 1;
        } else {
            self.wco_counter = if busy { 29 } else { 9 };
            if self.ovr_counter == 0 {
                self.ovr_counter = 1;
            }
            out.push_str(&format!("|WCO:{}", report::axes(wco)));
        }
        if self.ovr_counter > 0 {
            self.ovr_counter -= 1;
        } else {
            self.ovr_counter = if busy { 19 } else { 9 };
            out.push_str("|Ov:100,100,100");
            let mut a = String::new();
            match self.gc.spindle {
                3 => a.push('S'),
                4 => a.push('C'),
                _ => {}
            }
            if self.gc.flood {
                a.push('F');
            }
            if self.gc.mist {
                a.push('M');
            }
            if !a.is_empty() {
                out.push_str(&format!("|A:{a}"));
            }
        }
        out.push_str(">\r\n");
        out
    }

    /// Whether the state allows `$` commands that need Idle or Alarm (system.c).
    pub(crate) fn idle_or_alarm(&self) -> bool {
        matches!(self.state_name(), "Idle" | "Alarm")
    }
}
