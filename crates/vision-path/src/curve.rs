//! The geometry of one piece of path: a straight line or a circular / helical / spiral arc,
//! parameterised by `s ∈ [0, len]` (machine units) with `|dp/ds| ≤ 1` (equality except on
//! spirals). Both ends are stored and returned exactly, so a path ends where it was told to.

use std::f64::consts::TAU;

use crate::limits::ShapeFactors;
use crate::vec3::Vec3;

/// A line or an arc.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Curve {
    Line(LineCurve),
    Arc(ArcCurve),
}

/// A straight line.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LineCurve {
    start: Vec3,
    end: Vec3,
    /// Unit direction.
    dir: Vec3,
    len: f64,
}

/// `p(φ) = base + (r0 + k_r·φ)·(e1·cos φ + e2·sin φ) + axis·k_z·φ` for `φ ∈ [phi_a, phi_b]`,
/// with `s = (φ − phi_a)·rho`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ArcCurve {
    base: Vec3,
    e1: Vec3,
    e2: Vec3,
    axis: Vec3,
    r0: f64,
    k_r: f64,
    k_z: f64,
    /// `ds/dφ`: the largest `|dp/dφ|` over the whole arc, so `|dp/ds| ≤ 1`.
    rho: f64,
    phi_a: f64,
    phi_b: f64,
    start: Vec3,
    end: Vec3,
    factors: ShapeFactors,
}

/// Why an arc could not be built (the caller adds the line number).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ArcProblem {
    NoPlane,
    OnCentre,
    /// The sweep is zero, not finite, beyond [`MAX_SWEEP`], or so small that the arc's
    /// length overflows.
    BadSweep,
    /// Turning by the sweep does not end at the end point.
    MissesEnd,
}

/// The largest sweep an arc may have, radians (a million turns).
pub(crate) const MAX_SWEEP: f64 = 1e6 * TAU;

impl LineCurve {
    /// The line from `start` to `end`, or `None` when they coincide.
    pub(crate) fn new(start: Vec3, end: Vec3) -> Option<LineCurve> {
        let d = end - start;
        let len = d.norm();
        (len > 0.0 && len.is_finite()).then(|| LineCurve { start, end, dir: d * (1.0 / len), len })
    }
}

impl ArcCurve {
    /// A G2/G3 arc from `start` to `end` about `centre`, turning `sweep` radians about
    /// `normal` (see [`crate::ArcShape`]). The sweep must take the arc to `end`.
    pub(crate) fn program(
        start: Vec3,
        end: Vec3,
        centre: Vec3,
        normal: Vec3,
        sweep: f64,
    ) -> Result<ArcCurve, ArcProblem> {
        let n = normal.unit().ok_or(ArcProblem::NoPlane)?;
        if !(sweep.is_finite() && sweep != 0.0 && sweep.abs() <= MAX_SWEEP) {
            return Err(ArcProblem::BadSweep);
        }
        let axis = if sweep < 0.0 { -n } else { n };
        let sweep = sweep.abs();
        let rs = start - centre;
        let re = end - centre;
        let rs_p = rs - axis * rs.dot(axis);
        let re_p = re - axis * re.dot(axis);
        let (r0, r1) = (rs_p.norm(), re_p.norm());
        let scale = 1.0 + start.max_abs().max(end.max_abs()).max(centre.max_abs());
        if !(r0 > 1e-9 * scale && r1 > 1e-9 * scale) {
            return Err(ArcProblem::OnCentre);
        }
        let e1 = rs_p * (1.0 / r0);
        let e2 = axis.cross(e1);
        let base = centre + axis * rs.dot(axis);
        let k_r = (r1 - r0) / sweep;
        let k_z = (end - start).dot(axis) / sweep;
        let arc = ArcCurve::build(base, e1, e2, axis, r0, r1, k_r, k_z, sweep, start, end);
        // The end is returned exactly; the sweep must reach it (as closely as the continuity
        // between segments is checked), or the path would jump there.
        if !((arc.at_phi(sweep) - end).norm() <= 1e-9 * scale) {
            return Err(ArcProblem::MissesEnd);
        }
        // A sweep so small that the rise along the axis makes the length overflow.
        if !(arc.rho * sweep).is_finite() {
            return Err(ArcProblem::BadSweep);
        }
        Ok(arc)
    }

