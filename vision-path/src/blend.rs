//! G64 corner blending: replace the corner between two pieces by circular arcs tangent to
//! both, passing within the tolerance of the programmed corner point.
//!
//! A blend is made as small as keeps the path at full speed — its radius `wanted`, the one at
//! which its centripetal limit allows the neighbours' speed — and never larger than the
//! tolerance and half of each neighbour allow: the path deviates no more than it must.
//!
//! * Two lines: one circular arc tangent to both at equal distances `ℓ` from the corner
//!   (radius `ℓ / tan(θ/2)`, passing `ℓ·tan(θ/4)` from the corner).
//! * Any arc involved: a biarc (two tangent-continuous circular arcs) between points at equal
//!   path distance `s` before and after the corner, `s` found by bisection, then checked (and
//!   shrunk) against the programmed path.

use crate::curve::Curve;
use vision_gcode::Xyz;

/// A corner blend: trim `s1` off the end of the incoming piece and `s2` off the start of the
/// outgoing one, and insert `pieces` between them.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Blend {
    pub(crate) s1: f64,
    pub(crate) s2: f64,
    pub(crate) pieces: Vec<Curve>,
}

/// The smallest trim (machine units) a blend uses when the tolerance and the neighbours allow
/// it, so that even a nearly tangent corner gets a blend long enough to keep.
const MIN_TRIM: f64 = 1e-6;

/// Blend the corner at `c1.end()` between `c1` and `c2`. `s1_max` and `s2_max` bound the
/// trims (half of each neighbour); `tolerance` bounds the distance from the corner point and
/// from the programmed path (`None`: only the trims bound it); `wanted` is the blend radius
/// beyond which a larger blend would not be faster (machine units). `None` when no useful
/// blend exists (the caller stops).
pub(crate) fn blend(
    c1: &Curve,
    s1_max: f64,
    c2: &Curve,
    s2_max: f64,
    tolerance: Option<f64>,
    wanted: f64,
) -> Option<Blend> {
    let s_max = s1_max.min(s2_max).min(c1.len()).min(c2.len());
    if !(s_max > 0.0) {
        return None;
    }
    let corner = c1.end();
    if let (Curve::Line(_), Curve::Line(_)) = (c1, c2) {
        let (u1, u2) = (c1.end_tangent(), c2.start_tangent());
        let theta = u1.angle_to(u2);
        let cap = tolerance.map_or(s_max, |p| s_max.min(p / (theta / 4.0).tan()));
        let ell = (wanted * (theta / 2.0).tan()).min(cap).max(MIN_TRIM.min(cap));
        if !(ell > 0.0) {
            return None;
        }
        let arc = Curve::from_tangent(c1.point(c1.len() - ell), u1, c2.point(ell))?;
        return Some(Blend { s1: ell, s2: ell, pieces: vec![arc] });
    }
    if c1.is_helix() || c2.is_helix() {
        return None;
    }
    let build = |lambda: f64| -> Option<Vec<Curve>> {
        let s = lambda * s_max;
        let (sa, sb) = (c1.len() - s, s);
        biarc(c1.point(sa), c1.deriv(sa).unit()?, c2.point(sb), c2.deriv(sb).unit()?)
    };
    let near_corner = |pieces: &[Curve]| pieces.iter().map(|p| p.distance_to(corner)).fold(f64::INFINITY, f64::min);
    let radius = |pieces: &[Curve]| pieces.iter().map(Curve::radius).fold(f64::INFINITY, f64::min);
    // Each search keeps the biarc of the trim it settles on, so none is built twice.
    // The largest trim that gives a biarc within P of the corner …
    let fits = |lambda: f64| build(lambda).filter(|b| tolerance.is_none_or(|p| near_corner(b) <= p));
    let (mut lambda, mut pieces) = match fits(1.0) {
        Some(b) => (1.0, Some(b)),
        None => largest(0.0, 1.0, fits),
    };
    // … no larger than keeps the path at speed …
    let floor = (MIN_TRIM / s_max).min(lambda);
    if let Some(b) = pieces.take_if(|b| radius(b) > wanted) {
        let (l, b) = smallest(floor, lambda, b, |l| build(l).filter(|b| radius(b) >= wanted));
        (lambda, pieces) = (l, Some(b));
    }
    // … and shrunk until the whole blend also stays within P of the programmed path (a
    // biarc between arcs can bulge slightly beyond the corner's distance).
    for _ in 0..20 {
        let pieces_now = pieces.filter(|_| lambda > 0.0)?;
        let s = lambda * s_max;
        let Some(p) = tolerance else {
            return Some(Blend { s1: s, s2: s, pieces: pieces_now });
        };
        let dev = path_deviation(&pieces_now, &c1.sub(c1.len() - s, c1.len()), &c2.sub(0.0, s));
        if dev <= p * (1.0 - DEVIATION_MARGIN) {
            return Some(Blend { s1: s, s2: s, pieces: pieces_now });
        }
        lambda *= 0.99 * p * (1.0 - DEVIATION_MARGIN) / dev;
        pieces = build(lambda);
    }
    None
}

