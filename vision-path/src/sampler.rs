//! Sampling the planned path at a fixed period: the setpoint iterator.
//!
//! The setpoints are samples, at `t = k·T`, of one continuous trajectory whose speed and
//! acceleration obey the limits; that is why the sampled bounds hold (see the repository's `docs/path-planner.md`).
//! Every stop is held until the next sample instant, so each stop point (G61 corner, dwell,
//! event, end) is itself a setpoint, exactly at the programmed position, with zero velocity.

use std::collections::VecDeque;

use crate::input::{Event, Item};
use crate::lookahead::{Lookahead, Ready};
use crate::profile::Profile;
use crate::shaper::{Marker, Piece, Shaper};
use crate::{PathError, PlanConfig};
use vision_gcode::Xyz;

/// One setpoint: where the machine must be at `time`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setpoint {
    /// Time since the path started, seconds (a multiple of the period).
    pub time: f64,
    /// Position in machine coordinates (X, Y, Z), machine units.
    pub position: Xyz,
    /// Commanded velocity (X, Y, Z), machine units per second.
    pub velocity: Xyz,
    /// Source line being executed.
    pub line: usize,
}

/// An event (output or tool change) at its time in the stream. It is emitted right after the
/// setpoint of the same time, at which the machine is at rest at the programmed point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimedEvent {
    /// Time since the path started, seconds.
    pub time: f64,
    /// Source line.
    pub line: usize,
    /// What happens.
    pub event: Event,
}

/// One element of the stream.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Step {
    /// A setpoint (one per period, in time order).
    Setpoint(Setpoint),
    /// An event, after the setpoint of its time.
    Event(TimedEvent),
}

/// What a whole run amounted to (see [`Setpoints::run_to_end`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    /// Time of the last setpoint: the cycle time, seconds.
    pub cycle_time: f64,
    /// Number of setpoints.
    pub setpoints: u64,
    /// Number of events.
    pub events: u64,
    /// Where the path ended, machine units.
    pub end: Xyz,
    /// Line of the last setpoint.
    pub line: usize,
}

#[expect(clippy::large_enum_variant, reason = "Pieces are the common case; boxing them would allocate once per piece.")]
enum Span {
    Motion { piece: Piece, profile: Profile, t0: f64, t1: f64 },
    Rest { pos: Xyz, line: usize, t1: f64 },
}

/// The setpoint stream of a program: an iterator of [`Step`]s at a fixed period, with bounded
/// memory (the look-ahead window), ending after the final rest setpoint or after an error.
///
/// An error from the items (or an item the planner cannot execute) is delivered at its place:
/// the path before it is completed and brought to rest, the rest setpoint is yielded, then
/// the error, then `None`.
pub struct Setpoints<I> {
    planner: Lookahead<I>,
    period: f64,
    tick: u64,
    /// [`PlanConfig::max_setpoints`].
    max_setpoints: u64,
    span: Span,
    /// Speed carried from a braking piece into the next (after [`Setpoints::stop`]).
    carry: f64,
    stopping: bool,
    /// Events waiting for the setpoint of their tick.
    due: VecDeque<(u64, TimedEvent)>,
    out: VecDeque<Result<Step, PathError>>,
    /// The tick of the final setpoint and the error to deliver after it.
    last: Option<(u64, Option<PathError>)>,
    finished: bool,
}

impl<J: Iterator<Item = Item>> Setpoints<std::iter::Map<J, fn(Item) -> Result<Item, PathError>>> {
    /// Plan a sequence of items that cannot fail.
    pub fn from_items(
        config: &PlanConfig,
        items: impl IntoIterator<Item = Item, IntoIter = J>,
    ) -> Result<Self, PathError> {
        let ok: fn(Item) -> Result<Item, PathError> = Ok;
        Setpoints::new(config, items.into_iter().map(ok))
    }
}