    #[allow(clippy::too_many_arguments)]
    fn build(
        base: Vec3,
        e1: Vec3,
        e2: Vec3,
        axis: Vec3,
        r0: f64,
        r1: f64,
        k_r: f64,
        k_z: f64,
        sweep: f64,
        start: Vec3,
        end: Vec3,
    ) -> ArcCurve {
        let (r_max, r_min) = (r0.max(r1), r0.min(r1));
        let rho = (r_max * r_max + k_r * k_r + k_z * k_z).sqrt();
        let in_plane = (k_r * k_r + r_max * r_max).sqrt() / rho;
        let q = [axis.x, axis.y, axis.z].map(|a| (1.0 - a * a).max(0.0).sqrt());
        let c = [0, 1, 2].map(|i| (q[i] * in_plane + axis.get(i).abs() * k_z.abs() / rho).min(1.0));
        let factors = ShapeFactors {
            c,
            q,
            kappa: (r_max * r_max + 4.0 * k_r * k_r).sqrt() / (rho * rho),
            cross: if k_r == 0.0 { 0.0 } else { (k_r.abs() / r_min).min(1.0) },
            circle: k_r == 0.0 && k_z == 0.0,
        };
        ArcCurve { base, e1, e2, axis, r0, k_r, k_z, rho, phi_a: 0.0, phi_b: sweep, start, end, factors }
    }

    fn radial(&self, phi: f64) -> (Vec3, Vec3) {
        let (sin, cos) = phi.sin_cos();
        (self.e1 * cos + self.e2 * sin, self.e2 * cos - self.e1 * sin)
    }

    fn at_phi(&self, phi: f64) -> Vec3 {
        let (radial, _) = self.radial(phi);
        self.base + radial * (self.r0 + self.k_r * phi) + self.axis * (self.k_z * phi)
    }

    fn deriv_phi(&self, phi: f64) -> Vec3 {
        let (radial, tangential) = self.radial(phi);
        (tangential * (self.r0 + self.k_r * phi) + radial * self.k_r + self.axis * self.k_z) * (1.0 / self.rho)
    }

    /// Distance from `p` to this arc: exact for circles; for spirals the radius at the
    /// point's angle is used (exact to first order in the radius change). Not for helices.
    fn distance_planar(&self, p: Vec3) -> f64 {
        let d = p - self.base;
        let h = d.dot(self.axis);
        let dp = d - self.axis * h;
        let raw = dp.dot(self.e2).atan2(dp.dot(self.e1));
        let phi = self.phi_a + (raw - self.phi_a).rem_euclid(TAU);
        if phi <= self.phi_b {
            (h * h + (dp.norm() - (self.r0 + self.k_r * phi)).powi(2)).sqrt()
        } else {
            (p - self.start).norm().min((p - self.end).norm())
        }
    }

    /// Whether the arc rises along its axis (a helix).
    fn is_helix(&self) -> bool {
        (self.k_z * (self.phi_b - self.phi_a)).abs() > 1e-9 * (1.0 + self.base.max_abs())
    }
}

impl Curve {
    /// The planar circular arc that leaves `start` along the unit `tangent` and reaches `end`;
    /// a straight line when `end` lies (nearly) on the tangent. `None` when the points coincide
    /// or `end` lies behind `start` on the tangent.
    pub(crate) fn from_tangent(start: Vec3, tangent: Vec3, end: Vec3) -> Option<Curve> {
        let chord = end - start;
        let c2 = chord.dot(chord);
        let off = chord - tangent * chord.dot(tangent);
        let h = off.norm();
        if !(c2 > 0.0) || !c2.is_finite() {
            return None;
        }
        if h <= 1e-12 * c2.sqrt() {
            return (chord.dot(tangent) > 0.0).then(|| LineCurve::new(start, end).map(Curve::Line)).flatten();
        }
        let m = off * (1.0 / h);
        let r = c2 / (2.0 * h);
        let base = start + m * r;
        let e1 = -m;
        let e2 = tangent;
        let axis = e1.cross(e2);
        let v = end - base;
        let mut sweep = v.dot(e2).atan2(v.dot(e1));
        if sweep <= 0.0 {
            sweep += TAU;
        }
        Some(Curve::Arc(ArcCurve::build(base, e1, e2, axis, r, r, 0.0, 0.0, sweep, start, end)))
    }

    /// Length of the path parameter, machine units (the arc length except on spirals, where
    /// it is a slight over-estimate).
    pub(crate) fn len(&self) -> f64 {
        match self {
            Curve::Line(l) => l.len,
            Curve::Arc(a) => (a.phi_b - a.phi_a) * a.rho,
        }
    }