/// Bisection steps of the trim searches.
const SEARCH_STEPS: u32 = 30;

/// The largest `x` in `(lo, hi]` where `ok(x)` gives a value, for `ok` giving one below some
/// threshold, with that value (`(lo, None)` if none is found).
fn largest<T>(mut lo: f64, mut hi: f64, ok: impl Fn(f64) -> Option<T>) -> (f64, Option<T>) {
    let mut found = None;
    for _ in 0..SEARCH_STEPS {
        let mid = 0.5 * (lo + hi);
        match ok(mid) {
            Some(v) => (lo, found) = (mid, Some(v)),
            None => hi = mid,
        }
    }
    (lo, found)
}

/// The smallest `x` in `[lo, hi]` where `ok(x)` gives a value, for `ok` giving one above some
/// threshold and at `hi` (`at_hi`), with that value.
fn smallest<T>(mut lo: f64, mut hi: f64, at_hi: T, ok: impl Fn(f64) -> Option<T>) -> (f64, T) {
    if let Some(v) = ok(lo) {
        return (lo, v);
    }
    let mut found = at_hi;
    for _ in 0..SEARCH_STEPS {
        let mid = 0.5 * (lo + hi);
        match ok(mid) {
            Some(v) => (hi, found) = (mid, v),
            None => lo = mid,
        }
    }
    (hi, found)
}

/// Samples along the blend when looking for its largest deviation from the path.
const DEVIATION_SAMPLES: u32 = 32;
/// Relative margin left for what the refined search may still miss.
const DEVIATION_MARGIN: f64 = 1e-3;

/// The largest distance from the blend pieces to the programmed path they replace: sampled,
/// then refined by a ternary search around the worst sample (the distance to the nearer of
/// two curves peaks in a kink, where sampling alone misses it by first order).
fn path_deviation(pieces: &[Curve], tail: &Curve, head: &Curve) -> f64 {
    let total: f64 = pieces.iter().map(Curve::len).sum();
    let at = |u: f64| {
        let mut u = u.clamp(0.0, total);
        for piece in pieces {
            if u <= piece.len() {
                let x = piece.point(u);
                return tail.distance_to(x).min(head.distance_to(x));
            }
            u -= piece.len();
        }
        0.0
    };
    let step = total / f64::from(DEVIATION_SAMPLES);
    let (mut worst_u, mut worst) = (0.0, 0.0f64);
    for j in 0..=DEVIATION_SAMPLES {
        let u = step * f64::from(j);
        let d = at(u);
        if d > worst {
            (worst_u, worst) = (u, d);
        }
    }
    let (mut lo, mut hi) = (worst_u - step, worst_u + step);
    for _ in 0..40 {
        let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
        if at(m1) < at(m2) {
            lo = m1;
        } else {
            hi = m2;
        }
    }
    worst.max(at(0.5 * (lo + hi)))
}

