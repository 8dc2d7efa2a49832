//! Program items → path pieces with their speed caps, and the stops between them.
//!
//! Each corner is decided here, with the next segment in hand: tangent joins pass, G61
//! corners stop, G64 corners are blended (the neighbours are trimmed and blend arcs inserted).
//! Dwells, events, the end and errors become stops that carry their payload.

use std::collections::VecDeque;
use std::f64::consts::PI;

use vision_gcode::{PathMode, Rate};

use crate::blend::blend;
use crate::curve::{ArcCurve, ArcProblem, Curve, LineCurve};
use crate::input::{Event, Item, Segment, Shape};
use crate::limits::{speed_and_accel, Limits, NORMAL_SHARE};
use crate::PathError;
use vision_gcode::{Xyz, MAX_COORDINATE};

/// Two pieces whose tangents differ by at most this angle (radians) join without stopping;
/// the velocity jump it allows (`v·θ`) is far below anything a drive can see.
pub(crate) const TANGENT_TOLERANCE: f64 = 1e-9;
/// Corners sharper than `π − this` (a reversal) stop instead of blending.
const REVERSAL_MARGIN: f64 = 1e-6;
/// Pieces shorter than this (machine units) are dropped.
const MIN_PIECE: f64 = 1e-12;
/// The longest accepted dwell, seconds.
const MAX_DWELL: f64 = 1e6;

/// A stretch of path with its own speed cap and tangential acceleration.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Piece {
    pub(crate) curve: Curve,
    pub(crate) line: usize,
    /// Speed cap of the path parameter, units/s.
    pub(crate) v_cap: f64,
    /// Tangential acceleration, units/s².
    pub(crate) accel: f64,
}

/// Why the path comes to rest between two pieces.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Marker {
    /// A corner that is not blended (G61, a reversal, or a blend that does not fit).
    Corner,
    /// G4.
    Dwell { line: usize, seconds: f64 },
    /// An output or tool change.
    Event { line: usize, event: Event },
    /// The end of the program.
    End { line: usize },
    /// The program failed here.
    Error(PathError),
}

/// What the shaper produces.
#[expect(clippy::large_enum_variant, reason = "Pieces are the common case; boxing them would allocate once per piece.")]
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Shaped {
    Piece(Piece),
    Stop(Marker),
}

/// The segment whose end corner waits for the next one.
struct Pending {
    /// The segment as it will be emitted (its caps kept up to date when a blend trims it).
    piece: Piece,
    /// Half the untrimmed length: the most either corner may trim.
    half: f64,
    requested: f64,
    mode: PathMode,
}

pub(crate) struct Shaper<I> {
    input: I,
    limits: Limits,
    pos: Xyz,
    last_line: usize,
    pending: Option<Pending>,
    out: VecDeque<Shaped>,
    done: bool,
}

impl<I: Iterator<Item = Result<Item, PathError>>> Shaper<I> {
    pub(crate) fn new(input: I, limits: Limits, start: Xyz) -> Shaper<I> {
        Shaper { input, limits, pos: start, last_line: 0, pending: None, out: VecDeque::new(), done: false }
    }

    /// The next piece or stop; the stream always ends with `Stop(End)` or `Stop(Error)`.
    pub(crate) fn next(&mut self) -> Option<Shaped> {
        loop {
            if let Some(s) = self.out.pop_front() {
                return Some(s);
            }
            if self.done {
                return None;
            }
            match self.input.next() {
                None => self.finish(Marker::End { line: self.last_line }),
                Some(Err(e)) => self.finish(Marker::Error(e)),
                Some(Ok(item)) => {
                    self.last_line = item.line();
                    if let Err(e) = self.take(item) {
                        self.finish(Marker::Error(e));
                    }
                }
            }
        }
    }

    fn finish(&mut self, marker: Marker) {
        self.flush();
        self.out.push_back(Shaped::Stop(marker));
        self.done = true;
    }

    fn take(&mut self, item: Item) -> Result<(), PathError> {
        match item {
            Item::Move(seg) => self.take_move(&seg),
            Item::Dwell { line, seconds } => {
                if !(seconds.is_finite() && (0.0..=MAX_DWELL).contains(&seconds)) {
                    return Err(invalid(
                        line,
                        format!(
                            "dwell of {} s is invalid; use 0 to {} seconds",
                            vision_math::show::number(seconds),
                            vision_math::show::number(MAX_DWELL)
                        ),
                    ));
                }
                self.flush();
                self.out.push_back(Shaped::Stop(Marker::Dwell { line, seconds }));
                Ok(())
            }
            Item::Event { line, event } => {
                self.flush();
                self.out.push_back(Shaped::Stop(Marker::Event { line, event }));
                Ok(())
            }
            Item::End { line } => {
                self.finish(Marker::End { line });
                Ok(())
            }
        }
    }