    /// The angle an arc sweeps, radians (0 for a line).
    pub(crate) fn sweep(&self) -> f64 {
        match self {
            Curve::Line(_) => 0.0,
            Curve::Arc(a) => a.phi_b - a.phi_a,
        }
    }

    /// The exact start point.
    pub(crate) fn start(&self) -> Vec3 {
        match self {
            Curve::Line(l) => l.start,
            Curve::Arc(a) => a.start,
        }
    }

    /// The exact end point.
    pub(crate) fn end(&self) -> Vec3 {
        match self {
            Curve::Line(l) => l.end,
            Curve::Arc(a) => a.end,
        }
    }

    /// The point at parameter `s` (clamped; the ends are exact).
    pub(crate) fn point(&self, s: f64) -> Vec3 {
        if s <= 0.0 {
            return self.start();
        }
        if s >= self.len() {
            return self.end();
        }
        match self {
            Curve::Line(l) => l.start + l.dir * s,
            Curve::Arc(a) => a.at_phi(a.phi_a + s / a.rho),
        }
    }

    /// `dp/ds` at parameter `s` (a unit vector except on spirals, where `|dp/ds| ≤ 1`).
    pub(crate) fn deriv(&self, s: f64) -> Vec3 {
        match self {
            Curve::Line(l) => l.dir,
            Curve::Arc(a) => a.deriv_phi(a.phi_a + s.clamp(0.0, self.len()) / a.rho),
        }
    }

    /// Unit tangent at the start.
    pub(crate) fn start_tangent(&self) -> Vec3 {
        let d = self.deriv(0.0);
        d.unit().unwrap_or(d)
    }

    /// Unit tangent at the end.
    pub(crate) fn end_tangent(&self) -> Vec3 {
        let d = self.deriv(self.len());
        d.unit().unwrap_or(d)
    }

    /// The part of the curve between parameters `a < b` (clamped), keeping exact ends where
    /// they are the original ends.
    pub(crate) fn sub(&self, a: f64, b: f64) -> Curve {
        let len = self.len();
        let (a, b) = (a.clamp(0.0, len), b.clamp(0.0, len));
        let start = self.point(a);
        let end = self.point(b);
        match self {
            Curve::Line(l) => Curve::Line(LineCurve { start, end, dir: l.dir, len: b - a }),
            Curve::Arc(arc) => Curve::Arc(ArcCurve {
                phi_a: arc.phi_a + a / arc.rho,
                phi_b: arc.phi_a + b / arc.rho,
                start,
                end,
                ..arc.clone()
            }),
        }
    }

    /// The shape's bounds (see [`ShapeFactors`]).
    pub(crate) fn factors(&self) -> ShapeFactors {
        match self {
            Curve::Line(l) => ShapeFactors {
                c: [l.dir.x.abs(), l.dir.y.abs(), l.dir.z.abs()],
                q: [0.0; 3],
                kappa: 0.0,
                cross: 0.0,
                circle: false,
            },
            Curve::Arc(a) => a.factors,
        }
    }

    /// The radius of an arc (its start radius for spirals), infinity for a line, machine units.
    pub(crate) fn radius(&self) -> f64 {
        match self {
            Curve::Line(_) => f64::INFINITY,
            Curve::Arc(a) => a.r0,
        }
    }

    /// Whether this is a helical arc (its corners are not blended).
    pub(crate) fn is_helix(&self) -> bool {
        matches!(self, Curve::Arc(a) if a.is_helix())
    }

    /// Distance from `p` to this curve, for lines and planar arcs (not helices).
    pub(crate) fn distance_to(&self, p: Vec3) -> f64 {
        match self {
            Curve::Line(l) => {
                let t = (p - l.start).dot(l.dir).clamp(0.0, l.len);
                (p - (l.start + l.dir * t)).norm()
            }
            Curve::Arc(a) => a.distance_planar(p),
        }
    }

