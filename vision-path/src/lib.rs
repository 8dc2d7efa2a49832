//! Path following (seed 002, SPEC §6): turn a program's motion into time-stamped setpoints at
//! a fixed period, within a maximum path acceleration and each axis's speed and acceleration,
//! with exact-stop (G61) and blended (G64 P) corners, arcs, dwells and tool outputs.
//!
//! * Input: [`Item`]s in program order — [`Segment`]s (lines and arcs in machine coordinates,
//!   with their feed or rapid and their path-control mode), dwells, events (M3/M4/M5, T/M6),
//!   the end. Errors from the item source travel in the same stream.
//! * Output: [`Setpoints`], an iterator of [`Step`]s — one [`Setpoint`] per period
//!   (time, position, velocity, line) with [`TimedEvent`]s in between — holding only a
//!   bounded look-ahead window, so a million-line program streams in constant memory.
//! * G-code: [`GcodeItems`] runs a program on the `vision-gcode` interpreter one line at a
//!   time and turns its events into items (the table of what becomes what is on the type).
//! * The seed's API: [`PathFollower`] — configure the axis → drive map ([`AxisMap`]) and the
//!   tools ([`ToolTable`]), `start` / [`PathFollower::start_gcode`] with a maximum path
//!   acceleration, poll [`PathFollower::status`], [`PathFollower::stop`]; setpoints (as drive
//!   positions) and output writes go to a [`MotionSink`], in real time or scaled ([`Pace`]).
//!
//! Units: positions in the machine unit (mm or inch, whatever the machine runs in), feed `F`
//! in machine units per minute (G94), speeds in units/s, accelerations in units/s² (the seed's
//! `maxPathAcceleration` is mm/s² on a metric machine), times in seconds.
//!
//! ```
//! use vision_path::{Item, Limits, PathMode, PlanConfig, Rate, Segment, Setpoints, Shape, Xyz};
//!
//! // One 100 mm feed move at F6000 (100 mm/s), a = 1000 mm/s², 1 ms setpoints.
//! let config = PlanConfig::new(Limits::uniform(1000.0, 500.0, 1000.0), 0.001, Xyz::ZERO);
//! let program = vec![Item::Move(Segment {
//!     line: 1,
//!     start: Xyz::ZERO,
//!     end: Xyz::new(100.0, 0.0, 0.0),
//!     shape: Shape::Line,
//!     rate: Rate::Feed(6000.0),
//!     mode: PathMode::ExactStop,
//! })];
//! let summary = Setpoints::from_items(&config, program)?.run_to_end()?;
//! // Trapezoid: 0.1 s up, 0.9 s at 100 mm/s, 0.1 s down.
//! assert!((summary.cycle_time - 1.1).abs() < 1e-9);
//! assert_eq!(summary.end, Xyz::new(100.0, 0.0, 0.0));
//! # Ok::<(), vision_path::PathError>(())
//! ```
//!
//! # The limits, precisely
//!
//! The setpoints are samples at `t = k·T` of one continuous trajectory `p(t)` along which:
//!
//! * the acceleration **vector** (tangential + centripetal) has length ≤ `max_path_accel`,
//!   and each of its X, Y, Z components ≤ that axis's `max_accel`;
//! * the velocity's X, Y, Z components ≤ each axis's `max_speed`, and the path speed ≤ the
//!   programmed feed (rapids: only the axes bound them).
//!
//! Because `p(t+T) − p(t) = ∫ v` and `p(t+T) − 2p(t) + p(t−T) = ∫ a(τ)·(T − |τ − t|) dτ`
//! (a triangle of area T²), the samples obey, for the path and per axis:
//! `|Δp| ≤ v_max·T` and `|Δ²p| ≤ a_max·T²`. The stated tolerance for the sampled bounds is
//! `(1 + 10⁻⁶)·bound + 10⁻⁹` units: floating-point rounding, plus the velocity jump allowed at
//! "tangent" joins (direction change ≤ 10⁻⁹ rad).
//!
//! How the limits are shared out:
//!
//! * A line at direction `u` moves at most `min(feed, max_speed_i/|u_i|)` and accelerates at
//!   most `min(max_path_accel, max_accel_i/|u_i|)`.
//! * On an arc or blend of curvature `κ`, the speed is capped so that the centripetal part
//!   `κ·v²` uses at most `√3/2` of `max_path_accel` (and half of each axis's `max_accel`);
//!   the tangential acceleration is what remains in quadrature (≥ ½ of it), and per axis what
//!   remains linearly. Helices and spirals use conservative bounds of the same form.
//! * Velocity planning is trapezoidal along the path (no jerk limit), with look-ahead over a
//!   bounded window (see `PlanConfig::lookahead`): the planner can always stop at the end of
//!   what it has read, so it never needs to see further than a braking distance.
//!
//! # Decisions
//!
//! * **G61** stops exactly (zero speed, position bit-exact) at every join whose direction
//!   changes by more than 10⁻⁹ rad; co-linear and exactly tangent joins (line into a tangent
//!   arc) pass at speed. Corners are held until the next sample instant, so every stop point
//!   is a setpoint (this costs at most one period per stop).
//! * **G64 P** is "the path passes within P of the programmed corner point" (the seed's
//!   wording) *and* stays within P of the programmed path. Two lines: one circular arc,
//!   exact. A corner with an arc: a biarc, searched by bisection and checked against the
//!   programmed path. A blend is only as large as keeps the neighbours' speed (its centripetal
//!   limit allows it), and never uses more than half of a neighbouring segment. G64 without P:
//!   only those two rules. `P0` behaves as G61. Corners sharper than π − 10⁻⁶ (reversals) and
//!   corners touching a helix stop instead of blending.
//! * The mode that governs a corner is the one of the segment that *ends* there.
//! * **Events** (M3/M4/M5, T/M6) and **dwells** are exact stops: the machine comes to rest at
//!   the programmed point, the event is emitted right after that setpoint, motion resumes.
//!   A dwell of `P` seconds holds for `P` rounded up to the next period.
//! * **Errors** travel in the stream at their place: the motion before the bad line is
//!   finished and brought to rest, then the error is delivered — never a jump, never a NaN.
//! * **Stop** ([`Setpoints::stop`]) brakes along the path at each piece's tangential limit
//!   (so the full bounds still hold) and ends at rest; later events do not happen.
//! * **Rapids** (G0) move at the axes' maximum speed (any F on the line is only remembered).
//! * **M0/M1** and user M-codes (reported, never executed: see [`GcodeItems`]) are exact stops (a
//!   zero-second dwell); the follower does not wait for an operator.
//! * **Tools**: a bare M3/M4/M5 acts on the tool of the last `T… M6`; `M3 $n` acts on `n`
//!   without selecting it (as the interpreter does); a tool wired to no outputs writes nothing
//!   (as in the interpreter). Switching a tool on first drives its other direction inactive.
//!   When a followed path ends — completed, stopped or failed — every output it drove active is
//!   driven inactive (as M2/M30 stop a spindle). Seed 002 says nothing about outputs when a path
//!   stops or fails; leaving a tool running on a machine at rest is the unsafe choice.
//! * **Axes**: a move of an axis no drive is mapped to is an error at its line; the follower's
//!   `start_gcode` checks the whole program (streaming, no handler) before anything moves.
//! * Arcs whose start and end radius differ slightly (rounded G-code) are spirals with
//!   linearly changing radius. They are blended and joined like circles; their path
//!   parameter runs at exactly the real speed at both ends (and at the ends of any part a
//!   blend cuts out of them), so the planned speed is the real speed at every join.
//! * An arc turns by the sweep it is given ([`ArcShape::sweep`]: the interpreter's angle), never
//!   by a rule of the planner's own: an end 10⁻⁸ mm past the start is a sliver or a full
//!   circle exactly as the interpreter decided. A sweep that does not reach the end point is
//!   refused at its line.