    fn take_move(&mut self, seg: &Segment) -> Result<(), PathError> {
        let line = seg.line;
        let start = seg.start;
        let end = seg.end;
        if !(start.is_finite() && end.is_finite()) {
            return Err(invalid(line, "a coordinate is not a finite number".into()));
        }
        if start.max_abs().max(end.max_abs()) > MAX_COORDINATE {
            return Err(invalid(
                line,
                format!("a coordinate is beyond ±{MAX_COORDINATE:e} units; check the program's units"),
            ));
        }
        let gap = (start - self.pos).norm();
        if gap > 1e-9 * (1.0 + self.pos.max_abs()) {
            return Err(invalid(
                line,
                format!(
                    "the move starts at {:?} but the previous one ended at {:?}; segments must be continuous",
                    seg.start, self.pos
                ),
            ));
        }
        let requested = match seg.rate {
            Rate::Rapid => f64::INFINITY,
            Rate::Feed(f) if Limits::SPEED_RANGE.contains(&(f / 60.0)) => f / 60.0,
            Rate::Feed(f) => {
                return Err(invalid(
                    line,
                    format!(
                        "feed F{} is invalid; program a feed between {} and {} units/min",
                        vision_math::show::number(f),
                        vision_math::show::number(Limits::SPEED_RANGE.start() * 60.0),
                        vision_math::show::number(Limits::SPEED_RANGE.end() * 60.0)
                    ),
                ))
            }
        };
        if let PathMode::Blend { tolerance: Some(p) } = seg.mode {
            if !(0.0..=MAX_COORDINATE).contains(&p) {
                return Err(invalid(line, format!("G64 P{p} is invalid; the tolerance must be 0 or more")));
            }
        }
        let curve = match seg.shape {
            Shape::Line => match LineCurve::new(self.pos, end) {
                Some(l) => Curve::Line(l),
                None => return Ok(()), // no motion
            },
            Shape::Arc(arc) => {
                let centre = arc.centre;
                let normal = arc.normal;
                if !(centre.is_finite() && normal.is_finite()) || centre.max_abs() > MAX_COORDINATE {
                    return Err(invalid(line, "an arc centre or normal is not a finite number in range".into()));
                }
                match ArcCurve::program(self.pos, end, centre, normal, arc.sweep) {
                    Ok(a) => Curve::Arc(a),
                    Err(p) => return Err(invalid(line, arc_message(p).into())),
                }
            }
        };
        self.pos = end;
        let next =
            Pending { half: curve.len() / 2.0, piece: self.piece(curve, line, requested), requested, mode: seg.mode };
        match self.pending.take() {
            None => self.pending = Some(next),
            Some(prev) => self.corner(prev, next),
        }
        Ok(())
    }

    /// Decide the corner between `prev` (ending) and `next` (starting), emit `prev`.
    fn corner(&mut self, mut prev: Pending, mut next: Pending) {
        let theta = prev.piece.curve.end_tangent().angle_to(next.piece.curve.start_tangent());
        if theta <= TANGENT_TOLERANCE {
            self.push(prev.piece);
            self.pending = Some(next);
            return;
        }
        let tolerance = match prev.mode {
            PathMode::Blend { tolerance } if tolerance != Some(0.0) && theta < PI - REVERSAL_MARGIN => Some(tolerance),
            _ => None,
        };
        // The blend radius at which the centripetal limit allows the neighbours' own speed: a
        // larger blend would deviate more without being faster.
        let target = prev.piece.v_cap.min(next.piece.v_cap);
        let weakest = self.limits.axes.iter().map(|a| a.max_accel).fold(self.limits.max_path_accel, f64::min);
        let wanted = target * target / (NORMAL_SHARE * weakest);
        let blended =
            tolerance.and_then(|tol| blend(&prev.piece.curve, prev.half, &next.piece.curve, next.half, tol, wanted));
        match blended {
            Some(b) => {
                let (line, requested) = (prev.piece.line, prev.requested.min(next.requested));
                let kept = prev.piece.curve.len() - b.s1;
                self.trim(&mut prev, 0.0, kept);
                self.push(prev.piece);
                for curve in b.pieces {
                    let piece = self.piece(curve, line, requested);
                    self.push(piece);
                }
                let len = next.piece.curve.len();
                self.trim(&mut next, b.s2, len);
            }
            None => {
                self.push(prev.piece);
                self.out.push_back(Shaped::Stop(Marker::Corner));
            }
        }
        self.pending = Some(next);
    }

    fn flush(&mut self) {
        if let Some(p) = self.pending.take() {
            self.push(p.piece);
        }
    }

    /// The piece `curve` of `line`, asked to run at `requested` (units/s), with the speed cap
    /// and tangential acceleration its shape allows under the limits.
    fn piece(&self, curve: Curve, line: usize, requested: f64) -> Piece {
        let (v_cap, accel) = speed_and_accel(&curve.factors(), requested, &self.limits);
        Piece { curve, line, v_cap, accel }
    }

    /// Cut `p` down to its parameters `a..b`, with the caps of the part. A part of a line or a
    /// circle has the whole's shape factors and keeps its caps (this runs at every blended
    /// corner: recomputing them there cost 2–3 % of the blended spiral benchmark's
    /// instructions); a part of a spiral is bounded more tightly and gets its own.
    fn trim(&self, p: &mut Pending, a: f64, b: f64) {
        let part = p.piece.curve.sub(a, b);
        if part.factors() == p.piece.curve.factors() {
            p.piece.curve = part;
        } else {
            p.piece = self.piece(part, p.piece.line, p.requested);
        }
    }

    fn push(&mut self, piece: Piece) {
        if piece.curve.len() >= MIN_PIECE {
            self.out.push_back(Shaped::Piece(piece));
        }
    }
}

fn invalid(line: usize, reason: String) -> PathError {
    PathError::InvalidItem { line, reason }
}

fn arc_message(p: ArcProblem) -> &'static str {
    match p {
        ArcProblem::NoPlane => "the arc's plane normal is zero; select a plane (G17, G18 or G19)",
        ArcProblem::OnCentre => "the arc has zero radius (start or end on the centre); check I, J, K",
        ArcProblem::BadSweep => "the arc's sweep is zero, not a finite number or over a million turns; check the arc",
        ArcProblem::MissesEnd => {
            "the arc's sweep does not turn it from its start to its end point; check the sweep and the centre"
        }
    }
}
