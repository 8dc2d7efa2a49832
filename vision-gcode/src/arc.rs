//! Arc geometry in the program frame (machine units): centre from I/J/K or R, the swept angle,
//! points along the arc and the polyline a non-uniform scale needs. Pure functions.
//!
//! Checks follow LinuxCNC 2.9 (`interp_arc.cc`, `arc_data_ijk` / `arc_data_r`): the radii to
//! start and end may differ by more than the centre tolerance (0.002 828 in, or 0.028 28 mm
//! under G21) only while that is within 0.1 % of the larger radius, and never by more than 100
//! times it; a radius below the radius tolerance (0.000 05 in / 0.001 27 mm) is too small; `R`
//! may fall short of half the chord by at most the radius tolerance and is then taken as a
//! semicircle.

use std::f64::consts::{FRAC_PI_2, TAU};

use crate::error::RunProblem;
use crate::geom::{ArcDirection, Plane, Xyz};

/// LinuxCNC's centre-format tolerance for inch programs (2 · 0.001 · √2 in).
pub const CENTRE_TOLERANCE_INCH: f64 = 2.0 * 0.001 * std::f64::consts::SQRT_2;
/// The same for millimetre programs (2 · 0.01 · √2 mm).
pub const CENTRE_TOLERANCE_MM: f64 = 2.0 * 0.01 * std::f64::consts::SQRT_2;
/// LinuxCNC's `R`-format tolerance for inch programs.
pub const RADIUS_TOLERANCE_INCH: f64 = 0.000_05;
/// The same for millimetre programs.
pub const RADIUS_TOLERANCE_MM: f64 = 0.000_05 * 25.4;

/// LinuxCNC's relative limit on the start/end radius difference of a centre-format arc (0.1 %).
const SPIRAL_RELATIVE_TOLERANCE: f64 = 0.001;

/// An arc whose end angle is this close to its start's (radians) is a full turn (emccanon.cc,
/// `min_arc_angle`).
const FULL_TURN_ANGLE: f64 = 1e-12;
/// An arc whose end is this close to its start in the plane (machine units) is a full turn
/// (posemath's `CART_FUZZ`).
const FULL_TURN_DISTANCE: f64 = 1e-8;

/// A tolerance in machine units, the smallest radius allowed (machine units), and the factor
/// that turns machine units into the program's units for error messages.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Tolerance {
    pub(crate) machine: f64,
    pub(crate) min_radius: f64,
    pub(crate) to_user: f64,
}

/// An arc in the program frame, machine units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Arc {
    pub(crate) plane: Plane,
    pub(crate) start: Xyz,
    pub(crate) end: Xyz,
    /// Centre, in-plane (first axis, second axis).
    pub(crate) center: (f64, f64),
    pub(crate) direction: ArcDirection,
    /// Total swept angle, radians, > 0.
    pub(crate) angle: f64,
    start_angle: f64,
    r0: f64,
    r1: f64,
}

fn in_plane(plane: Plane, p: Xyz) -> (f64, f64) {
    let (a, b, _) = plane.axes();
    (p.axis(a), p.axis(b))
}

impl Arc {
    /// The arc from `start` to `end` about `center` (in-plane), `turns` ≥ 1 times round, with
    /// the centre tolerance `tol`.
    pub(crate) fn from_centre(
        plane: Plane,
        start: Xyz,
        end: Xyz,
        center: (f64, f64),
        direction: ArcDirection,
        turns: u32,
        tol: Tolerance,
    ) -> Result<Arc, RunProblem> {
        let (tolerance, to_user) = (tol.machine, tol.to_user);
        let mut arc = Arc::through(plane, start, end, center, direction, 0.0);
        let (r0, r1) = (arc.r0, arc.r1);
        if !(r0.is_finite() && r1.is_finite()) {
            return Err(RunProblem::NonFinite { what: "the arc radius" });
        }
        if r0 < tol.min_radius || r1 < tol.min_radius {
            return Err(RunProblem::ArcZeroRadius);
        }
        let abs_err = (r0 - r1).abs();
        let rel_err = abs_err / r0.max(r1);
        if abs_err > 100.0 * tolerance || (rel_err > SPIRAL_RELATIVE_TOLERANCE && abs_err > tolerance) {
            return Err(RunProblem::ArcRadiusMismatch { start_radius: r0 * to_user, end_radius: r1 * to_user });
        }
        let (ea, eb) = in_plane(plane, end);
        let (sa, sb) = in_plane(plane, start);
        let (a0, a1) = (arc.start_angle, (eb - center.1).atan2(ea - center.0));
        let mut sweep = match direction {
            ArcDirection::CounterClockwise => a1 - a0,
            ArcDirection::Clockwise => a0 - a1,
        };
        // An end on the start, up to rounding, is a full turn (LinuxCNC: emccanon.cc's
        // `ARC_FEED` adds a turn when the end angle is within 1e-12 rad of the start's, and
        // posemath's `pmCircleInit` when the points are within CART_FUZZ in the plane). Such an
        // end comes from arithmetic (`X[#5420]` read back in other units, say), not intent.
        if (ea - sa).hypot(eb - sb) < FULL_TURN_DISTANCE {
            sweep = TAU;
        } else if sweep <= FULL_TURN_ANGLE {
            sweep += TAU;
        }
        arc.angle = sweep + TAU * f64::from(turns.saturating_sub(1));
        Ok(arc)
    }