    /// The curve's radius if it is an arc (blend arcs are circles).
    #[cfg(test)]
    pub(crate) fn arc_radius(&self) -> Option<f64> {
        match self {
            Curve::Line(_) => None,
            Curve::Arc(a) => Some(a.r0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn close(a: Vec3, b: Vec3, tol: f64) -> bool {
        (a - b).norm() <= tol
    }

    #[test]
    fn a_quarter_circle_g3_in_xy_runs_counter_clockwise_with_exact_ends() {
        let (s, e, c) = (Vec3::new(10.0, 0.0, 0.0), Vec3::new(0.0, 10.0, 0.0), Vec3::ZERO);
        let arc = Curve::Arc(ArcCurve::program(s, e, c, Vec3::new(0.0, 0.0, 1.0), FRAC_PI_2).unwrap());
        assert!((arc.len() - 10.0 * FRAC_PI_2).abs() < 1e-12);
        assert_eq!(arc.point(arc.len()), e);
        assert_eq!(arc.point(0.0), s);
        let mid = arc.point(arc.len() / 2.0);
        assert!(close(mid, Vec3::new(10.0 / 2f64.sqrt(), 10.0 / 2f64.sqrt(), 0.0), 1e-12));
        assert!(close(arc.start_tangent(), Vec3::new(0.0, 1.0, 0.0), 1e-12));
        assert!(close(arc.end_tangent(), Vec3::new(-1.0, 0.0, 0.0), 1e-12));
    }

    #[test]
    fn g2_goes_the_other_way_round_and_equal_ends_make_a_full_circle() {
        let (s, e, c) = (Vec3::new(10.0, 0.0, 0.0), Vec3::new(0.0, 10.0, 0.0), Vec3::ZERO);
        let cw = Curve::Arc(ArcCurve::program(s, e, c, Vec3::new(0.0, 0.0, 1.0), -3.0 * FRAC_PI_2).unwrap());
        assert!((cw.len() - 10.0 * 3.0 * FRAC_PI_2).abs() < 1e-9);
        assert!(close(cw.point(cw.len() / 3.0), Vec3::new(0.0, -10.0, 0.0), 1e-9));
        let full = Curve::Arc(ArcCurve::program(s, s, c, Vec3::new(0.0, 0.0, 1.0), TAU).unwrap());
        assert!((full.len() - 20.0 * PI).abs() < 1e-9);
        let two = Curve::Arc(ArcCurve::program(s, s, c, Vec3::new(0.0, 0.0, 1.0), 2.0 * TAU).unwrap());
        assert!((two.len() - 40.0 * PI).abs() < 1e-9);
    }

    #[test]
    fn g18_and_g19_planes_follow_the_right_hand_rule() {
        // G18: normal +Y; counter-clockwise goes from +Z towards +X.
        let arc = Curve::Arc(
            ArcCurve::program(
                Vec3::new(0.0, 0.0, 5.0),
                Vec3::new(5.0, 0.0, 0.0),
                Vec3::ZERO,
                Vec3::new(0.0, 1.0, 0.0),
                FRAC_PI_2,
            )
            .unwrap(),
        );
        assert!((arc.len() - 5.0 * FRAC_PI_2).abs() < 1e-12);
        // G19: normal +X; counter-clockwise goes from +Y towards +Z.
        let arc = Curve::Arc(
            ArcCurve::program(
                Vec3::new(0.0, 5.0, 0.0),
                Vec3::new(0.0, 0.0, 5.0),
                Vec3::ZERO,
                Vec3::new(1.0, 0.0, 0.0),
                FRAC_PI_2,
            )
            .unwrap(),
        );
        assert!((arc.len() - 5.0 * FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn a_helix_rises_linearly_and_its_length_includes_the_rise() {
        let s = Vec3::new(10.0, 0.0, 0.0);
        let e = Vec3::new(-10.0, 0.0, 4.0);
        let arc = Curve::Arc(ArcCurve::program(s, e, Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0), PI).unwrap());
        let expected = ((10.0 * PI).powi(2) + 16.0f64).sqrt();
        assert!((arc.len() - expected).abs() < 1e-9);
        assert!((arc.point(arc.len() / 2.0).z - 2.0).abs() < 1e-12);
        assert!((arc.deriv(1.0).norm() - 1.0).abs() < 1e-12);
        let f = arc.factors();
        assert!((f.c[2] - 4.0 / expected).abs() < 1e-12, "Z carries only the rise: {:?}", f.c);
    }

    #[test]
    fn a_spiral_keeps_its_parameter_speed_at_most_one() {
        let s = Vec3::new(10.0, 0.0, 0.0);
        let e = Vec3::new(0.0, 10.01, 0.0);
        let arc = Curve::Arc(ArcCurve::program(s, e, Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0), FRAC_PI_2).unwrap());
        for k in 0..=20 {
            let d = arc.deriv(arc.len() * f64::from(k) / 20.0).norm();
            assert!(d <= 1.0 + 1e-15 && d > 0.999, "{d}");
        }
        assert_eq!(arc.point(arc.len()), e);
    }

    #[test]
    fn degenerate_arcs_are_reported() {
        let s = Vec3::new(1.0, 0.0, 0.0);
        let z = Vec3::new(0.0, 0.0, 1.0);
        assert_eq!(ArcCurve::program(s, s, s, z, TAU), Err(ArcProblem::OnCentre));
        assert_eq!(ArcCurve::program(s, s, Vec3::ZERO, Vec3::ZERO, TAU), Err(ArcProblem::NoPlane));
        for sweep in [0.0, -0.0, f64::NAN, f64::INFINITY, 2.0 * MAX_SWEEP] {
            assert_eq!(ArcCurve::program(s, s, Vec3::ZERO, z, sweep), Err(ArcProblem::BadSweep), "{sweep}");
        }
        // A quarter turn does not reach the opposite point.
        let e = Vec3::new(-1.0, 0.0, 0.0);
        assert_eq!(ArcCurve::program(s, e, Vec3::ZERO, z, FRAC_PI_2), Err(ArcProblem::MissesEnd));
        // A rise of 5 over next to no angle: the pitch or the length overflows.
        let up = Vec3::new(1.0, 0.0, 5.0);
        assert_eq!(ArcCurve::program(s, up, Vec3::ZERO, z, 1e-308), Err(ArcProblem::MissesEnd));
        assert_eq!(ArcCurve::program(s, up, Vec3::ZERO, z, 1e-300), Err(ArcProblem::BadSweep));
    }

    #[test]
    fn the_sweep_decides_the_arc_not_a_full_circle_rule() {
        // The interpreter's `G0 X10 Y0 / G3 X10 Y0.00000001 I-10 J0`: a 1e-9 rad arc, not a
        // full circle.
        let (s, e) = (Vec3::new(10.0, 0.0, 0.0), Vec3::new(10.0, 1e-8, 0.0));
        let z = Vec3::new(0.0, 0.0, 1.0);
        let tiny = Curve::Arc(ArcCurve::program(s, e, Vec3::ZERO, z, 1e-9).unwrap());
        assert!((tiny.len() - 1e-8).abs() < 1e-20, "{}", tiny.len());
        // The same points with a sweep of one turn more: the full circle (plus the sliver).
        let full = Curve::Arc(ArcCurve::program(s, e, Vec3::ZERO, z, TAU + 1e-9).unwrap());
        assert!((full.len() - 10.0 * (TAU + 1e-9)).abs() < 1e-9);
        // Clockwise the long way round.
        let back = Curve::Arc(ArcCurve::program(s, e, Vec3::ZERO, z, 1e-9 - TAU).unwrap());
        assert!((back.len() - 10.0 * (TAU - 1e-9)).abs() < 1e-9);
        assert!(close(back.point(back.len() / 4.0), Vec3::new(0.0, -10.0, 0.0), 1e-6));
    }

    #[test]
    fn an_arc_from_a_tangent_is_tangent_there_and_ends_at_the_target() {
        let start = Vec3::new(-1.0, 0.0, 0.0);
        let end = Vec3::new(0.0, 1.0, 0.0);
        let c = Curve::from_tangent(start, Vec3::new(1.0, 0.0, 0.0), end).unwrap();
        assert!((c.arc_radius().unwrap() - 1.0).abs() < 1e-12);
        assert!(close(c.end_tangent(), Vec3::new(0.0, 1.0, 0.0), 1e-12));
        assert!((c.distance_to(Vec3::ZERO) - (2f64.sqrt() - 1.0)).abs() < 1e-12);
        let line = Curve::from_tangent(start, Vec3::new(1.0, 0.0, 0.0), Vec3::new(3.0, 0.0, 0.0)).unwrap();
        assert!(matches!(line, Curve::Line(_)));
        assert!(Curve::from_tangent(start, Vec3::new(1.0, 0.0, 0.0), Vec3::new(-3.0, 0.0, 0.0)).is_none());
    }

    #[test]
    fn a_sub_curve_keeps_the_geometry_between_its_parameters() {
        let arc = Curve::Arc(
            ArcCurve::program(
                Vec3::new(10.0, 0.0, 0.0),
                Vec3::new(-10.0, 0.0, 0.0),
                Vec3::ZERO,
                Vec3::new(0.0, 0.0, 1.0),
                PI,
            )
            .unwrap(),
        );
        let part = arc.sub(2.0, 7.0);
        assert!((part.len() - 5.0).abs() < 1e-12);
        assert!(close(part.point(1.0), arc.point(3.0), 1e-12));
        assert_eq!(part.start(), arc.point(2.0));
        let tail = arc.sub(7.0, arc.len());
        assert_eq!(tail.end(), arc.end());
    }
}
