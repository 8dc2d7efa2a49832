//! What the interpreter tells the machine: events in machine coordinates, each tagged with its
//! source line, streamed to an [`EventSink`] (never collected by the interpreter).

use crate::arc::Arc;
use crate::geom::{ArcDirection, Plane, Xyz};

/// How fast a move is asked to go (also the planner's input, `vision_path::Segment::rate`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Rate {
    /// G0: as fast as the machine's axes allow (any `F` on the line is only remembered).
    Rapid,
    /// G1, G2/G3 and arc polylines: feed `F`, machine units per minute (G94).
    Feed(f64),
}

/// Path control (G61 / G64) at the end of a move: how the planner treats the corner there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PathMode {
    /// G61: stop exactly at every corner; tangent (e.g. co-linear) joins do not stop.
    ExactStop,
    /// G64: blend corners. `tolerance` is the `P` word, machine units: the largest distance
    /// the path may pass from the programmed corner point. `None` (G64 without `P`) sets no
    /// distance: the planner limits a blend only by its own rules (`vision_path`: at most
    /// half of each neighbouring segment). `Some(0.0)` allows no deviation, i.e. G61.
    Blend {
        /// The `P` tolerance, machine units.
        tolerance: Option<f64>,
    },
}

/// A straight move (G0, G1, one segment of an arc polyline, or a G28 leg).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearMove {
    /// Source line (for handler G-code: the M-code's line).
    pub line: u32,
    /// Machine position before the move, machine units.
    pub start: Xyz,
    /// Machine position after the move, machine units.
    pub end: Xyz,
    /// Rapid or feed.
    pub rate: Rate,
    /// Path control at the end of the move.
    pub path: PathMode,
}

/// A circular or helical arc, exact in machine coordinates.
///
/// The arc turns about `center` in `plane` by `angle` radians in `direction` (seen from the
/// plane normal's positive side, see [`Plane`]); the in-plane radius goes linearly from
/// `|start − center|` to `|end − center|` (they agree within the interpreter's tolerance) and
/// the normal axis linearly from `start` to `end` (a helix when they differ).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcMove {
    /// Source line.
    pub line: u32,
    /// Machine position before the move, machine units.
    pub start: Xyz,
    /// Machine position after the move, machine units.
    pub end: Xyz,
    /// The centre, machine units; its normal-axis coordinate is `start`'s.
    pub center: Xyz,
    /// The plane.
    pub plane: Plane,
    /// The sense in machine coordinates (a mirroring G51 reverses the programmed one).
    pub direction: ArcDirection,
    /// Total swept angle, radians, > 0; more than 2π for multi-turn arcs (G2/G3 `P`).
    pub angle: f64,
    /// Feed, machine units per minute.
    pub feed: f64,
    /// Path control at the end of the move.
    pub path: PathMode,
}

impl ArcMove {
    /// Whole turns beyond the first partial one (0 for an ordinary arc or one full circle).
    #[must_use]
    pub fn extra_turns(&self) -> u32 {
        let turns = (self.angle / std::f64::consts::TAU - 1e-9).floor();
        if turns > 0.0 {
            #[expect(
                clippy::cast_possible_truncation,
                clippy::cast_sign_loss,
                reason = "A finite, non-negative count far below u32::MAX for any real arc."
            )]
            {
                turns as u32
            }
        } else {
            0
        }
    }

    /// The machine position at fraction `t` (0 … 1) of the swept angle.
    #[must_use]
    pub fn point_at(&self, t: f64) -> Xyz {
        let (a, b, _) = self.plane.axes();
        let center = (self.center.axis(a), self.center.axis(b));
        Arc::through(self.plane, self.start, self.end, center, self.direction, self.angle).point_along(t)
    }
}

/// M3 / M4 / M5: what a tool (or an explicit `A… P…` port) is driven to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SpindleCommand {
    /// M3: clockwise (the tool's clockwise output active; an explicit port high).
    Clockwise,
    /// M4: counter-clockwise (the tool's counter-clockwise output active; an explicit port
    /// high).
    CounterClockwise,
    /// M5: stop (both of the tool's outputs inactive; an explicit port low).
    Stop,
}

impl SpindleCommand {
    /// The M-code: `"M3"`, `"M4"` or `"M5"`.
    #[must_use]
    pub fn gcode(self) -> &'static str {
        match self {
            SpindleCommand::Clockwise => "M3",
            SpindleCommand::CounterClockwise => "M4",
            SpindleCommand::Stop => "M5",
        }
    }

    /// Whether the command switches something on (M3, M4) rather than off (M5).
    #[must_use]
    pub fn is_on(self) -> bool {
        self != SpindleCommand::Stop
    }
}

/// One digital output set high or low.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct OutputWrite {
    /// Digital I/O module device id.
    pub device: u32,
    /// Port on the device.
    pub port: u32,
    /// The level written: `true` = high (24 V).
    pub high: bool,
}

/// What an M3/M4/M5 does to the digital outputs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OutputChange {
    /// Source line.
    pub line: u32,
    /// The command.
    pub command: SpindleCommand,
    /// The tool acted on (implicit form: `$n` or the active tool), `None` for the explicit
    /// `A<device> P<port>` form.
    pub tool: Option<u32>,
    /// The outputs written, in order (empty when the tool has no outputs wired).
    pub writes: Vec<OutputWrite>,
}

