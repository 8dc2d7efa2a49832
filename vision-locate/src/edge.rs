//! A straight edge as a square pixel sees it: the step, blurred by a Gaussian of σ = `s` px
//! (defocus), averaged over the pixel's unit square (what the sensor and the renderer do).
//!
//! Projected onto the edge normal n = (cos φ, sin φ), the square is the sum of two uniform
//! offsets of widths a = |cos φ| and b = |sin φ| (a trapezoid), so the covered fraction at depth
//! t px inside the edge is the step convolved with two boxes and a Gaussian:
//!
//! `m(t) = s²/(a·b) · [G((t + c₁)/s) − G((t + c₂)/s) − G((t − c₂)/s) + G((t − c₁)/s)]`,
//! c₁ = (a + b)/2, c₂ = (a − b)/2, with G(u) = ((u² + 1)·Φ(u) + u·φ(u))/2 the second
//! antiderivative of Φ (the first is F(u) = u·Φ(u) + φ(u)). An edge along a pixel axis (b → 0)
//! takes the one-box form `s/a · [F((t + a/2)/s) − F((t − a/2)/s)]`.
//!
//! From s = [`S_SMOOTH`] on, the blur hides the trapezoid's shape but for its variance (1/12) and
//! a small fourth cumulant; the first Edgeworth term then matches the closed form to 1e-3 of the
//! contrast (less than 0.2 grey levels for a full-scale 8-bit edge), at one normal CDF instead
//! of four.

use crate::special::cdf_pdf;

/// Least blur σ (px) a model takes: a sharp edge is fitted at this blur, whose own effect (a
/// rounding of the ramp's corners over ~0.01 px) is far below the noise. It keeps the closed
/// form's divisions finite.
pub(crate) const S_MIN: f64 = 0.005;

/// Blur σ (px) from which the Edgeworth form replaces the closed form.
pub(crate) const S_SMOOTH: f64 = 0.5;

/// Below this width (a fraction of the pixel) a box counts as absent: an edge along a pixel
/// axis. Its effect, b²/24 times the profile's curvature, stays below 1e-5 of the contrast.
const THIN: f64 = 1e-3;

/// Beyond this many σ from 0, Φ is taken as 0 or 1 (it is within 1e-9 of it).
const FAR: f64 = 6.0;

/// The covered fraction of a pixel and its derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Edge {
    /// Covered fraction, 0 … 1.
    pub(crate) m: f64,
    /// ∂m/∂t, per px of depth.
    pub(crate) dt: f64,
    /// ∂m/∂s, per px of blur.
    pub(crate) ds: f64,
    /// ∂m/∂φ, per radian of the normal's direction.
    pub(crate) dphi: f64,
}

/// The pixel at depth `t` px inside an edge whose unit normal is (`nx`, `ny`), blur σ = `s` px
/// (at least [`S_MIN`]).
#[cfg(test)]
pub(crate) fn edge(t: f64, nx: f64, ny: f64, s: f64) -> Edge {
    Blur::new(s).profile(nx, ny).at(t)
}

/// What the profile needs of the blur alone, worked out once per pass.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Blur {
    s: f64,
    /// 1/s for the closed form; 1/σₑ for the Edgeworth form.
    inv: f64,
    /// σₑ² = s² + 1/12 and 1/(24·σₑ⁴) for the Edgeworth form.
    var: f64,
    scale: f64,
    /// The Edgeworth form's reach, FAR·σₑ px.
    far: f64,
    smooth: bool,
}

impl Blur {
    /// Blur σ = `s` px (at least [`S_MIN`]).
    pub(crate) fn new(s: f64) -> Blur {
        let smooth = s >= S_SMOOTH;
        let var = s * s + 1.0 / 12.0;
        let inv = if smooth { 1.0 / var.sqrt() } else { 1.0 / s };
        Blur { s, inv, var, scale: 1.0 / (24.0 * var * var), far: FAR * var.sqrt(), smooth }
    }

    /// The profile of edges of unit normal (`nx`, `ny`).
    #[inline]
    pub(crate) fn profile(&self, nx: f64, ny: f64) -> Profile {
        if self.smooth {
            self.smooth(nx, ny)
        } else {
            self.closed(nx, ny)
        }
    }

    #[inline]
    fn smooth(&self, nx: f64, ny: f64) -> Profile {
        let (a2, b2) = (nx * nx, ny * ny);
        // κ₄ and its slope in φ (a²·b² turns at 2·nx·ny·(nx² − ny²) per radian).
        let k4 = -(a2 * a2 + b2 * b2) / 120.0;
        let d_k4 = nx * ny * (a2 - b2) / 30.0;
        let (lam, d_lam) = (k4 * self.scale, d_k4 * self.scale);
        Profile { far: self.far, kind: Kind::Smooth { var: self.var, inv_se: self.inv, lam, s: self.s, d_lam } }
    }