    /// The arc from `start` to `end` about `center` (in-plane) sweeping `angle` radians, its
    /// radii and start angle measured from the points; no checks.
    pub(crate) fn through(
        plane: Plane,
        start: Xyz,
        end: Xyz,
        center: (f64, f64),
        direction: ArcDirection,
        angle: f64,
    ) -> Arc {
        let (sa, sb) = in_plane(plane, start);
        let (ea, eb) = in_plane(plane, end);
        let r0 = (sa - center.0).hypot(sb - center.1);
        let r1 = (ea - center.0).hypot(eb - center.1);
        let start_angle = (sb - center.1).atan2(sa - center.0);
        Arc { plane, start, end, center, direction, angle, start_angle, r0, r1 }
    }

    /// The centre of the `R`-format arc from `start` to `end` (LinuxCNC's construction: a
    /// positive `radius` gives at most a semicircle, a negative one more).
    ///
    /// `tol` is the radius tolerance.
    #[expect(clippy::float_cmp, reason = "a full circle is an exact repeat of the start point")]
    pub(crate) fn centre_from_radius(
        plane: Plane,
        start: Xyz,
        end: Xyz,
        radius: f64,
        direction: ArcDirection,
        tol: Tolerance,
    ) -> Result<(f64, f64), RunProblem> {
        let (tolerance, to_user) = (tol.machine, tol.to_user);
        let (sa, sb) = in_plane(plane, start);
        let (ea, eb) = in_plane(plane, end);
        if sa == ea && sb == eb {
            return Err(RunProblem::ArcRFullCircle);
        }
        let r = radius.abs();
        if r == 0.0 {
            return Err(RunProblem::ArcZeroRadius);
        }
        let (ma, mb) = ((ea + sa) / 2.0, (eb + sb) / 2.0);
        let mut half = (ma - ea).hypot(mb - eb);
        if half - r > tolerance {
            return Err(RunProblem::ArcRadiusTooSmall { radius: r * to_user, half_chord: half * to_user });
        }
        if half / r > 1.0 - 1e-12 {
            half = r;
        }
        let chord = (eb - sb).atan2(ea - sa);
        let right = (direction == ArcDirection::Clockwise) == (radius > 0.0);
        let theta = if right { chord - FRAC_PI_2 } else { chord + FRAC_PI_2 };
        let offset = r * (half / r).asin().cos();
        let center = (ma + offset * theta.cos(), mb + offset * theta.sin());
        if center.0.is_finite() && center.1.is_finite() {
            Ok(center)
        } else {
            Err(RunProblem::NonFinite { what: "the arc centre" })
        }
    }

    /// The centre as a 3D point whose normal-axis coordinate is the start's.
    pub(crate) fn center_point(&self) -> Xyz {
        let (a, b, _) = self.plane.axes();
        let mut c = self.start;
        c.set_axis(a, self.center.0);
        c.set_axis(b, self.center.1);
        c
    }

    /// The point at fraction `t` of the swept angle (radius and normal axis linear in `t`);
    /// exactly `end` at `t = 1`.
    pub(crate) fn point_at(&self, t: f64) -> Xyz {
        if t >= 1.0 {
            return self.end;
        }
        self.point_along(t)
    }

    /// The point at fraction `t` of the swept angle, computed for any `t` (at `t = 1` within
    /// rounding of `end`).
    pub(crate) fn point_along(&self, t: f64) -> Xyz {
        let (a, b, n) = self.plane.axes();
        let theta = self.start_angle + self.direction.sign() * t * self.angle;
        let r = self.r0 + t * (self.r1 - self.r0);
        let mut p = Xyz::ZERO;
        p.set_axis(a, self.center.0 + r * theta.cos());
        p.set_axis(b, self.center.1 + r * theta.sin());
        p.set_axis(n, self.start.axis(n) + t * (self.end.axis(n) - self.start.axis(n)));
        p
    }

