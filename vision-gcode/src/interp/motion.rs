//! Moves: G0/G1, G2/G3 (exact arcs or polylines), G28/G28.1, G30/G30.1, G53.

use crate::arc::{
    Arc, Tolerance, CENTRE_TOLERANCE_INCH, CENTRE_TOLERANCE_MM, RADIUS_TOLERANCE_INCH, RADIUS_TOLERANCE_MM,
};
use crate::error::{GCode, RunProblem};
use crate::event::{ArcMove, Event, EventSink, LinearMove, PathMode, Rate};
use crate::frame::{Placement, SystemRotation};
use crate::geom::{ArcDirection, Plane, Xyz, AXIS_LETTERS, CENTRE_LETTERS};
use crate::params::G92_OFFSET;
use vision_math::{LengthUnit, Point2};

use super::cycles::cycle_name;
use super::line::{in_range, LineRun, Pending};
use super::modal::MotionMode;

/// An arc that becomes line segments when flushed (it may be long: it is expanded lazily).
#[derive(Debug, Clone)]
pub(crate) struct Polyline {
    line: u32,
    arc: Arc,
    placement: Placement,
    segments: u64,
    /// Machine position where the next segment starts (the arc's start before any).
    start: Xyz,
    /// The next segment to emit, from 1.
    next: u64,
    feed: f64,
    /// The line's path mode, for the last segment.
    path: PathMode,
    /// The chord tolerance: interior vertices are not programmed points, so they blend within it.
    chord_tolerance: f64,
}

/// The most segments of a polyline emitted in one chunk ([`Polyline::emit_some`]).
const SEGMENTS_PER_CHUNK: u64 = 1024;

impl Polyline {
    /// Emits the segments; the last one ends exactly at the arc's mapped end point and carries
    /// the line's path mode, the others blend (G64 P chord tolerance) even under G61.
    pub(crate) fn emit(&mut self, sink: &mut dyn EventSink) {
        self.emit_up_to(self.segments, sink);
    }

    /// Emits the next chunk of segments; whether segments are left.
    pub(crate) fn emit_some(&mut self, sink: &mut dyn EventSink) -> bool {
        self.emit_up_to(self.next.saturating_add(SEGMENTS_PER_CHUNK - 1).min(self.segments), sink);
        self.next <= self.segments
    }

    fn emit_up_to(&mut self, last: u64, sink: &mut dyn EventSink) {
        let interior = PathMode::Blend { tolerance: Some(self.chord_tolerance) };
        for k in self.next..=last {
            // k ≤ segments ≤ the configured limit (10⁷ by default): exact in f64.
            let t = k as f64 / self.segments as f64;
            let to = self.placement.machine_of(self.arc.point_at(t));
            let path = if k == self.segments { self.path } else { interior };
            sink.event(&Event::Linear(LinearMove {
                line: self.line,
                start: self.start,
                end: to,
                rate: Rate::Feed(self.feed),
                path,
            }));
            self.start = to;
        }
        self.next = self.next.max(last + 1);
    }
}

