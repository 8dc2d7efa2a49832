//! The geometry of one piece of path: a straight line or a circular / helical / spiral arc,
//! parameterised by `s ∈ [0, len]` (machine units) with `|dp/ds| ≤ 1`, and `|dp/ds| = 1` at
//! both ends (everywhere except inside spirals), so the speed planned along `s` is the real
//! speed wherever two pieces join. Both ends are stored and returned exactly, so a path ends
//! where it was told to.

use std::f64::consts::TAU;

use crate::limits::ShapeFactors;
use vision_gcode::Xyz;

/// A line or an arc.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Curve {
    Line(LineCurve),
    Arc(ArcCurve),
}

/// A straight line.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LineCurve {
    start: Xyz,
    end: Xyz,
    /// Unit direction.
    dir: Xyz,
    len: f64,
}

/// `p(φ) = base + (r0 + k_r·φ)·(e1·cos φ + e2·sin φ) + axis·k_z·φ` for `φ ∈ [phi_a, phi_b]`.
///
/// The parameter: `ds/dφ = h(φ)` goes linearly from `|dp/dφ|` at `phi_a` to `|dp/dφ|` at
/// `phi_b`, so `|dp/ds| = 1` at both ends. In between `|dp/ds| = |dp/dφ| / h ≤ 1`, because
/// `|dp/dφ| = √(r(φ)² + k_r² + k_z²)` with `r` linear in `φ` is convex and `h` is its chord.
/// Circles and helices (`k_r = 0`) have `h` constant: `s` is the arc length.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ArcCurve {
    base: Xyz,
    e1: Xyz,
    e2: Xyz,
    axis: Xyz,
    r0: f64,
    k_r: f64,
    k_z: f64,
    /// Angle range, radians from `e1`.
    phi_a: f64,
    phi_b: f64,
    /// `ds/dφ` at `phi_a`, machine units per radian.
    h_a: f64,
    /// `d²s/dφ²` (constant), machine units per radian².
    dh: f64,
    /// `s` at `phi_b`, machine units.
    len: f64,
    start: Xyz,
    end: Xyz,
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
    pub(crate) fn new(start: Xyz, end: Xyz) -> Option<LineCurve> {
        let d = end - start;
        let len = d.norm();
        (len > 0.0 && len.is_finite()).then(|| LineCurve { start, end, dir: d * (1.0 / len), len })
    }
}

impl ArcCurve {
    /// A G2/G3 arc from `start` to `end` about `centre`, turning `sweep` radians about
    /// `normal` (see [`crate::ArcShape`]). The sweep must take the arc to `end`.
    pub(crate) fn program(start: Xyz, end: Xyz, centre: Xyz, normal: Xyz, sweep: f64) -> Result<ArcCurve, ArcProblem> {
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
        // Radii equal but for rounding (a circle whose centre and ends were converted between
        // units) make a circle, not a spiral: the two are planned with different shares of
        // the axis acceleration, so rounding must not pick one.
        let k_r = if (r1 - r0).abs() <= 1e-9 * scale { 0.0 } else { (r1 - r0) / sweep };
        let k_z = (end - start).dot(axis) / sweep;
        let arc = ArcCurve::build(base, e1, e2, axis, r0, k_r, k_z, (0.0, sweep), start, end);
        // The end is returned exactly; the sweep must reach it (as closely as the continuity
        // between segments is checked), or the path would jump there.
        if !((arc.at_phi(sweep) - end).norm() <= 1e-9 * scale) {
            return Err(ArcProblem::MissesEnd);
        }
        // A sweep so small that the rise along the axis makes the length overflow.
        if !arc.len.is_finite() {
            return Err(ArcProblem::BadSweep);
        }
        Ok(arc)
    }

