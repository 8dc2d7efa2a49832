//! The interpreter's events as lines a Grbl 1.1 firmware accepts.
//!
//! The host runs the program in `vision_gcode` (subroutines, expressions, cycles, tools, the
//! alignment); what reaches the firmware is only what Grbl 1.1 parses: absolute G0/G1/G2/G3 in
//! its work coordinates (mm, 3 decimals), G4, G17–G19, F, S, M0–M5, M7–M9, M30. Each line holds
//! only the axes and modal words that change, and is at most [`MAX_LINE`] characters.
//!
//! Positions are kept in whole micrometres as the firmware will parse them, so that an arc's
//! I/J/K is the rounded centre minus the position the firmware really holds: Grbl checks the
//! end radius against the start radius with that position (gcode.c, error:33).
//!
//! ```
//! use vision_gcode::{Event, LinearMove, PathMode, Rate, Xyz};
//! use vision_grbl::emit::{Emitter, Frame};
//!
//! let frame = Frame { mm_per_unit: 25.4, wco: [-100.0, -50.0, 0.0], work_system: 1 };
//! let mut emitter = Emitter::new(frame, Xyz::ZERO)?;
//! assert_eq!(emitter.preamble(), ["G21 G90 G94 G17 G54"]);
//! let mv = LinearMove {
//!     line: 1,
//!     start: Xyz::ZERO,
//!     end: Xyz::new(1.0, 0.0, 0.0),
//!     rate: Rate::Feed(10.0),
//!     path: PathMode::ExactStop,
//! };
//! // 1 in = 25.4 mm machine, 125.4 mm in the work frame; 10 in/min = 254 mm/min.
//! assert_eq!(emitter.event(&Event::Linear(mv))?, ["G1 X125.4 F254"]);
//! # Ok::<(), vision_grbl::emit::EmitError>(())
//! ```

mod arc;

use vision_gcode::{Event, LinearMove, Plane, Rate, Xyz};

/// The longest line sent: Grbl's line buffer holds 80 bytes with the terminator, so 79
/// characters (protocol.h, `LINE_BUFFER_SIZE`).
pub const MAX_LINE: usize = 79;

/// The largest magnitude of a coordinate or an arc offset written (mm): eight significant
/// digits with three decimals, all that Grbl's `read_float` keeps.
pub const MAX_COORDINATE_MM: f64 = 99_999.0;

/// The largest feed (mm/min), spindle speed (rpm) or dwell (s) written: eight digits.
pub const MAX_VALUE: f64 = 99_999_999.0;

/// Where the firmware's work coordinates are: work (mm) = machine × `mm_per_unit` − `wco`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Millimetres per machine unit of the events (1 for a mm machine, 25.4 for inch).
    pub mm_per_unit: f64,
    /// The firmware's work coordinate offset (its `WCO`), mm.
    pub wco: [f64; 3],
    /// The firmware's work system, 1..=6 for G54..G59.
    pub work_system: u8,
}

/// Why an event cannot be sent to Grbl.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EmitError {
    /// A number of the frame or the event is NaN or infinite.
    #[error("{what} is not a finite number: check the program and the alignment")]
    NonFinite {
        /// What it is.
        what: &'static str,
    },
    /// A coordinate, offset, feed, speed or time beyond what Grbl reads exactly.
    #[error("{word} {value} is beyond Grbl's range (±{limit}): move the work offset or the part")]
    BeyondRange {
        /// The word's letter.
        word: char,
        /// The value, in the word's unit (mm, mm/min, rpm, s).
        value: f64,
        /// The limit.
        limit: f64,
    },
    /// A value Grbl refuses (a negative dwell or speed, a feed of zero).
    #[error("{word} {value} is refused by Grbl: it needs a positive value")]
    BadValue {
        /// The word's letter.
        word: char,
        /// The value.
        value: f64,
    },
    /// The frame is not one Grbl has (mm per unit not positive, work system outside 1..=6).
    #[error("the Grbl frame is invalid: {what}")]
    BadFrame {
        /// What is wrong.
        what: &'static str,
    },
    /// A line longer than Grbl's line buffer.
    #[error("the line `{line}` is longer than Grbl's {MAX_LINE} characters")]
    LineTooLong {
        /// The line.
        line: String,
    },
    /// An arc Grbl would refuse or run otherwise, even after its centre was adjusted.
    #[error("the arc of line {line} cannot be written for Grbl: {why}")]
    Arc {
        /// Source line.
        line: u32,
        /// Why.
        why: &'static str,
    },
    /// A user M-code with no handler: the host must run it, the firmware has no such code.
    #[error("M{code} on line {line} has no handler: a vision M-code must run in the host, never on Grbl")]
    UnhandledMCode {
        /// Source line.
        line: u32,
        /// The M number.
        code: u32,
    },
}