/// The G-code of a motion mode.
fn motion_name(mode: MotionMode) -> &'static str {
    match mode {
        MotionMode::Rapid => "G0",
        MotionMode::Linear => "G1",
        MotionMode::Arc(ArcDirection::Clockwise) => "G2",
        MotionMode::Arc(ArcDirection::CounterClockwise) => "G3",
        MotionMode::Cycle(code) => cycle_name(code),
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
        if self.w.has(b'@') || self.w.has(b'^') {
            let (x, y) = self.polar(owner)?;
            t.x = x;
            t.y = y;
        }
        Ok(t)
    }

    /// LinuxCNC's polar words (interp_find.cc, `find_ends`): `@` the distance from the program
    /// origin (G90) or a change of it (G91), `^` the angle in degrees counter-clockwise from +X,
    /// or a change of it; a word left out keeps the current point's. The new X/Y, machine units.
    fn polar(&mut self, owner: &'static str) -> Result<(f64, f64), RunProblem> {
        let (distance, angle) = self.polar_words(owner)?;
        let (x, y) = (self.st.program.x, self.st.program.y);
        if !self.st.absolute {
            return polar_step(x, y, distance, angle);
        }
        let (radius, theta) = match (distance, angle) {
            (Some(r), Some(a)) => (r, a),
            (Some(_), None) if x == 0.0 && y == 0.0 => {
                return Err(RunProblem::Polar { problem: "at the origin the angle ^ is needed" })
            }
            (Some(r), None) => (r, y.atan2(x)),
            (None, a) => (x.hypot(y), a.unwrap_or(0.0)),
        };
        Ok((radius * theta.cos(), radius * theta.sin()))
    }

    /// The polar words where LinuxCNC allows them: the distance (machine units) and the angle
    /// (radians).
    pub(super) fn polar_words(&mut self, owner: &'static str) -> Result<(Option<f64>, Option<f64>), RunProblem> {
        let refuse = |problem| Err(RunProblem::Polar { problem });
        if !self.cfg.rules().polar_words {
            return refuse("a LinuxCNC feature; program X and Y in this dialect");
        }
        if self.st.plane != Plane::Xy {
            return refuse("they work in the G17 plane only");
        }
        if self.w.has(b'X') || self.w.has(b'Y') {
            return refuse("X or Y on the same line: give either X/Y or @/^");
        }
        Ok((self.length(b'@', owner)?, self.w.take(b'^', owner)?.map(f64::to_radians)))
    }

    /// G28 / G30: via the point the axis words name (if any) to the position stored at
    /// `#home`…`#home + 2` (machine coordinates); with axis words, on those axes only.
    pub(super) fn g28(&mut self, home: u32, name: &'static str) -> Result<(), RunProblem> {
        let given = AXIS_LETTERS.map(|l| self.w.has(l));
        let pl = self.placement();
        // As LinuxCNC, always a first leg, to the current point when no axis word names one.
        let via = self.target(name)?;
        let m = self.checked(pl.machine_of(via))?;
        self.rapid_to_machine(m);
        let [hx, hy, hz] = self.params.triple(home);
        let home = Xyz::new(hx, hy, hz);
        let m = if !given.iter().any(|g| *g) {
            home
        } else if self.cfg.rules().home_axes_in_current_system {
            // rs274 (`convert_home`) reads the stored position in the current system
            // (`find_relative`) and gives the named program axes of the waypoint its
            // coordinates: in a rotated system homing X alone moves the machine's Y too.
            let mut end = via;
            let at = pl.program_of(home);
            for axis in (0..3).filter(|&a| given[a]) {
                end.set_axis(axis, at.axis(axis));
            }
            self.checked(pl.machine_of(end))?
        } else {
            let mut m = self.st.machine;
            for axis in (0..3).filter(|&a| given[a]) {
                m.set_axis(axis, home.axis(axis));
            }
            m
        };
        self.rapid_to_machine(m);
        self.st.rederive_program(self.params);
        Ok(())
    }

    pub(super) fn rapid_to_machine(&mut self, end: Xyz) {
        let start = self.st.machine;
        self.emit(Event::Linear(LinearMove { line: self.line, start, end, rate: Rate::Rapid, path: self.st.path }));
        self.st.machine = end;
    }

    /// G28.1 / G30.1: stores the machine position at `#home`…`#home + 2`.
    #[expect(clippy::cast_possible_truncation, reason = "axis indices are 0..3")]
    pub(super) fn g28_1(&mut self, home: u32) {
        let m = self.st.machine;
        for axis in 0..3 {
            self.params.set(home + axis as u32, m.axis(axis));
        }
    }

    /// `m`, a machine position a move goes to, when it is finite and within range.
    pub(super) fn checked(&self, m: Xyz) -> Result<Xyz, RunProblem> {
        if !m.is_finite() {
            return Err(RunProblem::NonFinitePosition);
        }
        in_range(m.max_abs(), || "the move's machine position".into())?;
        Ok(m)
    }

    /// The line's motion: `code` is its motion-group code (if any), `axes_taken` whether another
    /// code owns the axis words, `g53` whether the line has G53.
    pub(super) fn motion(&mut self, code: Option<u16>, axes_taken: bool, g53: bool) -> Result<(), RunProblem> {
        let previous = self.st.motion;
        if let Some(code) = code {
            self.st.motion = match code {
                0 => Some(MotionMode::Rapid),
                10 => Some(MotionMode::Linear),
                20 => Some(MotionMode::Arc(ArcDirection::Clockwise)),
                30 => Some(MotionMode::Arc(ArcDirection::CounterClockwise)),
                800 => None,
                cycle => Some(MotionMode::Cycle(GCode(cycle))),
            };
        }
        let polar = self.w.has(b'@') || self.w.has(b'^');
        let has_axes = self.w.has(b'X') || self.w.has(b'Y') || self.w.has(b'Z') || polar;
        if polar && g53 {
            return Err(RunProblem::Polar { problem: "not with G53: program X and Y there" });
        }
        if g53 {
            // G53 moves with G0/G1, which end a series of cycles like any other motion: the
            // next cycle starts its own, from the Z it finds (rs274's `convert_motion` clears
            // `cycle_il_flag` for every non-cycle motion; G53 goes through there too).
            self.st.cycle.initial_level = None;
            return self.g53();
        }
        if code == Some(800) {
            self.st.cycle.initial_level = None;
            if has_axes && !axes_taken {
                return Err(RunProblem::G80AxisWords);
            }
        }
        if let (Some(MotionMode::Cycle(cycle)), false) = (self.st.motion, axes_taken) {
            // A cycle runs on axis words, or where its code is written.
            if has_axes || code.is_some() {
                return self.canned_cycle(cycle, previous);
            }
            return Ok(());
        }
        // LinuxCNC moves wherever a motion code is written: `G0` alone is a move to the current
        // point, `G2 I1` a full circle.
        let written = matches!(code, Some(0 | 10 | 20 | 30));
        if axes_taken || !(has_axes || written) {
            if let (false, Some(MotionMode::Arc(dir))) = (axes_taken, self.st.motion) {
                if [b'I', b'J', b'K', b'R'].iter().any(|&l| self.w.has(l)) {
                    return Err(RunProblem::ArcNoEnd { code: motion_name(MotionMode::Arc(dir)) });
                }
            }
            return Ok(());
        }
        // A `let … else`, not `ok_or`: no error value is built (and dropped) on every move.
        let Some(mode) = self.st.motion else { return Err(RunProblem::NoMotionMode) };
        let name = motion_name(mode);
        self.st.cycle.initial_level = None;
        match mode {
            MotionMode::Rapid => {
                let target = self.target(name)?;
                self.linear(target, Rate::Rapid)
            }
            MotionMode::Linear => {
                let target = self.target(name)?;
                let feed = self.feed(name)?;
                self.linear(target, Rate::Feed(feed))
            }
            MotionMode::Arc(direction) => {
                let target = self.target(name)?;
                self.arc(target, direction, name)
            }
            MotionMode::Cycle(cycle) => self.canned_cycle(cycle, previous),
        }
    }

    /// The feed rate for a feed move, machine units per minute: set and positive; under G95
    /// the programmed feed per revolution times the spindle speed `S`.
    pub(super) fn feed(&self, code: &'static str) -> Result<f64, RunProblem> {
        let f = match self.st.feed {
            None => return Err(RunProblem::NoFeedRate { code }),
            Some(f) if f <= 0.0 => return Err(RunProblem::ZeroFeedRate { code }),
            Some(f) => f,
        };
        if !self.st.per_revolution {
            return Ok(f);
        }
        match self.st.speed {
            Some(s) if s > 0.0 => in_range(f * s, || format!("{code}'s feed per minute (F × S under G95)")),
            _ => Err(RunProblem::NoSpindleSpeed { code }),
        }
    }

    /// G53 with G0/G1: a straight move to the given machine coordinates (absolute, current
    /// units; unmentioned axes stay).
    fn g53(&mut self) -> Result<(), RunProblem> {
        let mode = self.st.motion;
        let rate = match mode {
            Some(MotionMode::Rapid) => Rate::Rapid,
            Some(MotionMode::Linear) => Rate::Feed(self.feed("G1")?),
            _ => return Err(RunProblem::G53Form { hint: "program G0 or G1 on the G53 line" }),
        };
        if !self.st.absolute {
            return Err(RunProblem::G53Form { hint: "switch to G90 first" });
        }
        let owner = if rate == Rate::Rapid { "G53 G0" } else { "G53 G1" };
        if self.cfg.rules().carries_current_point {
            return self.g53_linuxcnc(owner, rate);
        }
        let mut end = self.st.machine;
        for (axis, &letter) in AXIS_LETTERS.iter().enumerate() {
            if let Some(v) = self.length(letter, owner)? {
                end.set_axis(axis, v);
            }
        }
        let end = self.checked(end)?;
        let start = self.st.machine;
        self.emit(Event::Linear(LinearMove { line: self.line, start, end, rate, path: self.st.path }));
        self.st.machine = end;
        self.st.rederive_program(self.params);
        Ok(())
    }

    /// LinuxCNC's G53 (interp_find.cc, `find_ends`): the end is a program point, an axis
    /// without a word keeping the current point's coordinate (Z exactly; X/Y through the
    /// system's rotation), a given one the machine coordinate less the offsets. Where the
    /// current point no longer reads the machine position (after a rotation change with a G92
    /// offset), the unmentioned axes go where the current point is, as rs274 sends them; and
    /// a cycle after the G53 compares the very Z the program had with its R level.
    fn g53_linuxcnc(&mut self, owner: &'static str, rate: Rate) -> Result<(), RunProblem> {
        let (x, y, z) = (self.length(b'X', owner)?, self.length(b'Y', owner)?, self.length(b'Z', owner)?);
        let p = self.st.program;
        let [gx, gy, gz] = self.params.triple(G92_OFFSET);
        let (origin, tool) = (self.st.origin, self.st.tool_offset);
        let mut target = p;
        if x.is_some() || y.is_some() {
            let c = SystemRotation::turn(self.st.rotation, Point2::new(p.x + gx, p.y + gy));
            let ex = x.map_or(c.x, |x| x - (origin.x - tool.x));
            let ey = y.map_or(c.y, |y| y - (origin.y - tool.y));
            let back = SystemRotation::turn(-self.st.rotation, Point2::new(ex, ey));
            target.x = back.x - gx;
            target.y = back.y - gy;
        }
        if let Some(z) = z {
            target.z = ((z - origin.z) - gz) - tool.z - self.st.frame.local_z;
        }
        // The given machine coordinates exactly (the round trip through the offsets differs
        // by rounding only).
        let mut end = self.placement().machine_of(target);
        for (axis, given) in [x, y, z].into_iter().enumerate() {
            if let Some(v) = given {
                end.set_axis(axis, v);
            }
        }
        let end = self.checked(end)?;
        let start = self.st.machine;
        self.emit(Event::Linear(LinearMove { line: self.line, start, end, rate, path: self.st.path }));
        self.st.program = target;
        self.st.machine = end;
        Ok(())
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
        let turns = self.count(b'P', name, "P counts full turns and must be at least 1")?;
        let feed = self.feed(name)?;
        let start = self.st.program;
        let to_user = self.cfg.machine_unit.factor_to(self.st.units);
        let inch = self.st.units == LengthUnit::Inch;
        let min_radius = self.conv(if inch { RADIUS_TOLERANCE_INCH } else { RADIUS_TOLERANCE_MM });
        let tolerance = Tolerance { machine: min_radius, min_radius, to_user };
        let center = match (radius, ca, cb) {
            (Some(_), Some(_), _) | (Some(_), _, Some(_)) => return Err(RunProblem::ArcBothForms { code: name }),
            (Some(r), None, None) => Arc::centre_from_radius(plane, start, target, r, direction, tolerance)?,
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
        let tolerance = Tolerance { machine, ..tolerance };
        let arc = Arc::from_centre(plane, start, target, center, direction, turns, tolerance)?;
        let pl = self.placement();
        let end = self.checked(pl.machine_of(target))?;
        let machine_start = self.st.machine;
        let exact = match plane {
            Plane::Xy => pl.frame.is_similarity(),
            Plane::Zx | Plane::Yz => pl.is_translation(),
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
                next: 1,
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

/// An incremental polar step from (x, y): first the distance from the origin grows by
/// `distance`, then the angle by `angle` (radians), as rs274 does; undefined at the origin.
pub(super) fn polar_step(
    mut x: f64,
    mut y: f64,
    distance: Option<f64>,
    angle: Option<f64>,
) -> Result<(f64, f64), RunProblem> {
    if (distance.is_some() || angle.is_some()) && x == 0.0 && y == 0.0 {
        return Err(RunProblem::Polar { problem: "an incremental (G91) polar move is undefined at the origin" });
    }
    if let Some(r) = distance {
        let (radius, theta) = (x.hypot(y) + r, y.atan2(x));
        (x, y) = (radius * theta.cos(), radius * theta.sin());
    }
    if let Some(a) = angle {
        let (radius, theta) = (x.hypot(y), y.atan2(x) + a);
        (x, y) = (radius * theta.cos(), radius * theta.sin());
    }
    Ok((x, y))
}