    /// The arc over `phi ∈ [range.0, range.1]` (radians from `e1`) with exact ends.
    #[expect(clippy::too_many_arguments, reason = "an arc's whole description")]
    #[expect(clippy::float_cmp, reason = "equal heights give an exactly flat helix")]
    fn build(
        base: Xyz,
        e1: Xyz,
        e2: Xyz,
        axis: Xyz,
        r0: f64,
        k_r: f64,
        k_z: f64,
        (phi_a, phi_b): (f64, f64),
        start: Xyz,
        end: Xyz,
    ) -> ArcCurve {
        let (r_a, r_b) = (r0 + k_r * phi_a, r0 + k_r * phi_b);
        let side2 = k_r * k_r + k_z * k_z;
        let (h_a, h_b) = ((r_a * r_a + side2).sqrt(), (r_b * r_b + side2).sqrt());
        let span = phi_b - phi_a;
        let dh = if h_a == h_b { 0.0 } else { (h_b - h_a) / span };
        let len = 0.5 * (h_a + h_b) * span;
        let factors = arc_factors(axis, (r_a, r_b), k_r, k_z, h_a.min(h_b), dh);
        ArcCurve { base, e1, e2, axis, r0, k_r, k_z, phi_a, phi_b, h_a, dh, len, start, end, factors }
    }

    /// `(φ, ds/dφ)` at parameter `s ∈ [0, len]`: `s = h_a·Δ + dh·Δ²/2` with `Δ = φ − phi_a`,
    /// solved without cancellation, and `h = √(h_a² + 2·dh·s)`.
    fn phi_h(&self, s: f64) -> (f64, f64) {
        if self.dh == 0.0 {
            return (self.phi_a + s / self.h_a, self.h_a);
        }
        let h = (self.h_a * self.h_a + 2.0 * self.dh * s).max(0.0).sqrt();
        (self.phi_a + 2.0 * s / (self.h_a + h), h)
    }

    fn radial(&self, phi: f64) -> (Xyz, Xyz) {
        let (sin, cos) = phi.sin_cos();
        (self.e1 * cos + self.e2 * sin, self.e2 * cos - self.e1 * sin)
    }

    /// The point at angle `phi`, whose radial direction is `radial`.
    fn position(&self, radial: Xyz, phi: f64) -> Xyz {
        self.base + radial * (self.r0 + self.k_r * phi) + self.axis * (self.k_z * phi)
    }

    /// `dp/ds` at angle `phi` (radial and tangential directions `dirs`), where `ds/dφ = h`.
    fn direction(&self, (radial, tangential): (Xyz, Xyz), phi: f64, h: f64) -> Xyz {
        (tangential * (self.r0 + self.k_r * phi) + radial * self.k_r + self.axis * self.k_z) * (1.0 / h)
    }

    fn at_phi(&self, phi: f64) -> Xyz {
        self.position(self.radial(phi).0, phi)
    }

