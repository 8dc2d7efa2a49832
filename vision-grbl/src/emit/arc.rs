//! Arcs as G2/G3 lines that Grbl's `gc_execute_line` accepts and `mc_arc` sweeps as meant.
//!
//! Grbl takes the start from the position it holds (the last rounded end sent), the centre as
//! start + I/J/K, and refuses (error:33) an end radius off the start radius by more than
//! 0.005 mm and 0.1 % (or 0.5 mm). It sweeps from the angle of the start to that of the end,
//! a full turn when they agree within 5·10⁻⁷ rad. So each piece is checked as Grbl will read
//! it: rounded, radius and sweep. A piece that fails (a spiral whose radius changes more than
//! Grbl allows, an end that rounding puts behind the start) is halved; one shorter than
//! [`STRAIGHT_BELOW_MM`] goes as a straight line. Turns beyond the first are full circles
//! (end == start in the plane), the normal axis advancing linearly.

use std::f64::consts::TAU;

use vision_gcode::{ArcDirection, ArcMove, Xyz};

use super::{EmitError, Emitter, AXES, MAX_COORDINATE_MM, OFFSETS};

/// An arc piece this short (mm along it) goes as a straight line: rounding the ends to 1 µm
/// moves them about as much.
const STRAIGHT_BELOW_MM: f64 = 0.002;
/// motion_control.c, `ARC_ANGULAR_TRAVEL_EPSILON` (radians).
const GRBL_EPSILON: f64 = 5e-7;
/// An end this close to the start's angle (radians), but not on it, is read as a full turn by
/// Grbl and as a tiny arc by LinuxCNC.
const AMBIGUOUS: f64 = 4.0 * GRBL_EPSILON;
/// The most halvings of one piece: at most 2¹² lines per turn.
const MAX_SPLITS: u32 = 12;
/// The largest difference (mm along the arc) between what Grbl sweeps and the piece.
const SWEEP_TOLERANCE_MM: f64 = 0.005;
/// Grbl's radius check, kept to 80 % of its limits (Grbl computes in 32-bit floats).
const RADIUS_MARGIN: f64 = 0.8;

impl Emitter {
    /// The lines of one arc event.
    pub(super) fn arc(&mut self, a: &ArcMove, out: &mut Vec<String>) -> Result<(), EmitError> {
        if !(a.start.is_finite() && a.end.is_finite() && a.center.is_finite() && a.angle.is_finite()) {
            return Err(EmitError::NonFinite { what: "an arc" });
        }
        if !(a.angle > 0.0) {
            return Err(EmitError::Arc { line: a.line, why: "its swept angle is not positive" });
        }
        self.select_plane(a.plane, out);
        let turns = a.extra_turns();
        let turn = TAU / a.angle;
        for i in 0..turns {
            let (t0, t1) = (f64::from(i) * turn, f64::from(i + 1) * turn);
            self.piece(a, t0, t1, None, 0, out)?;
        }
        let last = f64::from(turns) * turn;
        self.piece(a, last, 1.0, Some(last), 0, out)
    }

    /// The part of `a` from fraction `t0` to `t1` of its sweep: a whole turn (`last` is
    /// `None`) or part of the last, where a spiral's radius changes (`last`: where it begins).
    fn piece(
        &mut self,
        a: &ArcMove,
        t0: f64,
        t1: f64,
        last: Option<f64>,
        depth: u32,
        out: &mut Vec<String>,
    ) -> Result<(), EmitError> {
        let (p, q, _) = a.plane.axes();
        let theta = (t1 - t0) * a.angle;
        let centre = self.work_um(a.center, "the centre of an arc")?;
        let mut end = self.work_um(point(a, t1, last.unwrap_or(1.0)), "a point of an arc")?;
        if last.is_none() {
            end[p] = self.pos[p];
            end[q] = self.pos[q];
        }
        let offset = [centre[p] - self.pos[p], centre[q] - self.pos[q]];
        let radius = mm(offset[0]).hypot(mm(offset[1]));
        if radius * theta <= STRAIGHT_BELOW_MM {
            return self.line_to(end, Some(a.feed), out);
        }
        let to_end = [end[p] - centre[p], end[q] - centre[q]];
        let sweep = grbl_sweep(offset, to_end, a.direction);
        if !grbl_radius_ok(radius, mm(to_end[0]).hypot(mm(to_end[1])))
            || sweep.is_none_or(|sweep| (sweep - theta).abs() * radius > SWEEP_TOLERANCE_MM)
        {
            if depth >= MAX_SPLITS {
                return Err(EmitError::Arc {
                    line: a.line,
                    why: "Grbl would refuse it (radius) or sweep it otherwise even in 4096 pieces",
                });
            }
            let mid = 0.5 * (t0 + t1);
            self.piece(a, t0, mid, last, depth + 1, out)?;
            return self.piece(a, mid, t1, last, depth + 1, out);
        }
        let mut words: Vec<String> = Vec::new();
        words.extend(self.motion_word(if a.direction == ArcDirection::Clockwise { 2 } else { 3 }));
        for i in 0..3 {
            // Grbl wants an in-plane axis word even for a full circle.
            if i == p || i == q || end[i] != self.pos[i] {
                words.push(format!("{}{}", AXES[i], super::fmt_um(end[i])));
            }
        }
        let mut offsets = [(p, offset[0]), (q, offset[1])];
        offsets.sort_unstable_by_key(|&(axis, _)| axis);
        for (axis, v) in offsets {
            let value = mm(v);
            if value.abs() > MAX_COORDINATE_MM {
                return Err(EmitError::BeyondRange { word: OFFSETS[axis], value, limit: MAX_COORDINATE_MM });
            }
            words.push(format!("{}{}", OFFSETS[axis], super::fmt_um(v)));
        }
        words.extend(self.feed_word(a.feed)?);
        self.pos = end;
        out.push(words.join(" "));
        Ok(())
    }
}