/// Turns events into Grbl lines, keeping the firmware's modal state and position as sent.
#[derive(Debug, Clone)]
pub struct Emitter {
    frame: Frame,
    /// The position the firmware holds, work coordinates, micrometres.
    pos: [i64; 3],
    /// The motion mode last sent (0..=3), `None` when unknown.
    motion: Option<u8>,
    /// The plane last sent.
    plane: Option<Plane>,
    /// The feed last sent, thousandths of mm/min.
    feed: Option<i64>,
    /// After M2/M30: the preamble goes out again before the next line.
    reset: bool,
}

impl Emitter {
    /// An emitter for a firmware at machine position `start` (machine units), its parser in
    /// the [`Emitter::preamble`]'s modes.
    ///
    /// # Errors
    /// [`EmitError::BadFrame`], [`EmitError::NonFinite`], or [`EmitError::BeyondRange`] for a
    /// start outside Grbl's range.
    pub fn new(frame: Frame, start: Xyz) -> Result<Emitter, EmitError> {
        if !frame.mm_per_unit.is_finite() || frame.wco.iter().any(|v| !v.is_finite()) {
            return Err(EmitError::NonFinite { what: "the Grbl frame" });
        }
        if !(frame.mm_per_unit > 0.0) {
            return Err(EmitError::BadFrame { what: "millimetres per unit must be positive" });
        }
        if !(1..=6).contains(&frame.work_system) {
            return Err(EmitError::BadFrame { what: "the work system must be 1..=6 (G54..G59)" });
        }
        let mut emitter =
            Emitter { frame, pos: [0; 3], motion: None, plane: Some(Plane::Xy), feed: None, reset: false };
        emitter.pos = emitter.work_um(start, "the start position")?;
        Ok(emitter)
    }

    /// The line that puts the firmware's parser in the emitter's modes: mm, absolute, units per
    /// minute, G17, and the work system.
    #[must_use]
    pub fn preamble(&self) -> Vec<String> {
        vec![format!("G21 G90 G94 G17 G{}", 53 + self.frame.work_system)]
    }

    /// The lines for one event (possibly none). A failing event changes nothing.
    ///
    /// # Errors
    /// [`EmitError`]: a non-finite or out-of-range number, a line too long, an arc Grbl would
    /// refuse, a user M-code.
    pub fn event(&mut self, event: &Event) -> Result<Vec<String>, EmitError> {
        let mut next = self.clone();
        let mut lines = next.lines(event)?;
        if next.reset && !lines.is_empty() && !matches!(event, Event::ProgramEnd { .. }) {
            // Grbl's M2/M30 reset its parser to G54, G17, G90, G94 and G1.
            let mut all = self.preamble();
            all.append(&mut lines);
            lines = all;
            next.reset = false;
        }
        for line in &mut lines {
            fit(line)?;
        }
        *self = next;
        Ok(lines)
    }

    fn lines(&mut self, event: &Event) -> Result<Vec<String>, EmitError> {
        let mut out = Vec::new();
        match event {
            Event::Linear(m) => self.linear(m, &mut out)?,
            Event::Arc(a) => self.arc(a, &mut out)?,
            Event::Dwell { seconds, .. } => out.push(format!("G4 P{}", value('P', *seconds)?)),
            Event::Spindle { command, speed, .. } => match speed {
                Some(s) if command.is_on() => out.push(format!("{} S{}", command.gcode(), value('S', *s)?)),
                _ => out.push(command.gcode().to_string()),
            },
            Event::Output(o) => out.push(o.command.gcode().to_string()),
            Event::Coolant { coolant, .. } => out.push(coolant.gcode().to_string()),
            Event::Stop { optional, .. } => out.push(if *optional { "M1" } else { "M0" }.to_string()),
            Event::ProgramEnd { code, .. } => {
                out.push(if *code == 30 { "M30" } else { "M2" }.to_string());
                self.motion = None;
                self.plane = Some(Plane::Xy);
                self.feed = None;
                self.reset = true;
            }
            Event::ToolChange { .. } => {}
            Event::UserMCode(call) => return Err(EmitError::UnhandledMCode { line: call.line, code: call.code }),
        }
        Ok(out)
    }

