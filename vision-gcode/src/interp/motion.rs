//! Moves: G0/G1, G2/G3 (exact arcs or polylines), G28/G28.1.

use crate::arc::{
    Arc, Tolerance, CENTRE_TOLERANCE_INCH, CENTRE_TOLERANCE_MM, RADIUS_TOLERANCE_INCH, RADIUS_TOLERANCE_MM,
};
use crate::error::RunProblem;
use crate::event::{ArcMove, Event, EventSink, LinearMove, PathMode, Rate};
use crate::frame::Placement;
use crate::geom::{ArcDirection, Plane, Xyz, AXIS_LETTERS, CENTRE_LETTERS};
use crate::params::G28_POSITION;
use crate::words::whole;
use vision_math::LengthUnit;

use super::line::{LineRun, Pending};
use super::modal::MotionMode;

/// An arc that becomes line segments when flushed (it may be long: it is expanded lazily).
#[derive(Debug, Clone)]
pub(crate) struct Polyline {
    line: u32,
    arc: Arc,
    placement: Placement,
    segments: u64,
    /// Machine position where the arc starts.
    start: Xyz,
    feed: f64,
    /// The line's path mode, for the last segment.
    path: PathMode,
    /// The chord tolerance: interior vertices are not programmed points, so they blend within it.
    chord_tolerance: f64,
}

impl Polyline {
    /// Emits the segments; the last one ends exactly at the arc's mapped end point and carries
    /// the line's path mode, the others blend (G64 P chord tolerance) even under G61.
    pub(crate) fn emit(&self, sink: &mut dyn EventSink) {
        let mut from = self.start;
        let interior = PathMode::Blend { tolerance: Some(self.chord_tolerance) };
        for k in 1..=self.segments {
            // k ≤ segments ≤ the configured limit (10⁷ by default): exact in f64.
            #[allow(clippy::cast_precision_loss)]
            let t = k as f64 / self.segments as f64;
            let to = self.placement.machine_of(self.arc.point_at(t));
            let path = if k == self.segments { self.path } else { interior };
            sink.event(&Event::Linear(LinearMove {
                line: self.line,
                start: from,
                end: to,
                rate: Rate::Feed(self.feed),
                path,
            }));
            from = to;
        }
    }
}

/// The G-code of a motion mode.
fn motion_name(mode: MotionMode) -> &'static str {
    match mode {
        MotionMode::Rapid => "G0",
        MotionMode::Linear => "G1",
        MotionMode::Arc(ArcDirection::Clockwise) => "G2",
        MotionMode::Arc(ArcDirection::CounterClockwise) => "G3",
    }
}