    /// Distance from `p` to this arc: exact for circles; for spirals the radius at the
    /// point's angle is used (exact to first order in the radius change). Not for helices.
    fn distance_planar(&self, p: Xyz) -> f64 {
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

/// The bounds of an arc whose radius goes linearly from `r_a` to `r_b` (see [`ShapeFactors`],
/// and [`ArcCurve`] for the parameter), with `h_min` the smaller end of `ds/dφ` (the smallest
/// anywhere: `h` is linear) and `dh` its slope.
///
/// With `p′ = dp/dφ = t·r + ρ̂·k_r + axis·k_z` (`|p′| = g ≤ h`) and `p″ = −ρ̂·r + 2·k_r·t`:
/// `dp/ds = p′/h` and `d²p/ds² = p″/h² − p′·dh/h³`, so
/// * `|d²p/ds²| ≤ (√(r_max² + 4k_r²) + |dh|) / h_min²` (`kappa`);
/// * `dp/ds · d²p/ds² = k_r·r/h³ − g²·dh/h⁴`, at most `|k_r|·r_max/h_min³ + |dh|/h_min²` (`cross·kappa`);
/// * axis `i` sees `p′_i ≤ q_i·√(r² + k_r²) + |axis_i|·|k_z|` with `q_i` the length of its
///   projection on the plane, divided by `h ≥ g` (`c`), and `d²p_i/ds²` at most
///   `q_i·kappa + |axis_i|·|k_z|·|dh|/h_min³` (the rise term only on spiral helices) (`q`).
fn arc_factors(axis: Xyz, (r_a, r_b): (f64, f64), k_r: f64, k_z: f64, h_min: f64, dh: f64) -> ShapeFactors {
    let (r_max, r_min) = (r_a.max(r_b), r_a.min(r_b));
    let (kr2, kz2) = (k_r * k_r, k_z * k_z);
    let in_plane = ((r_max * r_max + kr2) / (r_max * r_max + kr2 + kz2)).sqrt();
    let axial = k_z.abs() / (r_min * r_min + kr2 + kz2).sqrt();
    let kappa = ((r_max * r_max + 4.0 * kr2).sqrt() + dh.abs()) / (h_min * h_min);
    let rise = k_z.abs() * dh.abs() / (h_min * h_min * h_min);
    let a = [axis.x.abs(), axis.y.abs(), axis.z.abs()];
    let proj = a.map(|a| (1.0 - a * a).max(0.0).sqrt());
    ShapeFactors {
        c: [0, 1, 2].map(|i| (proj[i] * in_plane + a[i] * axial).min(1.0)),
        q: [0, 1, 2].map(|i| (proj[i] + a[i] * rise / kappa).min(1.0)),
        kappa,
        cross: ((k_r.abs() * r_max / h_min + dh.abs()) / (h_min * h_min * kappa)).min(1.0),
        circle: k_r == 0.0 && k_z == 0.0,
    }
}

impl Curve {
    /// The planar circular arc that leaves `start` along the unit `tangent` and reaches `end`;
    /// a straight line when `end` lies (nearly) on the tangent. `None` when the points coincide
    /// or `end` lies behind `start` on the tangent.
    pub(crate) fn from_tangent(start: Xyz, tangent: Xyz, end: Xyz) -> Option<Curve> {
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
        // The arc turns by twice the angle between the tangent and the chord, in (0, 2π). Not
        // from `end − base`: on a nearly straight arc the centre is far away, and the rounding
        // of `m` (relative error ~10⁻¹⁷·|chord|/h) times the radius made the sweep, and so the
        // length, wrong by a large factor, so the path jumped where the piece ended.
        let sweep = 2.0 * h.atan2(chord.dot(tangent));
        Some(Curve::Arc(ArcCurve::build(base, e1, e2, axis, r, 0.0, 0.0, (0.0, sweep), start, end)))
    }

    /// Length of the path parameter, machine units (the arc length except on spirals, where
    /// it is a slight over-estimate).
    pub(crate) fn len(&self) -> f64 {
        match self {
            Curve::Line(l) => l.len,
            Curve::Arc(a) => a.len,
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
    pub(crate) fn start(&self) -> Xyz {
        match self {
            Curve::Line(l) => l.start,
            Curve::Arc(a) => a.start,
        }
    }

    /// The exact end point.
    pub(crate) fn end(&self) -> Xyz {
        match self {
            Curve::Line(l) => l.end,
            Curve::Arc(a) => a.end,
        }
    }

    /// The point at parameter `s` (clamped; the ends are exact).
    pub(crate) fn point(&self, s: f64) -> Xyz {
        if s <= 0.0 {
            return self.start();
        }
        if s >= self.len() {
            return self.end();
        }
        match self {
            Curve::Line(l) => l.start + l.dir * s,
            Curve::Arc(a) => a.at_phi(a.phi_h(s).0),
        }
    }

    /// `dp/ds` at parameter `s` (a unit vector except inside spirals, where `|dp/ds| ≤ 1`).
    pub(crate) fn deriv(&self, s: f64) -> Xyz {
        match self {
            Curve::Line(l) => l.dir,
            Curve::Arc(a) => {
                let (phi, h) = a.phi_h(s.clamp(0.0, a.len));
                a.direction(a.radial(phi), phi, h)
            }
        }
    }

    /// [`Curve::point`] and [`Curve::deriv`] at `s` together, bit for bit, evaluating an
    /// arc's angle once (the setpoint hot path).
    pub(crate) fn point_and_deriv(&self, s: f64) -> (Xyz, Xyz) {
        match self {
            Curve::Line(l) => (self.point(s), l.dir),
            Curve::Arc(a) => {
                let (phi, h) = a.phi_h(s.clamp(0.0, a.len));
                let dirs = a.radial(phi);
                let point = if s <= 0.0 {
                    a.start
                } else if s >= a.len {
                    a.end
                } else {
                    a.position(dirs.0, phi)
                };
                (point, a.direction(dirs, phi, h))
            }
        }
    }

    /// Unit tangent at the start.
    pub(crate) fn start_tangent(&self) -> Xyz {
        let d = self.deriv(0.0);
        d.unit().unwrap_or(d)
    }

    /// Unit tangent at the end.
    pub(crate) fn end_tangent(&self) -> Xyz {
        let d = self.deriv(self.len());
        d.unit().unwrap_or(d)
    }

    /// The part of the curve between parameters `a < b` (clamped), keeping exact ends where
    /// they are the original ends. An arc's part gets its own parameter, so `|dp/ds| = 1` at
    /// its ends too (a spiral cut for a blend joins the blend at the same speed).
    pub(crate) fn sub(&self, a: f64, b: f64) -> Curve {
        let len = self.len();
        let (a, b) = (a.clamp(0.0, len), b.clamp(0.0, len));
        let start = self.point(a);
        let end = self.point(b);
        match self {
            Curve::Line(l) => Curve::Line(LineCurve { start, end, dir: l.dir, len: b - a }),
            Curve::Arc(arc) => Curve::Arc(ArcCurve::build(
                arc.base,
                arc.e1,
                arc.e2,
                arc.axis,
                arc.r0,
                arc.k_r,
                arc.k_z,
                (arc.phi_h(a).0, arc.phi_h(b).0),
                start,
                end,
            )),
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
            Curve::Arc(a) => a.r0 + a.k_r * a.phi_a,
        }
    }

    /// Whether this is a helical arc (its corners are not blended).
    pub(crate) fn is_helix(&self) -> bool {
        matches!(self, Curve::Arc(a) if a.is_helix())
    }

    /// Distance from `p` to this curve, for lines and planar arcs (not helices).
    pub(crate) fn distance_to(&self, p: Xyz) -> f64 {
        match self {
            Curve::Line(l) => {
                let t = (p - l.start).dot(l.dir).clamp(0.0, l.len);
                (p - (l.start + l.dir * t)).norm()
            }
            Curve::Arc(a) => a.distance_planar(p),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn close(a: Xyz, b: Xyz, tol: f64) -> bool {
        (a - b).norm() <= tol
    }

    #[test]
    fn a_nearly_straight_tangent_arc_is_as_long_as_its_chord_and_runs_along_it() {
        // A biarc piece a planner run produced (radius 7.4 km, 0.13 mm long): its sweep came
        // out 2.5 times too large, so the path ran 0.2 mm past the piece's end and jumped back.
        let start = Xyz::new(-4.111846120672503, 0.6365548900226443, 3.0);
        let end = Xyz::new(-4.242390796453222, 0.6147396097029565, 3.0);
        let tangent = Xyz::new(-0.9863229716703146, -0.16482413523340556, 0.0);
        let arc = Curve::from_tangent(start, tangent, end).unwrap();
        assert!(matches!(arc, Curve::Arc(_)) && arc.radius() > 1e6, "{arc:?}");
        let chord = (end - start).norm();
        assert!((arc.len() - chord).abs() < 1e-12, "{} vs {chord}", arc.len());
        for k in 0..=8 {
            let s = arc.len() * f64::from(k) / 8.0;
            let along = start + (end - start) * (f64::from(k) / 8.0);
            assert!(close(arc.point(s), along, 1e-9), "{k}: {:?} vs {along:?}", arc.point(s));
        }
        // And an ordinary one: a half circle of radius 1.
        let half = Curve::from_tangent(Xyz::ZERO, Xyz::new(0.0, 1.0, 0.0), Xyz::new(2.0, 0.0, 0.0)).unwrap();
        assert!((half.len() - PI).abs() < 1e-12 && (half.radius() - 1.0).abs() < 1e-12);
        assert!(close(half.point(FRAC_PI_2), Xyz::new(1.0, 1.0, 0.0), 1e-12));
    }

    #[test]
    fn a_quarter_circle_g3_in_xy_runs_counter_clockwise_with_exact_ends() {
        let (s, e, c) = (Xyz::new(10.0, 0.0, 0.0), Xyz::new(0.0, 10.0, 0.0), Xyz::ZERO);
        let arc = Curve::Arc(ArcCurve::program(s, e, c, Xyz::new(0.0, 0.0, 1.0), FRAC_PI_2).unwrap());
        assert!((arc.len() - 10.0 * FRAC_PI_2).abs() < 1e-12);
        assert_eq!(arc.point(arc.len()), e);
        assert_eq!(arc.point(0.0), s);
        let mid = arc.point(arc.len() / 2.0);
        assert!(close(mid, Xyz::new(10.0 / 2f64.sqrt(), 10.0 / 2f64.sqrt(), 0.0), 1e-12));
        assert!(close(arc.start_tangent(), Xyz::new(0.0, 1.0, 0.0), 1e-12));
        assert!(close(arc.end_tangent(), Xyz::new(-1.0, 0.0, 0.0), 1e-12));
    }

    #[test]
    fn g2_goes_the_other_way_round_and_equal_ends_make_a_full_circle() {
        let (s, e, c) = (Xyz::new(10.0, 0.0, 0.0), Xyz::new(0.0, 10.0, 0.0), Xyz::ZERO);
        let cw = Curve::Arc(ArcCurve::program(s, e, c, Xyz::new(0.0, 0.0, 1.0), -3.0 * FRAC_PI_2).unwrap());
        assert!((cw.len() - 10.0 * 3.0 * FRAC_PI_2).abs() < 1e-9);
        assert!(close(cw.point(cw.len() / 3.0), Xyz::new(0.0, -10.0, 0.0), 1e-9));
        let full = Curve::Arc(ArcCurve::program(s, s, c, Xyz::new(0.0, 0.0, 1.0), TAU).unwrap());
        assert!((full.len() - 20.0 * PI).abs() < 1e-9);
        let two = Curve::Arc(ArcCurve::program(s, s, c, Xyz::new(0.0, 0.0, 1.0), 2.0 * TAU).unwrap());
        assert!((two.len() - 40.0 * PI).abs() < 1e-9);
    }

    #[test]
    fn g18_and_g19_planes_follow_the_right_hand_rule() {
        // G18: normal +Y; counter-clockwise goes from +Z towards +X.
        let arc = Curve::Arc(
            ArcCurve::program(
                Xyz::new(0.0, 0.0, 5.0),
                Xyz::new(5.0, 0.0, 0.0),
                Xyz::ZERO,
                Xyz::new(0.0, 1.0, 0.0),
                FRAC_PI_2,
            )
            .unwrap(),
        );
        assert!((arc.len() - 5.0 * FRAC_PI_2).abs() < 1e-12);
        // G19: normal +X; counter-clockwise goes from +Y towards +Z.
        let arc = Curve::Arc(
            ArcCurve::program(
                Xyz::new(0.0, 5.0, 0.0),
                Xyz::new(0.0, 0.0, 5.0),
                Xyz::ZERO,
                Xyz::new(1.0, 0.0, 0.0),
                FRAC_PI_2,
            )
            .unwrap(),
        );
        assert!((arc.len() - 5.0 * FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn a_helix_rises_linearly_and_its_length_includes_the_rise() {
        let s = Xyz::new(10.0, 0.0, 0.0);
        let e = Xyz::new(-10.0, 0.0, 4.0);
        let arc = Curve::Arc(ArcCurve::program(s, e, Xyz::ZERO, Xyz::new(0.0, 0.0, 1.0), PI).unwrap());
        let expected = ((10.0 * PI).powi(2) + 16.0f64).sqrt();
        assert!((arc.len() - expected).abs() < 1e-9);
        assert!((arc.point(arc.len() / 2.0).z - 2.0).abs() < 1e-12);
        assert!((arc.deriv(1.0).norm() - 1.0).abs() < 1e-12);
        let f = arc.factors();
        assert!((f.c[2] - 4.0 / expected).abs() < 1e-12, "Z carries only the rise: {:?}", f.c);
    }

    #[test]
    fn a_spiral_keeps_its_parameter_speed_at_most_one_and_exactly_one_at_its_ends() {
        let s = Xyz::new(10.0, 0.0, 0.0);
        let e = Xyz::new(0.0, 10.01, 0.0);
        let arc = Curve::Arc(ArcCurve::program(s, e, Xyz::ZERO, Xyz::new(0.0, 0.0, 1.0), FRAC_PI_2).unwrap());
        for k in 0..=20 {
            let d = arc.deriv(arc.len() * f64::from(k) / 20.0).norm();
            assert!(d <= 1.0 + 1e-15 && d > 0.999, "{d}");
        }
        assert!((arc.deriv(0.0).norm() - 1.0).abs() < 1e-15);
        assert!((arc.deriv(arc.len()).norm() - 1.0).abs() < 1e-15);
        assert_eq!(arc.point(arc.len()), e);
        // A part cut out of it (as a blend does) runs at speed 1 at its own ends too.
        let part = arc.sub(1.0, 9.0);
        assert!((part.deriv(0.0).norm() - 1.0).abs() < 1e-15);
        assert!((part.deriv(part.len()).norm() - 1.0).abs() < 1e-15);
        assert!(close(part.start(), arc.point(1.0), 1e-12) && close(part.end(), arc.point(9.0), 1e-12));
        assert!(close(part.point(part.len() / 2.0), arc.point(5.0), 1e-3));
    }

    /// `|dp/ds| ≤ 1` and every [`ShapeFactors`] bound, checked by finite differences along
    /// circles, helices, spirals (up to a radius ratio of 3) and spiral helices in all
    /// orientations, and along parts of them.
    #[test]
    fn the_shape_factors_bound_the_derivatives_of_every_arc() {
        let normals = [Xyz::new(0.0, 0.0, 1.0), Xyz::new(0.0, 1.0, 0.0), Xyz::new(0.3, -0.5, 0.8)];
        let mut checked = 0;
        for normal in normals {
            let n = normal.unit().unwrap();
            let e1 = Xyz::new(1.0, 2.0, -0.5).cross(n).unit().unwrap();
            let e2 = n.cross(e1);
            for (r0, r1) in [(2.0, 2.0), (1.0, 1.5), (1.5, 1.0), (0.1, 0.128), (3.0, 1.0), (1.0, 3.0)] {
                for rise in [0.0, 0.7, -4.0] {
                    for sweep in [0.3f64, -2.5, 9.0] {
                        let start = e1 * r0;
                        let (sin, cos) = sweep.abs().sin_cos();
                        let turn = if sweep < 0.0 { -1.0 } else { 1.0 };
                        let end = (e1 * cos + e2 * (turn * sin)) * r1 + n * rise;
                        let arc = Curve::Arc(ArcCurve::program(start, end, Xyz::ZERO, normal, sweep).unwrap());
                        for piece in [arc.sub(0.0, arc.len()), arc.sub(0.3 * arc.len(), 0.7 * arc.len())] {
                            check_factors(&piece);
                            checked += 1;
                        }
                    }
                }
            }
        }
        assert_eq!(checked, 3 * 6 * 3 * 3 * 2);
    }

    fn check_factors(c: &Curve) {
        let f = c.factors();
        let (len, d) = (c.len(), 1e-5 * c.len());
        assert!((c.deriv(0.0).norm() - 1.0).abs() < 1e-14 && (c.deriv(len).norm() - 1.0).abs() < 1e-14);
        for k in 1..200 {
            let s = len * f64::from(k) / 200.0;
            let d1 = c.deriv(s);
            let d2 = (c.deriv(s + d) - c.deriv(s - d)) * (0.5 / d);
            let slack = 1e-6 * (1.0 + f.kappa);
            assert!(d1.norm() <= 1.0 + 1e-14, "|dp/ds| = {}", d1.norm());
            assert!(d2.norm() <= f.kappa + slack, "{} > kappa {}", d2.norm(), f.kappa);
            assert!(d1.dot(d2).abs() <= f.cross * f.kappa + slack, "{} > cross {f:?}", d1.dot(d2));
            let (a1, a2): ([f64; 3], [f64; 3]) = (d1.into(), d2.into());
            for i in 0..3 {
                assert!(a1[i].abs() <= f.c[i] + 1e-12, "axis {i}: {} > c {f:?}", a1[i]);
                assert!(a2[i].abs() <= f.q[i] * f.kappa + slack, "axis {i}: {} > q·kappa {f:?}", a2[i]);
            }
            if f.circle {
                let a = d2 * 0.3 + d1 * 0.7;
                let parts: [f64; 3] = a.into();
                for (part, q) in parts.iter().zip(f.q) {
                    assert!(part.abs() <= q * a.norm() + 1e-12, "a circle's vectors lie in its plane");
                }
            }
        }
    }

    #[test]
    fn point_and_deriv_are_point_and_deriv() {
        let s = Xyz::new(10.0, 0.0, 0.0);
        let e = Xyz::new(0.0, 10.5, 3.0);
        let spiral = Curve::Arc(ArcCurve::program(s, e, Xyz::ZERO, Xyz::new(0.0, 0.0, 1.0), FRAC_PI_2).unwrap());
        let line = Curve::Line(LineCurve::new(s, e).unwrap());
        for c in [spiral.clone(), spiral.sub(2.0, 9.0), line] {
            for k in -2..=42 {
                let at = c.len() * f64::from(k) / 40.0;
                assert_eq!(c.point_and_deriv(at), (c.point(at), c.deriv(at)), "{c:?} at {at}");
            }
        }
    }

    #[test]
    fn degenerate_arcs_are_reported() {
        let s = Xyz::new(1.0, 0.0, 0.0);
        let z = Xyz::new(0.0, 0.0, 1.0);
        assert_eq!(ArcCurve::program(s, s, s, z, TAU), Err(ArcProblem::OnCentre));
        assert_eq!(ArcCurve::program(s, s, Xyz::ZERO, Xyz::ZERO, TAU), Err(ArcProblem::NoPlane));
        for sweep in [0.0, -0.0, f64::NAN, f64::INFINITY, 2.0 * MAX_SWEEP] {
            assert_eq!(ArcCurve::program(s, s, Xyz::ZERO, z, sweep), Err(ArcProblem::BadSweep), "{sweep}");
        }
        // A quarter turn does not reach the opposite point.
        let e = Xyz::new(-1.0, 0.0, 0.0);
        assert_eq!(ArcCurve::program(s, e, Xyz::ZERO, z, FRAC_PI_2), Err(ArcProblem::MissesEnd));
        // A rise of 5 over next to no angle: the pitch or the length overflows.
        let up = Xyz::new(1.0, 0.0, 5.0);
        assert_eq!(ArcCurve::program(s, up, Xyz::ZERO, z, 1e-308), Err(ArcProblem::MissesEnd));
        assert_eq!(ArcCurve::program(s, up, Xyz::ZERO, z, 1e-300), Err(ArcProblem::BadSweep));
    }

    #[test]
    fn the_sweep_decides_the_arc_not_a_full_circle_rule() {
        // The interpreter's `G0 X10 Y0 / G3 X10 Y0.00000001 I-10 J0`: a 1e-9 rad arc, not a
        // full circle.
        let (s, e) = (Xyz::new(10.0, 0.0, 0.0), Xyz::new(10.0, 1e-8, 0.0));
        let z = Xyz::new(0.0, 0.0, 1.0);
        let tiny = Curve::Arc(ArcCurve::program(s, e, Xyz::ZERO, z, 1e-9).unwrap());
        assert!((tiny.len() - 1e-8).abs() < 1e-20, "{}", tiny.len());
        // The same points with a sweep of one turn more: the full circle (plus the sliver).
        let full = Curve::Arc(ArcCurve::program(s, e, Xyz::ZERO, z, TAU + 1e-9).unwrap());
        assert!((full.len() - 10.0 * (TAU + 1e-9)).abs() < 1e-9);
        // Clockwise the long way round.
        let back = Curve::Arc(ArcCurve::program(s, e, Xyz::ZERO, z, 1e-9 - TAU).unwrap());
        assert!((back.len() - 10.0 * (TAU - 1e-9)).abs() < 1e-9);
        assert!(close(back.point(back.len() / 4.0), Xyz::new(0.0, -10.0, 0.0), 1e-6));
    }

    #[test]
    fn an_arc_from_a_tangent_is_tangent_there_and_ends_at_the_target() {
        let start = Xyz::new(-1.0, 0.0, 0.0);
        let end = Xyz::new(0.0, 1.0, 0.0);
        let c = Curve::from_tangent(start, Xyz::new(1.0, 0.0, 0.0), end).unwrap();
        assert!((c.radius() - 1.0).abs() < 1e-12);
        assert!(close(c.end_tangent(), Xyz::new(0.0, 1.0, 0.0), 1e-12));
        assert!((c.distance_to(Xyz::ZERO) - (2f64.sqrt() - 1.0)).abs() < 1e-12);
        let line = Curve::from_tangent(start, Xyz::new(1.0, 0.0, 0.0), Xyz::new(3.0, 0.0, 0.0)).unwrap();
        assert!(matches!(line, Curve::Line(_)));
        assert!(Curve::from_tangent(start, Xyz::new(1.0, 0.0, 0.0), Xyz::new(-3.0, 0.0, 0.0)).is_none());
    }

    #[test]
    fn a_sub_curve_keeps_the_geometry_between_its_parameters() {
        let arc = Curve::Arc(
            ArcCurve::program(
                Xyz::new(10.0, 0.0, 0.0),
                Xyz::new(-10.0, 0.0, 0.0),
                Xyz::ZERO,
                Xyz::new(0.0, 0.0, 1.0),
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