    /// Where the lines sent so far leave the machine, machine coordinates in mm (the firmware's
    /// `MPos`): the work position as sent plus the frame's offset.
    #[must_use]
    pub fn machine_mm(&self) -> [f64; 3] {
        std::array::from_fn(|i| {
            #[expect(clippy::cast_precision_loss, reason = "Micrometres within ±1e8: exact in an f64.")]
            let mm = self.pos[i] as f64 / 1000.0;
            mm + self.frame.wco[i]
        })
    }

    /// A machine position (machine units) as the firmware's work coordinates, micrometres.
    fn work_um(&self, p: Xyz, what: &'static str) -> Result<[i64; 3], EmitError> {
        let k = self.frame.mm_per_unit;
        let w = [p.x * k - self.frame.wco[0], p.y * k - self.frame.wco[1], p.z * k - self.frame.wco[2]];
        if w.iter().any(|v| !v.is_finite()) {
            return Err(EmitError::NonFinite { what });
        }
        let mut out = [0; 3];
        for (i, v) in w.into_iter().enumerate() {
            out[i] = um(AXES[i], v)?;
        }
        Ok(out)
    }

    /// The feed word for `feed` (machine units per minute), `None` when it is the one sent.
    fn feed_word(&mut self, feed: f64) -> Result<Option<String>, EmitError> {
        let mm = feed * self.frame.mm_per_unit;
        if !mm.is_finite() {
            return Err(EmitError::NonFinite { what: "the feed" });
        }
        let text = value('F', mm)?;
        let thousandths = thousandths(mm);
        if thousandths <= 0 {
            return Err(EmitError::BadValue { word: 'F', value: mm });
        }
        if self.feed == Some(thousandths) {
            return Ok(None);
        }
        self.feed = Some(thousandths);
        Ok(Some(format!("F{text}")))
    }

    /// The motion word when it changes.
    fn motion_word(&mut self, motion: u8) -> Option<String> {
        (self.motion != Some(motion)).then(|| {
            self.motion = Some(motion);
            format!("G{motion}")
        })
    }

    fn linear(&mut self, m: &LinearMove, out: &mut Vec<String>) -> Result<(), EmitError> {
        let end = self.work_um(m.end, "the end of a move")?;
        let feed = match m.rate {
            Rate::Rapid => None,
            Rate::Feed(f) => Some(f),
        };
        self.line_to(end, feed, out)
    }

    /// A straight move to `end` (work, µm) at `feed` (machine units/min; `None`: rapid);
    /// nothing when no axis changes.
    fn line_to(&mut self, end: [i64; 3], feed: Option<f64>, out: &mut Vec<String>) -> Result<(), EmitError> {
        if end == self.pos {
            return Ok(());
        }
        let mut words = Vec::new();
        words.extend(self.motion_word(u8::from(feed.is_some())));
        for i in 0..3 {
            if end[i] != self.pos[i] {
                words.push(format!("{}{}", AXES[i], fmt_um(end[i])));
            }
        }
        if let Some(f) = feed {
            words.extend(self.feed_word(f)?);
        }
        self.pos = end;
        out.push(words.join(" "));
        Ok(())
    }

    /// The plane line when the plane changes.
    fn select_plane(&mut self, plane: Plane, out: &mut Vec<String>) {
        if self.plane != Some(plane) {
            self.plane = Some(plane);
            out.push(plane.gcode().to_string());
        }
    }
}

/// The axis letters.
const AXES: [char; 3] = ['X', 'Y', 'Z'];
/// The offset letters.
const OFFSETS: [char; 3] = ['I', 'J', 'K'];

