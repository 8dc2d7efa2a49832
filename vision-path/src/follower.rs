//! The seed's path-following API: configure the axis → drive map and the tools
//! (`configPathMode`), start a path with a maximum path acceleration (`startPath`), poll it
//! (`getPathStatus`), stop it (`stopPath`).
//!
//! A [`PathFollower`] runs the setpoint stream on a background thread and hands each setpoint
//! (as drive positions) and each output write to a [`MotionSink`] — the drives and the I/O
//! modules, or a simulator. [`Pace`] sets how fast: real time, a multiple of it, or as fast
//! as the sink takes them.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use vision_gcode::{OutputWrite, ToolTable, Xyz};

use crate::input::{Event, Item, Segment, Shape};
use crate::limits::{AxisLimits, Limits, PlanConfig};
use crate::sampler::{Setpoint, Setpoints, Step};
use crate::tools;
use crate::PathError;

/// A G-code axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Axis {
    /// X.
    X,
    /// Y.
    Y,
    /// Z.
    Z,
}

impl Axis {
    /// All three, in order.
    pub const ALL: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];

    fn index(self) -> usize {
        self as usize
    }

    fn letter(self) -> char {
        ['X', 'Y', 'Z'][self.index()]
    }
}

/// Which drive each axis is mapped to (seed: `driveAssociation = {"X": 1, "Y": 3}`). For
/// synchronised drives, map the parent drive. An unmapped axis must not move.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AxisMap {
    drives: [Option<u32>; 3],
}

impl AxisMap {
    /// The map from `(axis, drive)` pairs; an axis or a drive given twice is refused.
    pub fn new(pairs: &[(Axis, u32)]) -> Result<AxisMap, PathError> {
        let mut map = AxisMap::default();
        for &(axis, drive) in pairs {
            if map.drives[axis.index()].is_some() {
                return Err(PathError::BadMapping(format!(
                    "axis {} is mapped twice; map each axis once",
                    axis.letter()
                )));
            }
            if let Some(other) = Axis::ALL.iter().find(|a| map.drives[a.index()] == Some(drive)) {
                return Err(PathError::BadMapping(format!(
                    "drive {drive} is mapped to both {} and {}; map each drive to one axis (the parent of synchronised drives)",
                    other.letter(),
                    axis.letter()
                )));
            }
            map.drives[axis.index()] = Some(drive);
        }
        Ok(map)
    }

    /// The drive mapped to `axis`.
    pub fn drive(&self, axis: Axis) -> Option<u32> {
        self.drives[axis.index()]
    }
}

/// One drive's target position, machine units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrivePosition {
    /// Drive number.
    pub drive: u32,
    /// Target position, machine units.
    pub position: f64,
}

/// Where setpoints and output writes go: the drives and I/O modules, or a simulator.
pub trait MotionSink: Send {
    /// One setpoint, with the mapped drives' positions. An error halts the path at once.
    fn setpoint(&mut self, setpoint: &Setpoint, drives: &[DrivePosition]) -> Result<(), String>;
    /// One digital output write. An error halts the path.
    fn output(&mut self, write: OutputWrite) -> Result<(), String>;
}

/// How fast the follower feeds the sink.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Pace {
    /// One setpoint per period of wall-clock time.
    RealTime,
    /// `k` times real time (`k > 0`): tests and simulations that must not sleep for real.
    Scaled(f64),
    /// As fast as the sink accepts setpoints.
    Unpaced,
}

/// The follower's configuration (seed: `configPathMode` plus each drive's limits).
#[derive(Debug, Clone, PartialEq)]
pub struct FollowerConfig {
    /// Axis → drive.
    pub axes: AxisMap,
    /// The tools (the interpreter's table; only their outputs matter here).
    pub tools: ToolTable,
    /// X, Y, Z speed and acceleration limits (those of the mapped drives).
    pub axis_limits: [AxisLimits; 3],
    /// Setpoint period, seconds.
    pub period: f64,
    /// Look-ahead window, pieces (see [`PlanConfig::lookahead`]).
    pub lookahead: usize,
    /// Where the machine is before the first path, machine units.
    pub start: Xyz,
}

impl FollowerConfig {
    /// A configuration with a 1 ms period, the default look-ahead and the machine at 0, 0, 0.
    pub fn new(axes: AxisMap, tools: ToolTable, axis_limits: [AxisLimits; 3]) -> FollowerConfig {
        FollowerConfig {
            axes,
            tools,
            axis_limits,
            period: 0.001,
            lookahead: PlanConfig::DEFAULT_LOOKAHEAD,
            start: Xyz::ZERO,
        }
    }
}

/// Where a path is in its life.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunState {
    /// No path started yet.
    Idle,
    /// Moving (or dwelling) along the path.
    Running,
    /// Braking after [`PathFollower::stop`].
    Stopping,
    /// The path ran to its end.
    Completed,
    /// Stopped on request.
    Stopped,
    /// Halted by an error ([`PathStatus::error`]).
    Failed,
}