/// M7 / M8 / M9.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Coolant {
    /// M7: mist on.
    Mist,
    /// M8: flood on.
    Flood,
    /// M9: all coolant off.
    Off,
}

impl Coolant {
    /// The M-code: `"M7"`, `"M8"` or `"M9"`.
    #[must_use]
    pub fn gcode(self) -> &'static str {
        match self {
            Coolant::Mist => "M7",
            Coolant::Flood => "M8",
            Coolant::Off => "M9",
        }
    }
}

/// A user M-code met with no handler attached (reported, not executed).
#[derive(Debug, Clone, PartialEq)]
pub struct UserCall {
    /// Source line.
    pub line: u32,
    /// The M number.
    pub code: u32,
    /// The line's other words, letter and evaluated value, in alphabetical order (`$` last).
    pub words: Vec<(char, f64)>,
    /// The line's comments.
    pub comments: Vec<String>,
}

/// One thing the machine must do, in machine coordinates (machine units).
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// A straight move.
    Linear(LinearMove),
    /// An exact arc.
    Arc(ArcMove),
    /// G4: stay in place.
    Dwell {
        /// Source line.
        line: u32,
        /// Time, seconds.
        seconds: f64,
    },
    /// M6: the tool changed (the machine does not move; the offsets apply from the next move).
    ToolChange {
        /// Source line.
        line: u32,
        /// The new tool (0 = none).
        tool: u32,
        /// Its X/Y offset and Z length, machine units.
        offset: Xyz,
    },
    /// M3 / M4 / M5 acting on a tool's outputs (the tool named by `$n` or loaded by M6) or on an
    /// explicit port.
    Output(OutputChange),
    /// M3 / M4 / M5 with no tool loaded and no `$n` or port: a plain spindle, as in CAM
    /// programs (`M3 S12000`). Nothing is wired to it here; a host with a spindle drives it.
    Spindle {
        /// Source line.
        line: u32,
        /// Start clockwise, counter-clockwise, or stop.
        command: SpindleCommand,
        /// The last `S` (revolutions per minute), `None` before any.
        speed: Option<f64>,
    },
    /// M7 / M8 / M9.
    Coolant {
        /// Source line.
        line: u32,
        /// Which coolant, or off.
        coolant: Coolant,
    },
    /// M0 (program stop) or M1 (optional stop): the host decides whether to wait.
    Stop {
        /// Source line.
        line: u32,
        /// `true` for M1.
        optional: bool,
    },
    /// M2 / M30: the program is over.
    ProgramEnd {
        /// Source line.
        line: u32,
        /// 2 or 30.
        code: u32,
    },
    /// A user M-code with no handler attached.
    UserMCode(UserCall),
}

impl Event {
    /// The source line of the event.
    #[must_use]
    pub fn line(&self) -> u32 {
        match self {
            Event::Linear(m) => m.line,
            Event::Arc(a) => a.line,
            Event::Output(o) => o.line,
            Event::UserMCode(c) => c.line,
            Event::Dwell { line, .. }
            | Event::ToolChange { line, .. }
            | Event::Spindle { line, .. }
            | Event::Coolant { line, .. }
            | Event::Stop { line, .. }
            | Event::ProgramEnd { line, .. } => *line,
        }
    }

    /// The machine position after the event, for motion events.
    #[must_use]
    pub fn end(&self) -> Option<Xyz> {
        match self {
            Event::Linear(m) => Some(m.end),
            Event::Arc(a) => Some(a.end),
            _ => None,
        }
    }
}

/// Where events go.
pub trait EventSink {
    /// Receives one event, in program order.
    fn event(&mut self, event: &Event);
}

impl<F: FnMut(&Event)> EventSink for F {
    fn event(&mut self, event: &Event) {
        self(event);
    }
}

/// Collecting into a `Vec` is the caller's choice (tests, short programs).
impl EventSink for Vec<Event> {
    fn event(&mut self, event: &Event) {
        self.push(event.clone());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_points_and_turns() {
        let arc = ArcMove {
            line: 1,
            start: Xyz::new(1.0, 0.0, 0.0),
            end: Xyz::new(1.0, 0.0, 2.0),
            center: Xyz::ZERO,
            plane: Plane::Xy,
            direction: ArcDirection::CounterClockwise,
            angle: 4.0 * std::f64::consts::PI,
            feed: 10.0,
            path: PathMode::ExactStop,
        };
        assert_eq!(arc.extra_turns(), 1);
        let quarter = arc.point_at(0.125);
        assert!((quarter.x).abs() < 1e-12 && (quarter.y - 1.0).abs() < 1e-12 && (quarter.z - 0.25).abs() < 1e-12);
        let cw = ArcMove { direction: ArcDirection::Clockwise, angle: std::f64::consts::FRAC_PI_2, ..arc };
        assert_eq!(cw.extra_turns(), 0);
        assert!((cw.point_at(1.0).y + 1.0).abs() < 1e-12);
    }
}