impl<I: Iterator<Item = Result<Item, PathError>>> Setpoints<I> {
    /// Plan `items` (read lazily) under `config`.
    pub fn new(config: &PlanConfig, items: I) -> Result<Setpoints<I>, PathError> {
        config.validate()?;
        let start = config.start;
        let shaper = Shaper::new(items, config.limits, start);
        Ok(Setpoints {
            planner: Lookahead::new(shaper, config.lookahead),
            period: config.period,
            max_setpoints: config.max_setpoints,
            tick: 0,
            span: Span::Rest { pos: start, line: 0, t1: 0.0 },
            carry: 0.0,
            stopping: false,
            due: VecDeque::new(),
            out: VecDeque::new(),
            last: None,
            finished: false,
        })
    }

    /// The setpoint period, seconds.
    pub fn period(&self) -> f64 {
        self.period
    }

    /// Bring the path to a controlled stop: from the next setpoint on, brake along the path
    /// at each piece's acceleration limit, then end the stream at rest. Outputs and dwells
    /// not yet reached do not happen. Calling it again, or after the end, does nothing.
    pub fn stop(&mut self) {
        if self.stopping || self.finished || self.last.is_some() {
            return;
        }
        self.stopping = true;
        let now = self.tick.saturating_sub(1) as f64 * self.period;
        match &mut self.span {
            Span::Motion { piece, profile, t0, t1 } if self.tick > 0 => {
                let (s, v) = profile.at(now - *t0);
                *profile = Profile::braking(s, v, piece.curve.len(), piece.accel);
                *t0 = now;
                *t1 = now + profile.duration();
            }
            _ => {
                let (pos, line) = self.position_line(now);
                self.span = Span::Rest { pos, line, t1: now };
                self.last = Some((self.tick, None));
            }
        }
    }

    /// Drain the stream and summarise it (cycle time, counts, end position).
    pub fn run_to_end(mut self) -> Result<Summary, PathError> {
        let mut summary = Summary { cycle_time: 0.0, setpoints: 0, events: 0, end: Xyz::ZERO, line: 0 };
        for step in &mut self {
            match step? {
                Step::Setpoint(s) => {
                    summary.cycle_time = s.time;
                    summary.setpoints += 1;
                    summary.end = s.position;
                    summary.line = s.line;
                }
                Step::Event(_) => summary.events += 1,
            }
        }
        Ok(summary)
    }

    fn span_end(&self) -> f64 {
        match self.span {
            Span::Motion { t1, .. } | Span::Rest { t1, .. } => t1,
        }
    }

    /// The first tick at or after `t`.
    #[expect(clippy::cast_possible_truncation, clippy::cast_sign_loss, reason = "a non-negative tick count, floored")]
    fn grid_tick(&self, t: f64) -> u64 {
        // From below: `t` is often exactly a tick time, and `t / T` may round above k.
        let mut k = (t / self.period).floor().max(0.0) as u64;
        while (k as f64) * self.period < t {
            k += 1;
        }
        k
    }

    /// Where the current span leaves the machine and its line.
    fn span_exit(&self) -> (Xyz, usize) {
        match &self.span {
            Span::Motion { piece, profile, .. } => (piece.curve.point(profile.end_s()), piece.line),
            Span::Rest { pos, line, .. } => (*pos, *line),
        }
    }

    fn position_line(&self, t: f64) -> (Xyz, usize) {
        match &self.span {
            Span::Motion { piece, profile, t0, .. } => (piece.curve.point(profile.at(t - t0).0), piece.line),
            Span::Rest { pos, line, .. } => (*pos, *line),
        }
    }

    /// Hold at rest until the next tick and end the stream there (after `error`, if any).
    fn rest_and_finish(&mut self, error: Option<PathError>) {
        let t = self.span_end();
        let (pos, line) = self.span_exit();
        let k = self.grid_tick(t);
        self.span = Span::Rest { pos, line, t1: k as f64 * self.period };
        self.last = Some((k, error));
    }