/// The point of `a` at fraction `t` of its sweep, machine units: the normal axis linear in
/// `t`, the radius that of the start until `last` and then linear to the end's.
fn point(a: &ArcMove, t: f64, last: f64) -> Xyz {
    if t >= 1.0 {
        return a.end;
    }
    let (p, q, n) = a.plane.axes();
    let (s, e) = (a.start - a.center, a.end - a.center);
    let (r0, r1) = (s.axis(p).hypot(s.axis(q)), e.axis(p).hypot(e.axis(q)));
    let spiral = if last < 1.0 { ((t - last) / (1.0 - last)).clamp(0.0, 1.0) } else { 0.0 };
    let r = r0 + (r1 - r0) * spiral;
    let phi = s.axis(q).atan2(s.axis(p)) + a.direction.sign() * t * a.angle;
    let mut out = a.center;
    out.set_axis(p, a.center.axis(p) + r * phi.cos());
    out.set_axis(q, a.center.axis(q) + r * phi.sin());
    out.set_axis(n, a.start.axis(n) + t * (a.end.axis(n) - a.start.axis(n)));
    out
}

/// Micrometres as millimetres.
fn mm(um: i64) -> f64 {
    um as f64 / 1000.0
}

/// gcode.c's arc check (error:33), with [`RADIUS_MARGIN`].
fn grbl_radius_ok(start_radius: f64, end_radius: f64) -> bool {
    let delta = (end_radius - start_radius).abs();
    let limit = |v: f64| v * RADIUS_MARGIN;
    !(delta > limit(0.005) && (delta > limit(0.5) || delta > limit(0.001) * start_radius))
}

/// The angle `mc_arc` sweeps (radians, > 0) from the start (centre − `offset`) to the end
/// (centre + `to_end`), both in µm in the plane's (first, second) axes. `None` when an end off
/// the start lies within [`AMBIGUOUS`] of its angle: Grbl would sweep a full turn or next to
/// nothing depending on its epsilon (LinuxCNC's is 10⁻¹²), so the piece is halved instead.
fn grbl_sweep(offset: [i64; 2], to_end: [i64; 2], direction: ArcDirection) -> Option<f64> {
    let (r0, r1) = (-offset[0] as f64, -offset[1] as f64);
    let (t0, t1) = (to_end[0] as f64, to_end[1] as f64);
    let mut travel = (r0 * t1 - r1 * t0).atan2(r0 * t0 + r1 * t1);
    if travel.abs() <= AMBIGUOUS && [-offset[0], -offset[1]] != to_end {
        return None;
    }
    match direction {
        ArcDirection::Clockwise => {
            if travel >= -GRBL_EPSILON {
                travel -= TAU;
            }
        }
        ArcDirection::CounterClockwise => {
            if travel <= GRBL_EPSILON {
                travel += TAU;
            }
        }
    }
    Some(travel.abs())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grbls_sweep_and_radius_check() {
        let quarter = grbl_sweep([-1000, 0], [0, 1000], ArcDirection::CounterClockwise).expect("clear");
        assert!((quarter - TAU / 4.0).abs() < 1e-12);
        let three_quarters = grbl_sweep([-1000, 0], [0, 1000], ArcDirection::Clockwise).expect("clear");
        assert!((three_quarters - 0.75 * TAU).abs() < 1e-12);
        for direction in [ArcDirection::Clockwise, ArcDirection::CounterClockwise] {
            let full = grbl_sweep([-1000, 0], [1000, 0], direction).expect("a full turn");
            assert!((full - TAU).abs() < 1e-12);
            // 10⁻⁶ rad past the start: a full turn to Grbl, next to nothing to LinuxCNC.
            assert_eq!(grbl_sweep([-1_000_000_000, 0], [1_000_000_000, 1000], direction), None);
        }
        assert!(grbl_radius_ok(1.0, 1.0035));
        assert!(!grbl_radius_ok(1.0, 1.0045));
        assert!(grbl_radius_ok(100.0, 100.07));
        assert!(!grbl_radius_ok(100.0, 100.09));
        assert!(!grbl_radius_ok(10_000.0, 10_000.5));
    }
}