/// The seed's `getPathStatus`.
#[derive(Debug, Clone, PartialEq)]
pub struct PathStatus {
    /// Where the path is in its life.
    pub state: RunState,
    /// Source line of the last setpoint sent.
    pub line: usize,
    /// Position of the last setpoint sent, machine units.
    pub position: Xyz,
    /// Path time of the last setpoint sent, seconds since the start.
    pub elapsed: f64,
    /// Why the path failed, when it did.
    pub error: Option<PathError>,
}

impl PathStatus {
    /// Whether a path is still moving (running or braking).
    pub fn running(&self) -> bool {
        matches!(self.state, RunState::Running | RunState::Stopping)
    }
}

struct Shared {
    status: Mutex<PathStatus>,
    stop: AtomicBool,
}

impl Shared {
    fn status(&self) -> MutexGuard<'_, PathStatus> {
        self.status.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

/// Runs paths on a background thread; see the module docs.
///
/// At the end of every path — completed, stopped or failed — each output the path drove
/// active is driven inactive again (as M2/M30 stop the spindle).
pub struct PathFollower {
    config: FollowerConfig,
    shared: Arc<Shared>,
    worker: Option<JoinHandle<()>>,
}

impl PathFollower {
    /// A follower with this configuration (limits and period are checked here).
    pub fn new(config: FollowerConfig) -> Result<PathFollower, PathError> {
        plan_config(&config, 1.0).validate()?;
        let status = PathStatus { state: RunState::Idle, line: 0, position: config.start, elapsed: 0.0, error: None };
        Ok(PathFollower {
            config,
            shared: Arc::new(Shared { status: Mutex::new(status), stop: AtomicBool::new(false) }),
            worker: None,
        })
    }

    /// Start following `items` from where the last path left the machine, under
    /// `max_path_accel` (units/s²), feeding `sink` at `pace`. Refused while a path runs.
    ///
    /// Errors in the items (including a move of an unmapped axis, an unknown tool) halt the
    /// path at their place, at rest; [`PathFollower::status`] then reports them.
    pub fn start<I, S>(&mut self, items: I, max_path_accel: f64, sink: S, pace: Pace) -> Result<(), PathError>
    where
        I: IntoIterator<Item = Result<Item, PathError>>,
        I::IntoIter: Send + 'static,
        S: MotionSink + 'static,
    {
        if self.status().running() {
            return Err(PathError::AlreadyRunning);
        }
        if let Pace::Scaled(k) = pace {
            if !(k.is_finite() && k > 0.0) {
                return Err(PathError::InvalidConfig {
                    what: "pace factor",
                    value: k,
                    reason: "must be greater than 0",
                });
            }
        }
        self.join();
        let mut config = plan_config(&self.config, max_path_accel);
        config.start = self.status().position;
        let axes = self.config.axes;
        let checked = items.into_iter().map(move |r| r.and_then(|item| check_axes(&axes, item)));
        let stream = Setpoints::new(&config, checked)?;
        {
            let mut status = self.shared.status();
            *status = PathStatus { state: RunState::Running, error: None, elapsed: 0.0, ..status.clone() };
        }
        self.shared.stop.store(false, Ordering::SeqCst);
        let worker = Worker {
            axes,
            tools: self.config.tools.clone(),
            shared: Arc::clone(&self.shared),
            pace,
            selected: None,
            driven: BTreeMap::new(),
        };
        self.worker = Some(std::thread::spawn(move || worker.run(stream, sink)));
        Ok(())
    }

    /// The configuration.
    pub fn config(&self) -> &FollowerConfig {
        &self.config
    }

    /// The current status (the seed's `getPathStatus`).
    pub fn status(&self) -> PathStatus {
        self.shared.status().clone()
    }

    /// Ask for a controlled stop (brake along the path within the limits) without waiting.
    pub fn request_stop(&self) {
        self.shared.stop.store(true, Ordering::SeqCst);
    }

    /// Stop the path (the seed's `stopPath`): brake along the path within the limits, switch
    /// the path's outputs off, and return the final status once the machine is at rest.
    pub fn stop(&mut self) -> PathStatus {
        self.request_stop();
        self.wait()
    }

    /// Wait until the path has ended and return the final status.
    pub fn wait(&mut self) -> PathStatus {
        self.join();
        self.status()
    }