    /// Segments needed so that a polyline through equally spaced points stays within
    /// `chord_tolerance` of the arc after a map that stretches lengths by at most `stretch`.
    ///
    /// A chord over angle δ of a circle of radius r leaves it by r·(1 − cos(δ/2)); a linear map
    /// moves that distance by at most `stretch` times.
    pub(crate) fn segments(&self, stretch: f64, chord_tolerance: f64) -> u64 {
        let r = self.r0.max(self.r1) * stretch;
        let step =
            if chord_tolerance >= r { FRAC_PI_2 } else { (2.0 * (1.0 - chord_tolerance / r).acos()).min(FRAC_PI_2) };
        let n = (self.angle / step).ceil();
        if n.is_finite() && n >= 1.0 {
            #[expect(
                clippy::cast_possible_truncation,
                clippy::cast_sign_loss,
                reason = "Saturating float → int conversion: absurd counts are refused by the caller."
            )]
            {
                n as u64
            }
        } else if n.is_finite() {
            1
        } else {
            u64::MAX
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const T3: Tolerance = Tolerance { machine: 0.03, min_radius: 0.001, to_user: 1.0 };
    const T4: Tolerance = Tolerance { machine: 1e-3, min_radius: 1e-5, to_user: 1.0 };
    const T5: Tolerance = Tolerance { machine: 1e-4, min_radius: 1e-5, to_user: 1.0 };

    #[test]
    fn centre_format_angles() {
        let s = Xyz::new(500.0, 250.0, 500.0);
        let e = Xyz::new(0.0, 250.0, 500.0);
        let arc =
            Arc::from_centre(Plane::Xy, s, e, (250.0, 250.0), ArcDirection::CounterClockwise, 1, T3).expect("valid");
        assert!((arc.angle - PI).abs() < 1e-12);
        let top = arc.point_at(0.5);
        assert!((top.x - 250.0).abs() < 1e-9 && (top.y - 500.0).abs() < 1e-9);
        let full =
            Arc::from_centre(Plane::Xy, s, s, (250.0, 250.0), ArcDirection::Clockwise, 3, T3).expect("full circle");
        assert!((full.angle - 3.0 * TAU).abs() < 1e-12);
        // An end on the start up to rounding, on either side of it: a full turn each P.
        for nudge in [1e-13, -1e-13, 4e-9, -4e-9] {
            for direction in [ArcDirection::Clockwise, ArcDirection::CounterClockwise] {
                let near = Xyz::new(s.x, s.y + nudge, s.z);
                let arc = Arc::from_centre(Plane::Xy, s, near, (250.0, 250.0), direction, 2, T3).expect("full");
                assert!((arc.angle - 2.0 * TAU).abs() < 1e-6, "{nudge} {direction:?}: {}", arc.angle);
            }
        }
        let bad =
            Arc::from_centre(Plane::Xy, s, Xyz::new(0.0, 300.0, 0.0), (250.0, 250.0), ArcDirection::Clockwise, 1, T3);
        assert!(matches!(bad, Err(RunProblem::ArcRadiusMismatch { .. })));
        assert_eq!(
            Arc::from_centre(Plane::Xy, s, e, (500.0, 250.0), ArcDirection::Clockwise, 1, T3),
            Err(RunProblem::ArcZeroRadius)
        );
    }

    #[test]
    fn radius_format_picks_the_short_or_long_arc() {
        let s = Xyz::new(0.0, 0.0, 0.0);
        let e = Xyz::new(2.0, 0.0, 0.0);
        // CCW from (0,0) to (2,0) with R1: the semicircle below (centre (1,0)).
        let c = Arc::centre_from_radius(Plane::Xy, s, e, 1.0, ArcDirection::CounterClockwise, T5).expect("ok");
        assert!((c.0 - 1.0).abs() < 1e-12 && c.1.abs() < 1e-9);
        // R2: short arc; CCW travelling +X has its centre on the left (+Y).
        let c = Arc::centre_from_radius(Plane::Xy, s, e, 2.0, ArcDirection::CounterClockwise, T5).expect("ok");
        assert!(c.1 > 0.0);
        let c = Arc::centre_from_radius(Plane::Xy, s, e, -2.0, ArcDirection::CounterClockwise, T5).expect("ok");
        assert!(c.1 < 0.0);
        assert!(matches!(
            Arc::centre_from_radius(Plane::Xy, s, e, 0.5, ArcDirection::Clockwise, T5),
            Err(RunProblem::ArcRadiusTooSmall { .. })
        ));
        assert_eq!(
            Arc::centre_from_radius(Plane::Xy, s, s, 1.0, ArcDirection::Clockwise, T5),
            Err(RunProblem::ArcRFullCircle)
        );
    }

    #[test]
    fn segment_count_bounds_the_chord_error() {
        let s = Xyz::new(10.0, 0.0, 0.0);
        let arc = Arc::from_centre(Plane::Xy, s, s, (0.0, 0.0), ArcDirection::CounterClockwise, 1, T4).expect("circle");
        let n = arc.segments(1.0, 1e-4);
        let step = arc.angle / n as f64;
        assert!(10.0 * (1.0 - (step / 2.0).cos()) <= 1e-4);
        assert!(arc.segments(2.0, 1e-4) > n);
    }
}