    #[inline]
    fn closed(&self, nx: f64, ny: f64) -> Profile {
        let (a, b, s, inv) = (nx.abs(), ny.abs(), self.s, self.inv);
        let c1 = 0.5 * (a + b);
        let far = c1 + FAR * s;
        if a.min(b) < THIN {
            return Profile { far, kind: Kind::OneBox { s, inv, w: a.max(b) } };
        }
        let sign = if nx * ny < 0.0 { -1.0 } else { 1.0 };
        Profile { far, kind: Kind::Exact { s, inv, c1, c2: 0.5 * (a - b), k: 1.0 / (a * b), a, b, sign } }
    }
}

/// The profile of the edges with one normal direction and blur, for any depth: what does not
/// depend on the depth worked out once (a cross has one such for all its edges).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Profile {
    /// Depth (px) beyond which the pixel is wholly inside (or, negated, outside).
    far: f64,
    kind: Kind,
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    /// The closed form: blur s, 1/s, the trapezoid's c₁ and c₂, 1/(a·b), a, b, sign(nx·ny).
    Exact { s: f64, inv: f64, c1: f64, c2: f64, k: f64, a: f64, b: f64, sign: f64 },
    /// An edge along a pixel axis: blur s, 1/s, the box width w.
    OneBox { s: f64, inv: f64, w: f64 },
    /// The Edgeworth form: σₑ², 1/σₑ, λ, the blur s and ∂λ/∂φ.
    Smooth { var: f64, inv_se: f64, lam: f64, s: f64, d_lam: f64 },
}

impl Profile {
    /// The pixel at depth `t` px inside the edge.
    #[inline(always)]
    pub(crate) fn at(&self, t: f64) -> Edge {
        // Wholly in or out (past the trapezoid and the blur's reach): the common case.
        if t > self.far {
            return INSIDE;
        }
        if t < -self.far {
            return OUTSIDE;
        }
        match self.kind {
            Kind::Exact { s, inv, c1, c2, k, a, b, sign } => exact(t, s, inv, c1, c2, k, a, b, sign),
            Kind::OneBox { s, inv, w } => {
                let [pp, cp, fp, _] = antiderivatives((t + 0.5 * w) * inv);
                let [pm, cm, fm, _] = antiderivatives((t - 0.5 * w) * inv);
                Edge { m: s / w * (fp - fm), dt: (cp - cm) / w, ds: (pp - pm) / w, dphi: 0.0 }
            }
            Kind::Smooth { var, inv_se, lam, s, d_lam } => edgeworth(t * inv_se, var, inv_se, lam, s, d_lam),
        }
    }
}

/// φ, Φ, F and G at `u`.
#[inline]
fn antiderivatives(u: f64) -> [f64; 4] {
    if u < -FAR {
        return [0.0; 4];
    }
    if u > FAR {
        return [0.0, 1.0, u, 0.5 * (u * u + 1.0)];
    }
    let (c, p) = cdf_pdf(u);
    [p, c, u * c + p, 0.5 * ((u * u + 1.0) * c + u * p)]
}

const INSIDE: Edge = Edge { m: 1.0, dt: 0.0, ds: 0.0, dphi: 0.0 };
const OUTSIDE: Edge = Edge { m: 0.0, dt: 0.0, ds: 0.0, dphi: 0.0 };

#[expect(clippy::too_many_arguments, reason = "the inner loop's terms as scalars, so it inlines")]
#[inline]
fn exact(t: f64, s: f64, inv: f64, c1: f64, c2: f64, k: f64, a: f64, b: f64, sign: f64) -> Edge {
    let p1 = antiderivatives((t + c1) * inv);
    let p2 = antiderivatives((t + c2) * inv);
    let q2 = antiderivatives((t - c2) * inv);
    let q1 = antiderivatives((t - c1) * inv);
    let sum = |i: usize| p1[i] - p2[i] - q2[i] + q1[i];
    let m = s * s * k * sum(3);
    // ∂m/∂s = s·∂²m/∂t² (the heat equation).
    let (dt, ds) = (s * k * sum(2), s * k * sum(1));
    // The box widths move with the normal: ∂a/∂φ = −σ·b, ∂b/∂φ = σ·a, σ = sign(nx·ny).
    let d_c1 = (p1[2] - q1[2]) * inv;
    let d_c2 = (q2[2] - p2[2]) * inv;
    let (d_a, d_b) = (0.5 * (d_c1 + d_c2), 0.5 * (d_c1 - d_c2));
    let turn = m * (b / a - a / b) + s * s * k * (a * d_b - b * d_a);
    Edge { m, dt, ds, dphi: sign * turn }
}