    fn join(&mut self) {
        if let Some(worker) = self.worker.take() {
            if worker.join().is_err() {
                let mut status = self.shared.status();
                status.state = RunState::Failed;
                status.error = Some(PathError::Sink { message: "the sink panicked".into() });
            }
        }
    }
}

impl Drop for PathFollower {
    fn drop(&mut self) {
        self.stop();
    }
}

fn plan_config(config: &FollowerConfig, max_path_accel: f64) -> PlanConfig {
    PlanConfig {
        limits: Limits { max_path_accel, axes: config.axis_limits },
        period: config.period,
        lookahead: config.lookahead,
        start: config.start,
        max_setpoints: PlanConfig::DEFAULT_MAX_SETPOINTS,
    }
}

/// Refuse a move of an axis no drive is mapped to.
pub(crate) fn check_axes(axes: &AxisMap, item: Item) -> Result<Item, PathError> {
    if let Item::Move(seg) = &item {
        for axis in Axis::ALL {
            if axes.drive(axis).is_none() && moves(seg, axis.index()) {
                return Err(PathError::UnmappedAxis { line: seg.line, axis: axis.letter() });
            }
        }
    }
    Ok(item)
}

/// Whether a segment moves axis `i`: its end differs, or it is an arc whose plane contains
/// (part of) the axis.
#[expect(clippy::float_cmp, reason = "an axis moves when its end differs at all")]
fn moves(seg: &Segment, i: usize) -> bool {
    if seg.end.axis(i) != seg.start.axis(i) {
        return true;
    }
    match seg.shape {
        Shape::Line => false,
        Shape::Arc(arc) => {
            let n = arc.normal;
            n.axis(i) * n.axis(i) < n.dot(n) * (1.0 - 1e-12)
        }
    }
}

struct Worker {
    axes: AxisMap,
    tools: ToolTable,
    shared: Arc<Shared>,
    pace: Pace,
    /// The tool a bare M3/M4/M5 controls (the last `T… M6`).
    selected: Option<u32>,
    /// Last level written per (device, port), and its inactive level.
    driven: BTreeMap<(u32, u32), (bool, bool)>,
}

impl Worker {
    fn run<I: Iterator<Item = Result<Item, PathError>>, S: MotionSink>(
        mut self,
        mut stream: Setpoints<I>,
        mut sink: S,
    ) {
        let began = Instant::now();
        let mut stopping = false;
        let mut outcome = Ok(());
        while let Some(step) = stream.next() {
            if !stopping && self.shared.stop.load(Ordering::SeqCst) {
                stopping = true;
                stream.stop();
                self.shared.status().state = RunState::Stopping;
            }
            let done = match step {
                Ok(Step::Setpoint(s)) => self.send(&s, began, &mut sink),
                Ok(Step::Event(e)) => match e.event {
                    Event::ToolChange(n) => {
                        self.selected = (n != 0).then_some(n);
                        Ok(())
                    }
                    Event::Output(command) => self.output(e.line, command, &mut sink),
                },
                Err(e) => Err(e),
            };
            if let Err(e) = done {
                outcome = Err(e);
                break;
            }
        }
        let off = self.all_off(&mut sink);
        let mut status = self.shared.status();
        match outcome.and(off) {
            Ok(()) => status.state = if stopping { RunState::Stopped } else { RunState::Completed },
            Err(e) => {
                status.state = RunState::Failed;
                status.error = Some(e);
            }
        }
    }

    fn send<S: MotionSink>(&self, s: &Setpoint, began: Instant, sink: &mut S) -> Result<(), PathError> {
        let scale = match self.pace {
            Pace::RealTime => Some(1.0),
            Pace::Scaled(k) => Some(k),
            Pace::Unpaced => None,
        };
        if let Some(k) = scale {
            let due = began + Duration::from_secs_f64(s.time / k);
            let now = Instant::now();
            if due > now {
                std::thread::sleep(due - now);
            }
        }
        let mut drives = [DrivePosition { drive: 0, position: 0.0 }; 3];
        let mut n = 0;
        for axis in Axis::ALL {
            if let Some(drive) = self.axes.drive(axis) {
                drives[n] = DrivePosition { drive, position: s.position.axis(axis.index()) };
                n += 1;
            }
        }
        sink.setpoint(s, &drives[..n]).map_err(|message| PathError::Sink { message })?;
        let mut status = self.shared.status();
        status.line = s.line;
        status.position = s.position;
        status.elapsed = s.time;
        Ok(())
    }

    fn output<S: MotionSink>(
        &mut self,
        line: usize,
        command: crate::OutputCommand,
        sink: &mut S,
    ) -> Result<(), PathError> {
        for w in tools::resolve(&self.tools, line, self.selected, command)? {
            self.write(w, sink)?;
        }
        Ok(())
    }

    fn write<S: MotionSink>(&mut self, w: OutputWrite, sink: &mut S) -> Result<(), PathError> {
        sink.output(w).map_err(|message| PathError::Sink { message })?;
        let inactive = self.inactive_level(w.device, w.port);
        self.driven.insert((w.device, w.port), (w.high, inactive));
        Ok(())
    }

    /// The level that switches a port off: the opposite of a tool's active value; low for a
    /// port that belongs to no tool (the explicit `M3/M4 A… P…` form drives it high).
    fn inactive_level(&self, device: u32, port: u32) -> bool {
        tools::outputs(&self.tools).find(|o| o.device == device && o.port == port).is_some_and(|o| !o.active_high)
    }

    /// Drive every output this path left active inactive.
    fn all_off<S: MotionSink>(&mut self, sink: &mut S) -> Result<(), PathError> {
        let on: Vec<_> = self
            .driven
            .iter()
            .filter(|(_, (level, inactive))| level != inactive)
            .map(|(&(device, port), &(_, inactive))| OutputWrite { device, port, high: inactive })
            .collect();
        for w in on {
            self.write(w, sink)?;
        }
        Ok(())
    }
}