impl LineRun<'_> {
    /// The program point the axis words name (absolute or incremental), machine units.
    pub(super) fn target(&mut self, owner: &'static str) -> Result<Xyz, RunProblem> {
        let mut t = self.st.program;
        for (axis, &letter) in AXIS_LETTERS.iter().enumerate() {
            if let Some(v) = self.length(letter, owner)? {
                t.set_axis(axis, if self.st.absolute { v } else { t.axis(axis) + v });
            }
        }
        Ok(t)
    }

    pub(super) fn g28(&mut self) -> Result<(), RunProblem> {
        let given = AXIS_LETTERS.map(|l| self.w.has(l));
        let pl = self.placement();
        if given.iter().any(|g| *g) {
            let via = self.target("G28")?;
            let m = self.checked(pl.machine_of(via))?;
            self.rapid_to_machine(m);
        }
        let home = self.params.triple(G28_POSITION);
        let mut m = self.st.machine;
        let all = !given.iter().any(|g| *g);
        for axis in (0..3).filter(|&a| all || given[a]) {
            m.set_axis(axis, home[axis]);
        }
        self.rapid_to_machine(m);
        self.st.rederive_program(self.params);
        Ok(())
    }

    pub(super) fn rapid_to_machine(&mut self, end: Xyz) {
        let start = self.st.machine;
        self.emit(Event::Linear(LinearMove { line: self.line, start, end, rate: Rate::Rapid, path: self.st.path }));
        self.st.machine = end;
    }

    pub(super) fn g28_1(&mut self) {
        let m = self.st.machine;
        for axis in 0..3 {
            self.params.set(G28_POSITION + axis as u32, m.axis(axis));
        }
    }

    pub(super) fn checked(&self, m: Xyz) -> Result<Xyz, RunProblem> {
        if m.is_finite() {
            Ok(m)
        } else {
            Err(RunProblem::NonFinitePosition)
        }
    }

    pub(super) fn motion(&mut self, code: Option<u16>, axes_taken: bool) -> Result<(), RunProblem> {
        if let Some(code) = code {
            self.st.motion = Some(match code {
                0 => MotionMode::Rapid,
                10 => MotionMode::Linear,
                20 => MotionMode::Arc(ArcDirection::Clockwise),
                _ => MotionMode::Arc(ArcDirection::CounterClockwise),
            });
        }
        let has_axes = self.w.has(b'X') || self.w.has(b'Y') || self.w.has(b'Z');
        if axes_taken || !has_axes {
            if let (false, Some(MotionMode::Arc(dir))) = (axes_taken, self.st.motion) {
                if [b'I', b'J', b'K', b'R'].iter().any(|&l| self.w.has(l)) {
                    return Err(RunProblem::ArcNoEnd { code: motion_name(MotionMode::Arc(dir)) });
                }
            }
            return Ok(());
        }
        let mode = self.st.motion.ok_or(RunProblem::NoMotionMode)?;
        let name = motion_name(mode);
        let target = self.target(name)?;
        match mode {
            MotionMode::Rapid => self.linear(target, Rate::Rapid),
            MotionMode::Linear => {
                let feed = self.st.feed.ok_or(RunProblem::NoFeedRate { code: name })?;
                self.linear(target, Rate::Feed(feed))
            }
            MotionMode::Arc(direction) => self.arc(target, direction, name),
        }
    }

    pub(super) fn linear(&mut self, target: Xyz, rate: Rate) -> Result<(), RunProblem> {
        let end = self.checked(self.placement().machine_of(target))?;
        let start = self.st.machine;
        self.emit(Event::Linear(LinearMove { line: self.line, start, end, rate, path: self.st.path }));
        self.st.program = target;
        self.st.machine = end;
        Ok(())
    }

    pub(super) fn arc(&mut self, target: Xyz, direction: ArcDirection, name: &'static str) -> Result<(), RunProblem> {
        let plane = self.st.plane;
        let (a, b, n) = plane.axes();
        let normal_letter = CENTRE_LETTERS[n];
        if self.w.has(normal_letter) {
            return Err(RunProblem::ArcCentreWord {
                letter: char::from(normal_letter),
                plane: plane.gcode(),
                centre: plane.centre_words(),
            });
        }
        let (la, lb) = plane.centre_letters();
        let radius = self.length(b'R', name)?;
        let ca = self.length(la, name)?;
        let cb = self.length(lb, name)?;
        let turns = match self.w.take(b'P', name)? {
            None => 1,
            Some(p) => match whole(b'P', p)? {
                0 => {
                    return Err(RunProblem::OutOfRange {
                        code: name,
                        letter: 'P',
                        value: p,
                        hint: "P counts full turns and must be at least 1",
                    })
                }
                t => t,
            },
        };
        let feed = self.st.feed.ok_or(RunProblem::NoFeedRate { code: name })?;
        let start = self.st.program;
        let to_user = self.cfg.machine_unit.factor_to(self.st.units);
        let inch = self.st.units == LengthUnit::Inch;
        let center = match (radius, ca, cb) {
            (Some(_), Some(_), _) | (Some(_), _, Some(_)) => return Err(RunProblem::ArcBothForms { code: name }),
            (Some(r), None, None) => {
                if turns != 1 {
                    return Err(RunProblem::OutOfRange {
                        code: name,
                        letter: 'P',
                        value: f64::from(turns),
                        hint: "multi-turn arcs need the centre form (I/J/K)",
                    });
                }
                let machine = self.conv(if inch { RADIUS_TOLERANCE_INCH } else { RADIUS_TOLERANCE_MM });
                Arc::centre_from_radius(plane, start, target, r, direction, Tolerance { machine, to_user })?
            }
            (None, None, None) => {
                return Err(RunProblem::ArcNoCentre { code: name, centre: plane.centre_words() });
            }
            (None, ca, cb) if self.st.arc_absolute => {
                let (Some(ca), Some(cb)) = (ca, cb) else {
                    let missing = if ca.is_none() { la } else { lb };
                    return Err(RunProblem::MissingWord {
                        code: name,
                        letter: char::from(missing),
                        hint: "under G90.1 both centre coordinates are absolute and required",
                    });
                };
                (ca, cb)
            }
            (None, ca, cb) => (start.axis(a) + ca.unwrap_or(0.0), start.axis(b) + cb.unwrap_or(0.0)),
        };
        let machine = self.conv(if inch { CENTRE_TOLERANCE_INCH } else { CENTRE_TOLERANCE_MM });
        let arc = Arc::from_centre(plane, start, target, center, direction, turns, Tolerance { machine, to_user })?;
        let pl = self.placement();
        let end = self.checked(pl.machine_of(target))?;
        let machine_start = self.st.machine;
        let exact = match plane {
            Plane::Xy => pl.frame.is_similarity(),
            Plane::Zx | Plane::Yz => pl.frame.is_translation(),
        };
        if exact {
            let center = self.checked(pl.machine_of(arc.center_point()))?;
            let direction = if plane == Plane::Xy && pl.frame.mirrors() { direction.reversed() } else { direction };
            self.emit(Event::Arc(ArcMove {
                line: self.line,
                start: machine_start,
                end,
                center,
                plane,
                direction,
                angle: arc.angle,
                feed,
                path: self.st.path,
            }));
        } else {
            let segments = arc.segments(pl.frame.stretch(), self.cfg.chord_tolerance);
            if segments > self.cfg.max_arc_segments {
                return Err(RunProblem::ArcTooManySegments { segments });
            }
            self.out.push(Pending::Polyline(Polyline {
                line: self.line,
                arc,
                placement: pl,
                segments,
                start: machine_start,
                feed,
                path: self.st.path,
                chord_tolerance: self.cfg.chord_tolerance,
            }));
        }
        self.st.program = target;
        self.st.machine = end;
        Ok(())
    }
}