/// Φ(z) − λ·He₃(z)·φ(z) at z = t/σₑ, σₑ² = s² + 1/12, λ = κ₄/(24·σₑ⁴), κ₄ = −(a⁴ + b⁴)/120 the
/// trapezoid's fourth cumulant.
#[inline]
fn edgeworth(z: f64, var: f64, inv_se: f64, lam: f64, s: f64, d_lam: f64) -> Edge {
    let (c, p) = cdf_pdf(z);
    let z2 = z * z;
    let he3 = z * (z2 - 3.0);
    let he4 = z2 * z2 - 6.0 * z2 + 3.0;
    let he5 = z * (z2 * z2 - 10.0 * z2 + 15.0);
    // ∂m/∂(s²) = ½·∂²m/∂t², exactly for this form too.
    let d_var = -0.5 * p * (z + lam * he5) / var;
    Edge { m: c - lam * he3 * p, dt: p * (1.0 + lam * he4) * inv_se, ds: 2.0 * s * d_var, dphi: -d_lam * he3 * p }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The covered fraction of the pixel at depth `t` by brute force: the sharp edge over a
    /// 2000 × 2000 grid of points in the pixel.
    fn brute(t: f64, nx: f64, ny: f64) -> f64 {
        let n = 2000;
        let mut inside = 0usize;
        for j in 0..n {
            for i in 0..n {
                let qx = -0.5 + (i as f64 + 0.5) / n as f64;
                let qy = -0.5 + (j as f64 + 0.5) / n as f64;
                inside += usize::from(t + qx * nx + qy * ny > 0.0);
            }
        }
        inside as f64 / (n * n) as f64
    }

    #[test]
    fn a_sharp_edge_is_the_pixels_exact_coverage() {
        for phi in [0.0, 0.3, std::f64::consts::FRAC_PI_4, 1.2, 2.0, -2.9] {
            let (ny, nx) = f64::sin_cos(phi);
            for t in [-0.8, -0.45, -0.2, 0.0, 0.1, 0.33, 0.6, 0.9] {
                let got = edge(t, nx, ny, S_MIN).m;
                let want = brute(t, nx, ny);
                // The grid's own resolution is 1/2000; S_MIN rounds the ramp's corners by less.
                assert!((got - want).abs() < 2e-3, "φ {phi}, t {t}: {got} vs {want}");
            }
        }
    }

    /// The closed form's constants at any blur.
    fn closed(s: f64) -> Blur {
        Blur { inv: 1.0 / s, smooth: false, ..Blur::new(s) }
    }

    #[test]
    fn the_two_forms_agree_where_they_meet() {
        for phi in [0.0, 0.4, std::f64::consts::FRAC_PI_4] {
            let (ny, nx) = f64::sin_cos(phi);
            for s in [S_SMOOTH, 0.8, 2.0] {
                for t in [-1.5, -0.7, -0.2, 0.0, 0.3, 0.9, 2.0] {
                    let (e, x) = (Blur::new(s).smooth(nx, ny).at(t), closed(s).closed(nx, ny).at(t));
                    let tol = if s == S_SMOOTH { 1e-3 } else { 2e-4 };
                    assert!((e.m - x.m).abs() < tol, "φ {phi} s {s} t {t}: {} vs {}", e.m, x.m);
                    assert!((e.dt - x.dt).abs() < 5.0 * tol, "φ {phi} s {s} t {t}: {} vs {}", e.dt, x.dt);
                }
            }
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let h = 1e-6;
        for s in [S_MIN, 0.05, 0.3, 0.7, 2.0] {
            for phi in [0.2, 0.9, 1.9, -0.6] {
                for t in [-0.6, -0.1, 0.0, 0.25, 0.7] {
                    let (ny, nx) = f64::sin_cos(phi);
                    let e = edge(t, nx, ny, s);
                    let at = |t: f64, phi: f64, s: f64| {
                        let (ny, nx) = f64::sin_cos(phi);
                        edge(t, nx, ny, s).m
                    };
                    let dt = (at(t + h, phi, s) - at(t - h, phi, s)) / (2.0 * h);
                    let ds = (at(t, phi, s + h) - at(t, phi, s - h)) / (2.0 * h);
                    let dphi = (at(t, phi + h, s) - at(t, phi - h, s)) / (2.0 * h);
                    // Φ is a 1e-7 approximation whose slope differs from φ by up to 1e-3 (see
                    // `special`), and by more per px where the blur is small.
                    let ok = |a: f64, b: f64| (a - b).abs() < 2e-3 * (1.0 + a.abs()) + 2e-5 / s;
                    assert!(ok(dt, e.dt), "s {s} φ {phi} t {t}: dt {dt} vs {}", e.dt);
                    assert!(ok(ds, e.ds), "s {s} φ {phi} t {t}: ds {ds} vs {}", e.ds);
                    assert!(ok(dphi, e.dphi), "s {s} φ {phi} t {t}: dφ {dphi} vs {}", e.dphi);
                }
            }
        }
    }
}