    /// Extend the timeline past the current span. Does nothing once the end is known.
    fn advance(&mut self) {
        if self.last.is_some() {
            return;
        }
        let t = self.span_end();
        if self.stopping {
            if let Span::Motion { profile, .. } = &self.span {
                self.carry = profile.end_speed();
            }
            if self.carry <= 0.0 {
                return self.rest_and_finish(None);
            }
        }
        match self.planner.next() {
            Some(Ready::Piece { piece, v0, v1 }) => {
                let len = piece.curve.len();
                let profile = if self.stopping {
                    Profile::braking(0.0, self.carry.min(v0), len, piece.accel)
                } else {
                    Profile::trapezoid(len, v0, v1, piece.v_cap, piece.accel)
                };
                let t1 = t + profile.duration();
                self.span = Span::Motion { piece, profile, t0: t, t1 };
            }
            Some(Ready::Stop(marker)) => {
                let (pos, prev_line) = self.span_exit();
                let k = self.grid_tick(t);
                let at = k as f64 * self.period;
                if self.stopping {
                    return self.rest_and_finish(None);
                }
                match marker {
                    Marker::Corner => self.span = Span::Rest { pos, line: prev_line, t1: at },
                    Marker::Dwell { line, seconds } => {
                        let end = self.grid_tick(at + seconds);
                        self.span = Span::Rest { pos, line, t1: end as f64 * self.period };
                    }
                    Marker::Event { line, event } => {
                        self.span = Span::Rest { pos, line, t1: at };
                        self.due.push_back((k, TimedEvent { time: at, line, event }));
                    }
                    Marker::End { line } => {
                        self.span = Span::Rest { pos, line, t1: at };
                        self.last = Some((k, None));
                    }
                    Marker::Error(e) => {
                        self.span = Span::Rest { pos, line: prev_line, t1: at };
                        self.last = Some((k, Some(e)));
                    }
                }
            }
            None => self.rest_and_finish(None),
        }
    }

    fn sample(&self, t: f64) -> Setpoint {
        let (position, velocity, line) = match &self.span {
            Span::Motion { piece, profile, t0, .. } => {
                let (s, v) = profile.at(t - t0);
                let (point, deriv) = piece.curve.point_and_deriv(s);
                (point, deriv * v, piece.line)
            }
            Span::Rest { pos, line, .. } => (*pos, Xyz::ZERO, *line),
        };
        Setpoint { time: t, position, velocity, line }
    }
}

impl<I: Iterator<Item = Result<Item, PathError>>> Iterator for Setpoints<I> {
    type Item = Result<Step, PathError>;

    fn next(&mut self) -> Option<Self::Item> {
        if let Some(x) = self.out.pop_front() {
            return Some(x);
        }
        if self.finished {
            return None;
        }
        let t = self.tick as f64 * self.period;
        // `>=`: stops and events due at exactly `t` are taken before sampling `t`.
        while t >= self.span_end() && self.last.is_none() {
            self.advance();
        }
        // Checked when the span is planned, not when its setpoints run out: a circle of radius
        // 10⁹ would otherwise be sampled for a minute before it failed.
        if self.span_end() / self.period >= self.max_setpoints as f64 {
            self.finished = true;
            let line = match &self.span {
                Span::Motion { piece, .. } => piece.line,
                Span::Rest { line, .. } => *line,
            };
            let days = self.max_setpoints as f64 * self.period / 86_400.0;
            return Some(Err(PathError::InvalidItem {
                line,
                reason: format!(
                    "the path runs longer than {} setpoints ({days:.1} days at this period); check the \
                     feeds, the limits and the program's units",
                    self.max_setpoints
                ),
            }));
        }
        let setpoint = self.sample(t);
        let tick = self.tick;
        self.tick += 1;
        while self.due.front().is_some_and(|(k, _)| *k <= tick) {
            if let Some((_, ev)) = self.due.pop_front() {
                self.out.push_back(Ok(Step::Event(ev)));
            }
        }
        if let Some((k, error)) = &mut self.last {
            if tick >= *k {
                if let Some(e) = error.take() {
                    self.out.push_back(Err(e));
                }
                self.finished = true;
            }
        }
        Some(Ok(Step::Setpoint(setpoint)))
    }
}
