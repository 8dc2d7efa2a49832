//! The link from the host's interpreter to a Grbl controller: each event becomes the lines Grbl
//! accepts ([`vision_grbl::emit`]) and streams at once; before a camera trigger the link waits
//! for the machine to stop and checks that it stopped where the program put it.

use std::collections::VecDeque;
use std::io::{BufRead, IsTerminal};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::time::{Duration, Instant};

use nalgebra::Point3;
use vision_driver_sim::Sim;
use vision_gcode::Event;
use vision_grbl::codes::{describe_alarm, describe_error};
use vision_grbl::emit::Emitter;
use vision_grbl::response::MachineState;
use vision_grbl::stream::{Sender, StreamError};

use super::StreamingReport;
use crate::run::{Drive, DriveStop};

/// The longest the machine may take to come to rest once every line is answered: the moves
/// still planned (up to the planner's blocks) at their feeds.
const IDLE_WAIT: Duration = Duration::from_secs(600);

/// How far (mm) the controller's reported position may be from where the program put the
/// machine before a trigger, beyond half a step: Grbl reports 3 decimals and the link rounds
/// to 3.
pub(crate) const POSITION_TOLERANCE_MM: f64 = 0.002;

/// The link's lengths.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Units {
    /// Millimetres per machine unit of the host's interpreter (the world's unit).
    pub mm_per_unit: f64,
    /// Millimetres per unit of the controller's reports (25.4 when `$13=1`).
    pub mm_per_report_unit: f64,
    /// How far (mm) each axis may stop from its target: half a step and the reports' rounding.
    pub tolerance: [f64; 3],
}

/// Lines remembered to name the one the controller refused (more than any receive buffer holds).
const REMEMBERED: usize = 4096;

/// The controller and the lines sent to it.
pub(crate) struct Link {
    sender: Sender,
    emitter: Emitter,
    units: Units,
    /// The simulated world, whose head is put where the controller says before each trigger.
    sim: Sim,
    /// (index of the pushed line, program line, text) of the last lines pushed.
    sent: VecDeque<(usize, u32, String)>,
    stop: Option<DriveStop>,
    port: String,
    started: Instant,
    /// Set by the Ctrl-C handler: a stop is the operator's.
    interrupted: Arc<AtomicBool>,
}

impl Link {
    /// A link over `sender`, whose lines `emitter` writes, with the firmware already set up.
    pub(crate) fn new(
        sender: Sender,
        emitter: Emitter,
        units: Units,
        sim: Sim,
        port: String,
        interrupted: Arc<AtomicBool>,
    ) -> Link {
        Link {
            sender,
            emitter,
            units,
            sim,
            sent: VecDeque::new(),
            stop: None,
            port,
            started: Instant::now(),
            interrupted,
        }
    }

    /// Streams `text` (the lines of the program's line `line`); a failure stops the link.
    pub(crate) fn push(&mut self, text: &str, line: u32) {
        if self.stop.is_some() {
            return;
        }
        let index = self.sender.lines_pushed();
        if self.sent.len() == REMEMBERED {
            self.sent.pop_front();
        }
        self.sent.push_back((index, line, text.to_string()));
        if let Err(e) = self.sender.push(text) {
            self.fail(&e, line);
        }
    }

    fn event(&mut self, event: &Event) {
        if self.stop.is_some() {
            return;
        }
        match self.emitter.event(event) {
            Ok(lines) => {
                for text in lines {
                    self.push(&text, event.line());
                }
                if matches!(event, Event::Stop { optional: false, .. }) {
                    self.program_stop(event.line());
                }
            }
            Err(e) => {
                self.stop = Some(DriveStop {
                    line: event.line(),
                    message: format!("line {} cannot be sent to the controller: {e}", event.line()),
                });
            }
        }
    }

    /// M0: the controller holds once it reaches it; the operator resumes from the terminal
    /// (Enter), as from a cycle-start button. Without a terminal nobody can: the job stops.
    fn program_stop(&mut self, line: u32) {
        if self.stop.is_some() {
            return;
        }
        if !std::io::stdin().is_terminal() {
            self.stop = Some(DriveStop {
                line,
                message: format!(
                    "M0 at line {line} holds the machine until an operator resumes it, and there is no terminal to \
                     ask on: run send from a terminal, or remove the M0"
                ),
            });
            let _ = self.sender.control().feed_hold();
            return;
        }
        let waited = self.sender.finish().and_then(|_| loop {
            let s = self.sender.status()?;
            if matches!(s.state, Some(MachineState::Hold | MachineState::Idle)) {
                break Ok(());
            }
            std::thread::sleep(vision_grbl::stream::MIN_POLL);
        });
        if let Err(e) = waited {
            self.fail(&e, line);
            return;
        }
        eprintln!("mach-vision: program stop (M0) at line {line}: the machine holds; press Enter to resume");
        let mut answer = String::new();
        let _ = std::io::stdin().lock().read_line(&mut answer);
        if let Err(e) = self.sender.control().resume() {
            self.fail(&StreamError::Write(e), line);
        }
    }

