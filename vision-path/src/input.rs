//! The planner's input: motion segments in machine coordinates and the non-motion items
//! between them, in program order.
//!
//! Lengths are machine units (whatever unit the machine runs in, mm or inch), feeds are
//! machine units per minute (G94), times are seconds. The rate, the path mode and the tool
//! command are the interpreter's own types ([`Rate`], [`PathMode`], [`SpindleCommand`]).

use vision_gcode::{PathMode, Rate, SpindleCommand, Xyz};

/// One item of a program, as the planner consumes it.
#[derive(Debug, Clone, PartialEq)]
pub enum Item {
    /// A straight or circular move.
    Move(Segment),
    /// `G4 P…`: stay at rest for `seconds` (≥ 0). The path stops exactly before it.
    Dwell {
        /// Source line.
        line: usize,
        /// Dwell time, seconds.
        seconds: f64,
    },
    /// A tool / output change or a tool selection. The path stops exactly at the programmed
    /// point, the event is emitted there, and motion resumes.
    Event {
        /// Source line.
        line: usize,
        /// What happens.
        event: Event,
    },
    /// End of program (`M2`/`M30` or the end of the text). Nothing after it is read.
    End {
        /// Source line.
        line: usize,
    },
}

impl Item {
    /// The item's source line.
    pub fn line(&self) -> usize {
        match self {
            Item::Move(s) => s.line,
            Item::Dwell { line, .. } | Item::Event { line, .. } | Item::End { line } => *line,
        }
    }
}

/// One motion segment, start and end in machine coordinates (machine units).
#[derive(Debug, Clone, PartialEq)]
pub struct Segment {
    /// Source line.
    pub line: usize,
    /// Where the move starts (must be where the previous move ended), machine units.
    pub start: Xyz,
    /// Where the move ends, machine units.
    pub end: Xyz,
    /// Straight line or arc.
    pub shape: Shape,
    /// Programmed feed (machine units per minute) or rapid.
    pub rate: Rate,
    /// The path-control mode governing the corner at the *end* of this segment (G64 `P` in
    /// machine units).
    pub mode: PathMode,
}

/// The geometry between `start` and `end`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// A straight line (G0/G1).
    Line,
    /// A circular or helical arc (G2/G3).
    Arc(ArcShape),
}

/// A G2/G3 arc: centre, plane normal and the angle it sweeps. Any displacement along the
/// normal between start and end makes it a helix; a start and end radius that differ slightly
/// (rounded G-code) make it a spiral whose radius changes linearly with angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcShape {
    /// The centre, machine units (its component along `normal` is ignored).
    pub centre: Xyz,
    /// The plane normal, any length: +Z for G17, +Y for G18, +X for G19. Counter-clockwise
    /// (G3) is a positive rotation about it (right-hand rule).
    pub normal: Xyz,
    /// The angle the arc turns about `normal`, radians: positive counter-clockwise (G3),
    /// negative clockwise (G2); beyond ±2π for multi-turn arcs (G2/G3 `P`), ±2π for a full
    /// circle. It is what the interpreter reports (`ArcMove::angle` with the direction's
    /// sign), and it must take the arc from `start` to `end` (within 10⁻⁹ relative to the
    /// coordinates' size), or the segment is refused.
    pub sweep: f64,
}

/// A non-motion event that happens at its place in the path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event {
    /// M3/M4/M5: switch a tool or a digital output.
    Output(OutputCommand),
    /// `T<n> M6`: select tool `n` for later M3/M4/M5 without `$n`.
    ToolChange(u32),
}

/// An output command as programmed (resolved to digital outputs by [`crate::ToolTable`]).
/// Both forms keep the M-code, so an event reads back as the G-code that caused it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputCommand {
    /// The implicit form `M3 [$n]`, `M4 [$n]`, `M5 [$n]`: drive a configured tool.
    Tool {
        /// `$n`; `None` means the tool selected by the last `T… M6`.
        tool: Option<u32>,
        /// M3, M4 or M5.
        command: SpindleCommand,
    },
    /// The explicit form `M3 A<device> P<port>` or `M4 A P` (drive the port high) and `M5 A P`
    /// (drive it low).
    Port {
        /// Digital I/O module device ID.
        device: u32,
        /// Port on the module.
        port: u32,
        /// M3, M4 (high) or M5 (low).
        command: SpindleCommand,
    },
}