/// Two circular arcs (or lines) from `a` leaving along `ta` to `b` arriving along `tb`,
/// tangent-continuous where they meet (the equal-tangent-length biarc).
fn biarc(a: Xyz, ta: Xyz, b: Xyz, tb: Xyz) -> Option<Vec<Curve>> {
    let v = b - a;
    let t = ta + tb;
    let qa = 2.0 * (ta.dot(tb) - 1.0);
    let qb = -2.0 * v.dot(t);
    let qc = v.dot(v);
    let d = if qa.abs() < 1e-12 {
        if !(v.dot(t) > 0.0) {
            return None;
        }
        qc / (2.0 * v.dot(t))
    } else {
        let root = (qb * qb - 4.0 * qa * qc).sqrt();
        2.0 * qc / (root - qb)
    };
    if !(d.is_finite() && d > 0.0) {
        return None;
    }
    let q0 = a + ta * d;
    let q1 = b - tb * d;
    let m = (q0 + q1) * 0.5;
    let tm = (q1 - q0).unit()?;
    let first = Curve::from_tangent(a, ta, m)?;
    let second = Curve::from_tangent(m, tm, b)?;
    let joins = first.end_tangent().angle_to(tm) < 1e-6 && second.end_tangent().angle_to(tb) < 1e-6;
    let no_loops = first.sweep() <= std::f64::consts::PI && second.sweep() <= std::f64::consts::PI;
    (joins && no_loops).then(|| vec![first, second])
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;
    use crate::curve::{ArcCurve, LineCurve};

    fn line(a: [f64; 3], b: [f64; 3]) -> Curve {
        Curve::Line(LineCurve::new(a.into(), b.into()).unwrap())
    }

    #[test]
    fn a_square_corner_blend_passes_exactly_p_from_the_corner() {
        let c1 = line([0.0, 0.0, 0.0], [100.0, 0.0, 0.0]);
        let c2 = line([100.0, 0.0, 0.0], [100.0, 100.0, 0.0]);
        let b = blend(&c1, 50.0, &c2, 50.0, Some(1.0), f64::INFINITY).unwrap();
        assert_eq!(b.pieces.len(), 1);
        let dev = b.pieces[0].distance_to(Xyz::new(100.0, 0.0, 0.0));
        assert!((dev - 1.0).abs() < 1e-9, "{dev}");
        // ℓ = P / tan(22.5°), radius ℓ / tan(45°) = ℓ.
        let ell = 1.0 / (std::f64::consts::PI / 8.0).tan();
        assert!((b.s1 - ell).abs() < 1e-9 && (b.pieces[0].radius() - ell).abs() < 1e-9);
        assert!(b.pieces[0].start_tangent().angle_to(c1.end_tangent()) < 1e-12);
        assert!(b.pieces[0].end_tangent().angle_to(c2.start_tangent()) < 1e-12);
    }

    #[test]
    fn without_p_a_line_blend_uses_half_of_the_shorter_neighbour_at_most() {
        let c1 = line([0.0, 0.0, 0.0], [10.0, 0.0, 0.0]);
        let c2 = line([10.0, 0.0, 0.0], [10.0, 4.0, 0.0]);
        let b = blend(&c1, 5.0, &c2, 2.0, None, f64::INFINITY).unwrap();
        assert_eq!(b.s1, 2.0);
        assert_eq!(b.s2, 2.0);
    }

    #[test]
    fn a_blend_is_no_larger_than_keeps_the_speed() {
        let c1 = line([0.0, 0.0, 0.0], [100.0, 0.0, 0.0]);
        let c2 = line([100.0, 0.0, 0.0], [100.0, 100.0, 0.0]);
        // A square corner: radius = ℓ, so wanting radius 3 trims 3 (P10 would allow 24).
        let b = blend(&c1, 50.0, &c2, 50.0, Some(10.0), 3.0).unwrap();
        assert!((b.s1 - 3.0).abs() < 1e-12);
        assert!((b.pieces[0].radius() - 3.0).abs() < 1e-9);
        // A nearly straight join still gets a blend of at least the minimum trim.
        let c3 = line([100.0, 0.0, 0.0], [200.0, 1e-7, 0.0]);
        let b = blend(&c1, 50.0, &c3, 50.0, None, 1.0).unwrap();
        assert!(b.s1 >= MIN_TRIM && b.pieces[0].len() > 1e-7);
    }

    #[test]
    fn a_line_to_arc_corner_gets_a_tangent_biarc_within_p() {
        // The seed's example: G1 to (110, 110), then G2 about (100, 60) to (110, 10).
        let c1 = line([60.0, 110.0, 0.0], [110.0, 110.0, 0.0]);
        let c2 = Curve::Arc(
            ArcCurve::program(
                Xyz::new(110.0, 110.0, 0.0),
                Xyz::new(110.0, 10.0, 0.0),
                Xyz::new(100.0, 60.0, 0.0),
                Xyz::new(0.0, 0.0, 1.0),
                -2.0 * 50f64.atan2(10.0),
            )
            .unwrap(),
        );
        let b = blend(&c1, c1.len() / 2.0, &c2, c2.len() / 2.0, Some(0.5), f64::INFINITY).unwrap();
        assert_eq!(b.pieces.len(), 2);
        let corner = Xyz::new(110.0, 110.0, 0.0);
        let dev = b.pieces.iter().map(|p| p.distance_to(corner)).fold(f64::INFINITY, f64::min);
        assert!(dev <= 0.5 && dev > 0.4, "the search should use most of the tolerance: {dev}");
        let a = c1.point(c1.len() - b.s1);
        assert!((b.pieces[0].start() - a).norm() < 1e-12);
        assert!(b.pieces[0].start_tangent().angle_to(c1.end_tangent()) < 1e-9);
        assert!(b.pieces[1].end_tangent().angle_to(c2.deriv(b.s2).unit().unwrap()) < 1e-9);
        assert!((b.pieces[1].end() - c2.point(b.s2)).norm() < 1e-12);
    }

    #[test]
    fn a_biarc_between_symmetric_tangents_is_one_circle() {
        let pieces =
            biarc(Xyz::new(-1.0, 0.0, 0.0), Xyz::new(1.0, 0.0, 0.0), Xyz::new(0.0, 1.0, 0.0), Xyz::new(0.0, 1.0, 0.0))
                .unwrap();
        for p in &pieces {
            assert!((p.radius() - 1.0).abs() < 1e-12);
        }
    }
}