    /// The program line of pushed line `index`, when it is remembered.
    fn program_line(&self, index: usize) -> Option<(u32, &str)> {
        self.sent.iter().find(|(i, _, _)| *i == index).map(|(_, line, text)| (*line, text.as_str()))
    }

    /// Stops the link on `e`, met while sending program line `line`.
    fn fail(&mut self, e: &StreamError, line: u32) {
        let reached = |link: &Link, index: Option<usize>| index.and_then(|i| link.program_line(i)).map(|(l, _)| l);
        let after =
            |l: Option<u32>| l.map_or_else(|| "before the first line".to_string(), |l| format!("after line {l}"));
        let operator = self.interrupted.load(Ordering::Relaxed);
        let stop = match e {
            StreamError::Firmware { index, code, in_flight, .. } => {
                let (at, text) = self.program_line(*index).map_or((line, String::new()), |(l, t)| (l, t.to_string()));
                let cleared = self.stop_job(*in_flight);
                DriveStop {
                    line: at,
                    message: format!(
                        "the controller refused `{text}` (program line {at}): {}; nothing after it was sent{cleared}",
                        describe_error(*code)
                    ),
                }
            }
            StreamError::Alarm { code, reached: index } => {
                let l = reached(self, *index);
                let why = if operator { " (the operator reset the controller)" } else { "" };
                DriveStop {
                    line: l.unwrap_or(line),
                    message: format!(
                        "the controller raised {}{why} {}; the job stopped",
                        describe_alarm(*code),
                        after(l)
                    ),
                }
            }
            StreamError::ConnectionLost { reason, reached: index } => {
                let l = reached(self, *index);
                let why = if operator { "the operator reset the controller" } else { reason.as_str() };
                DriveStop {
                    line: l.unwrap_or(line),
                    message: format!(
                        "the connection to {} was lost ({why}) {}, the last line the controller answered",
                        self.port,
                        after(l)
                    ),
                }
            }
            other => DriveStop {
                line,
                message: format!("streaming to {} stopped at program line {line}: {other}", self.port),
            },
        };
        self.stop = Some(stop);
    }

    /// After a refused line: the lines behind it in the controller's buffer must not run
    /// without it, so a feed hold stops the machine on its path and, once it is still, a soft
    /// reset (which keeps the position when not moving) discards them. What it says about it.
    fn stop_job(&mut self, in_flight: usize) -> String {
        if in_flight == 0 || self.sender.is_grblhal() {
            // grblHAL refuses every line while an error is latched: nothing behind it ran.
            return String::new();
        }
        let control = self.sender.control();
        if control.feed_hold().is_err() {
            return format!("; {in_flight} lines already in its buffer may run: stop the machine");
        }
        let deadline = Instant::now() + Duration::from_secs(30);
        while Instant::now() < deadline {
            match self.sender.status() {
                Ok(s) if s.state == Some(MachineState::Idle) => break,
                Ok(s) if s.state == Some(MachineState::Hold) && s.substate == Some(0) => break,
                Ok(_) => {}
                Err(_) => return format!("; {in_flight} lines already in its buffer may run: stop the machine"),
            }
        }
        match control.soft_reset() {
            Ok(()) => format!("; a feed hold and a soft reset discarded the {in_flight} lines already in its buffer"),
            Err(_) => format!("; the machine is held with {in_flight} lines in its buffer: reset it"),
        }
    }

    /// Waits until every line is answered and the machine is still.
    fn settle(&mut self) -> Result<[f64; 3], String> {
        if let Some(stop) = &self.stop {
            return Err(format!("the machine stopped at line {}: {}", stop.line, stop.message));
        }
        let line = self.sent.back().map_or(0, |(_, l, _)| *l);
        let waited = self.sender.finish().and_then(|_| self.sender.wait_idle(IDLE_WAIT));
        match waited {
            Ok(status) => {
                let wco = self.sender.wco();
                let mpos = match (status.mpos, status.wpos) {
                    (Some(m), _) => m,
                    (None, Some(w)) => std::array::from_fn(|i| w[i] + wco[i]),
                    (None, None) => return Err("the controller's status report has no position".into()),
                };
                Ok(mpos.map(|v| v * self.units.mm_per_report_unit))
            }
            Err(e) => {
                self.fail(&e, line);
                Err(self.stop.as_ref().map_or_else(String::new, |s| s.message.clone()))
            }
        }
    }

    /// Before a camera trigger: the machine still, where the program put it; the simulated
    /// head placed where the controller reports it.
    fn before_trigger(&mut self) -> Result<(), String> {
        let mpos = self.settle()?;
        moved_elsewhere(mpos, self.emitter.machine_mm(), self.units.tolerance).map_or(Ok(()), Err)?;
        let u = self.units.mm_per_unit;
        self.sim.place_head(Point3::new(mpos[0] / u, mpos[1] / u, mpos[2] / u));
        Ok(())
    }

    /// The streaming figures so far.
    pub(crate) fn figures(&self) -> StreamingReport {
        StreamingReport::new(&self.port, &self.sender, self.started.elapsed())
    }
}