mod blend;
mod curve;
mod error;
mod follower;
mod gcode;
mod input;
mod limits;
mod lookahead;
mod profile;
mod sampler;
mod shaper;
mod tools;

pub use error::PathError;
pub use follower::{
    Axis, AxisMap, DrivePosition, FollowerConfig, MotionSink, Pace, PathFollower, PathStatus, RunState,
};
pub use gcode::{item, GcodeItems};
pub use input::{ArcShape, Event, Item, OutputCommand, Segment, Shape};
pub use limits::{AxisLimits, Limits, PlanConfig};
pub use sampler::{Setpoint, Setpoints, Step, Summary, TimedEvent};
/// The interpreter's types this crate's API uses as they are: positions and directions
/// ([`Xyz`], machine units), a segment's [`Rate`] (feed in machine units per minute, or rapid)
/// and [`PathMode`] (G61, or G64 with `P` in machine units), an output event's
/// [`SpindleCommand`] (M3/M4/M5), the [`ToolTable`] (a [`Tool`]'s [`ToolOutputs`], its
/// [`DigitalOutput`]s) and the [`OutputWrite`]s a [`MotionSink`] receives.
pub use vision_gcode::{DigitalOutput, OutputWrite, PathMode, Rate, SpindleCommand, Tool, ToolOutputs, ToolTable, Xyz};