/// `v` (mm) in whole micrometres, after the range check.
#[expect(clippy::cast_possible_truncation, reason = "checked within ±99 999 mm first: at most 10^8 µm")]
fn um(word: char, v: f64) -> Result<i64, EmitError> {
    if !v.is_finite() {
        return Err(EmitError::NonFinite { what: "a coordinate" });
    }
    if v.abs() > MAX_COORDINATE_MM {
        return Err(EmitError::BeyondRange { word, value: v, limit: MAX_COORDINATE_MM });
    }
    Ok((v * 1000.0).round() as i64)
}

/// `v` in thousandths, for a value checked within [`MAX_VALUE`].
#[expect(clippy::cast_possible_truncation, reason = "checked within 10^8 first: at most 10^11")]
fn thousandths(v: f64) -> i64 {
    (v * 1000.0).round() as i64
}

/// A feed, speed or dwell as written: finite, not negative, within [`MAX_VALUE`], 3 decimals.
fn value(word: char, v: f64) -> Result<String, EmitError> {
    if !v.is_finite() {
        return Err(EmitError::NonFinite { what: "a feed, speed or dwell" });
    }
    if v < 0.0 {
        return Err(EmitError::BadValue { word, value: v });
    }
    if v > MAX_VALUE {
        return Err(EmitError::BeyondRange { word, value: v, limit: MAX_VALUE });
    }
    Ok(fmt_um(thousandths(v)))
}

/// Thousandths as a decimal with at most 3 decimals, no trailing zeros, no `-0`.
fn fmt_um(v: i64) -> String {
    let sign = if v < 0 { "-" } else { "" };
    let (int, frac) = (v.unsigned_abs() / 1000, v.unsigned_abs() % 1000);
    if frac == 0 {
        format!("{sign}{int}")
    } else {
        let digits = format!("{frac:03}");
        format!("{sign}{int}.{}", digits.trim_end_matches('0'))
    }
}

/// Keeps `line` within [`MAX_LINE`]: without its spaces if need be (Grbl ignores them).
fn fit(line: &mut String) -> Result<(), EmitError> {
    if line.len() > MAX_LINE {
        line.retain(|c| c != ' ');
    }
    if line.len() > MAX_LINE {
        return Err(EmitError::LineTooLong { line: line.clone() });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_written_short_and_exact() {
        assert_eq!(fmt_um(0), "0");
        assert_eq!(fmt_um(-1500), "-1.5");
        assert_eq!(fmt_um(99_999_999), "99999.999");
        assert_eq!(fmt_um(-7), "-0.007");
        assert_eq!(um('X', -0.0004), Ok(0));
        assert!(matches!(um('X', 99_999.5), Err(EmitError::BeyondRange { word: 'X', .. })));
        assert!(matches!(value('P', -1.0), Err(EmitError::BadValue { word: 'P', .. })));
        assert!(matches!(value('F', f64::NAN), Err(EmitError::NonFinite { .. })));
    }

    #[test]
    fn a_long_line_loses_its_spaces_then_is_refused() {
        let mut line = format!("G1 {}", "X1 ".repeat(30));
        fit(&mut line).expect("fits without spaces");
        assert!(line.len() <= MAX_LINE && !line.contains(' '));
        let mut line = "X1".repeat(40);
        assert!(matches!(fit(&mut line), Err(EmitError::LineTooLong { .. })));
    }

    #[test]
    fn the_frame_is_checked() {
        let frame = Frame { mm_per_unit: 1.0, wco: [0.0; 3], work_system: 7 };
        assert!(matches!(Emitter::new(frame, Xyz::ZERO), Err(EmitError::BadFrame { .. })));
        let frame = Frame { mm_per_unit: 0.0, work_system: 1, ..frame };
        assert!(matches!(Emitter::new(frame, Xyz::ZERO), Err(EmitError::BadFrame { .. })));
        let frame = Frame { mm_per_unit: f64::NAN, ..frame };
        assert!(matches!(Emitter::new(frame, Xyz::ZERO), Err(EmitError::NonFinite { .. })));
        let frame = Frame { mm_per_unit: 1.0, wco: [0.0; 3], work_system: 2 };
        assert!(matches!(Emitter::new(frame, Xyz::new(1e6, 0.0, 0.0)), Err(EmitError::BeyondRange { .. })));
        assert_eq!(Emitter::new(frame, Xyz::ZERO).expect("valid").preamble(), ["G21 G90 G94 G17 G55"]);
    }
}