/// Why a capture must not trust the commanded position: the controller reports the machine
/// (`mpos`, mm) farther from where the program put it (`expected`, mm) than an axis's
/// `tolerance` (mm). `None` when it is there.
pub(crate) fn moved_elsewhere(mpos: [f64; 3], expected: [f64; 3], tolerance: [f64; 3]) -> Option<String> {
    let off: [f64; 3] = std::array::from_fn(|i| (mpos[i] - expected[i]).abs());
    if (0..3).all(|i| off[i] <= tolerance[i]) {
        return None;
    }
    let worst = off.into_iter().fold(0.0, f64::max);
    Some(format!(
        "the controller reports the machine at X{:.3} Y{:.3} Z{:.3} mm, {worst:.3} mm from where the program put it \
         (X{:.3} Y{:.3} Z{:.3}): something else moved it, so the camera would look at the wrong place",
        mpos[0], mpos[1], mpos[2], expected[0], expected[1], expected[2]
    ))
}

/// How far (mm) each axis may stop from its target on a controller with `settings` (`$$`):
/// half a step (`$100`–`$102`, steps/mm) and the reports' rounding; the rounding alone when
/// the controller does not say.
pub(crate) fn stop_tolerance(settings: &[(u16, f64)]) -> [f64; 3] {
    std::array::from_fn(|axis| {
        let steps = settings.iter().find(|&&(n, _)| usize::from(n) == 100 + axis).map_or(0.0, |&(_, v)| v);
        if steps >= 1.0 {
            0.5 / steps + POSITION_TOLERANCE_MM
        } else {
            POSITION_TOLERANCE_MM
        }
    })
}

/// Millimetres per unit of a controller's reports: 25.4 when `$13=1` (report inches).
pub(crate) fn report_unit_mm(settings: &[(u16, f64)]) -> f64 {
    if settings.iter().any(|&(n, v)| n == 13 && v != 0.0) {
        vision_math::MM_PER_INCH
    } else {
        1.0
    }
}

/// The link, shared by the program's drive and the camera's wrapper (both on the thread that
/// runs the program, never at once).
#[derive(Clone)]
pub(crate) struct Shared(pub(crate) Arc<Mutex<Option<Link>>>);

impl Shared {
    fn lock(&self) -> MutexGuard<'_, Option<Link>> {
        self.0.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Before a camera trigger (see [`Link::before_trigger`]); without a link, nothing.
    pub(crate) fn before_trigger(&self) -> Result<(), String> {
        self.lock().as_mut().map_or(Ok(()), Link::before_trigger)
    }
}

impl Drive for Shared {
    fn event(&mut self, event: &Event) {
        if let Some(link) = self.lock().as_mut() {
            link.event(event);
        }
    }

    fn finish(&mut self) -> Option<DriveStop> {
        let mut guard = self.lock();
        let link = guard.as_mut()?;
        if link.stop.is_none() {
            let _ = link.settle();
        }
        link.stop.clone()
    }

    fn figures(&self) -> Option<StreamingReport> {
        self.lock().as_ref().map(Link::figures)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_machine_within_half_a_step_is_where_the_program_put_it() {
        let tolerance = stop_tolerance(&[(100, 250.0), (101, 80.0), (13, 0.0)]);
        let expected = [0.002 + POSITION_TOLERANCE_MM, 0.00625 + POSITION_TOLERANCE_MM, POSITION_TOLERANCE_MM];
        assert!((0..3).all(|i| (tolerance[i] - expected[i]).abs() < 1e-12), "{tolerance:?}");
        let coarse = stop_tolerance(&[(100, 0.5), (102, 1.0)]);
        assert!((coarse[0] - POSITION_TOLERANCE_MM).abs() < 1e-12 && (coarse[2] - 0.502).abs() < 1e-12, "{coarse:?}");
        let at = [10.0, 20.0, -1.0];
        assert_eq!(moved_elsewhere(at, at, tolerance), None);
        assert_eq!(moved_elsewhere([10.0039, 19.992, -1.0019], at, tolerance), None);
        for (axis, by) in [(0, 0.0041), (1, 0.0083), (2, 0.0021)] {
            let mut moved = at;
            moved[axis] += by;
            let why = moved_elsewhere(moved, at, tolerance).expect("refused");
            assert!(why.contains(&format!("{by:.3} mm from where")), "{why}");
            moved[axis] = at[axis] - by;
            assert!(moved_elsewhere(moved, at, tolerance).is_some(), "axis {axis} below");
        }
        let why = moved_elsewhere([12.5, 20.0, -1.0], at, tolerance).expect("refused");
        assert!(why.starts_with("the controller reports the machine at X12.500 Y20.000 Z-1.000 mm, 2.500 mm"), "{why}");
        assert!(why.contains("(X10.000 Y20.000 Z-1.000)"), "{why}");
    }

    #[test]
    fn reports_in_inches_are_read_as_inches() {
        assert!((report_unit_mm(&[(13, 1.0)]) - 25.4).abs() < 1e-12);
        assert!((report_unit_mm(&[(13, 0.0), (12, 1.0)]) - 1.0).abs() < 1e-12);
        assert!((report_unit_mm(&[]) - 1.0).abs() < 1e-12);
    }
}
