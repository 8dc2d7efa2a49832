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
//! What the limits mean exactly (the bounds every pair and triple of setpoints obeys), how they
//! are shared out on lines, arcs and blends, and every decision taken where seed 002 is open
//! (G61 and G64 P corners, events and dwells as exact stops, errors, stop, rapids, tools, axes,
//! spirals, arc sweeps) are in the repository's `docs/path-planner.md`.

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
