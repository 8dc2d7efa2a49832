//! The blurred-shape models: a disc, a ring and a cross, each with its gradient.

// Index loops read like the matrix algebra they implement.

use crate::edge::{Blur, Edge, Profile, S_MIN};

/// A blurred shape: geometric parameters `g`, always `g[0]` = cx, `g[1]` = cy (px), and last
/// the blur σ `s` (px).
pub(crate) trait Model {
    /// Number of geometric parameters.
    const G: usize;
    /// What `eval` needs of `g` and `sup` that does not change from pixel to pixel.
    type Pre;
    /// `Pre`, worked out once per pass.
    fn prepare(&self, g: &[f64], sup: &[f64]) -> Self::Pre;
    /// M at (x, y) px and its gradient with respect to `g` written into `grad`; `None` outside
    /// the pixels fitted on, which are chosen by the geometry `sup` (held fixed over several
    /// steps: a pixel set that followed every step made the fit flip between two states).
    /// `pre` is `prepare(g, sup)`.
    fn eval(&self, pre: &Self::Pre, g: &[f64], sup: &[f64], x: f64, y: f64, grad: &mut [f64]) -> Option<f64>;
    /// Radius (px) around the centre holding every fitted pixel.
    fn reach(&self, g: &[f64]) -> f64;
    /// Radius (px) around the centre holding the mark itself and its blurred edge: the mark is
    /// clipped when this leaves the image.
    fn extent(&self, g: &[f64]) -> f64;
    /// The x-offsets from the centre (px) of the fitted pixels in the row `dy` px below the
    /// centre, as up to two intervals (an empty one has lo > hi): rows of an annulus skip
    /// its hole instead of testing every pixel of the bounding box.
    fn span(&self, g: &[f64], _dy: f64) -> [(f64, f64); 2] {
        let r = self.reach(g);
        [(-r, r), (1.0, 0.0)]
    }
    /// Keeps a step sane (positive sizes, bounded moves); false when the fit has run away.
    fn constrain(&self, g: &mut [f64], before: &[f64]) -> bool;
}

/// The σ (px) of an edge with blur `s` px seen through the pixel's square (variance 1/12).
/// The fit steps in it rather than in s: the model is smooth in σₑ down to a sharp edge (where
/// its slope in s vanishes) and close to linear in it above.
pub(super) fn edge_width(s: f64) -> f64 {
    (s * s + 1.0 / 12.0).sqrt()
}

/// The blur s (px, at least [`S_MIN`]) of an edge of width `width` px.
pub(super) fn blur_of(width: f64) -> f64 {
    (width * width - 1.0 / 12.0).max(S_MIN * S_MIN).sqrt()
}

/// Width (px) of the band on each side of an edge that is fitted, for blur `s` px.
pub(crate) fn band(s: f64) -> f64 {
    2.5 * edge_width(s) + 2.0
}

/// The outward unit normal at offset (dx, dy) from a centre, ρ its length, and 1/ρ (0 at the
/// centre itself, where any normal will do).
#[inline]
fn radial(dx: f64, dy: f64, rho: f64) -> (f64, f64, f64) {
    if rho > 1e-9 {
        let ir = 1.0 / rho;
        (dx * ir, dy * ir, ir)
    } else {
        (1.0, 0.0, 0.0)
    }
}

/// Filled disc: g = [cx, cy, R, s].
pub(crate) struct Disc;

impl Model for Disc {
    const G: usize = 4;
    /// The band's width (px) and the blur.
    type Pre = (f64, Blur);
    fn prepare(&self, g: &[f64], sup: &[f64]) -> (f64, Blur) {
        (band(sup[3]), Blur::new(g[3]))
    }
    #[inline(always)]
    fn eval(&self, pre: &(f64, Blur), g: &[f64], sup: &[f64], x: f64, y: f64, grad: &mut [f64]) -> Option<f64> {
        // sqrt of the squares, not hypot: this runs per pixel and libm's hypot is slow.
        let (ex, ey) = (x - sup[0], y - sup[1]);
        if ((ex * ex + ey * ey).sqrt() - sup[2]).abs() > pre.0 {
            return None;
        }
        let (dx, dy) = (x - g[0], y - g[1]);
        let rho = (dx * dx + dy * dy).sqrt();
        let (ux, uy, ir) = radial(dx, dy, rho);
        // The normal turns by 1/ρ rad per px the centre moves across it.
        let e = pre.1.profile(ux, uy).at(g[2] - rho);
        grad[0] = e.dt * ux + e.dphi * uy * ir;
        grad[1] = e.dt * uy - e.dphi * ux * ir;
        grad[2] = e.dt;
        grad[3] = e.ds;
        Some(e.m)
    }
    fn reach(&self, g: &[f64]) -> f64 {
        g[2] + band(g[3])
    }
    fn extent(&self, g: &[f64]) -> f64 {
        g[2] + 2.0 * edge_width(g[3]).min(3.0) + 0.5
    }
    fn span(&self, g: &[f64], dy: f64) -> [(f64, f64); 2] {
        let b = band(g[3]);
        annulus_span(g[2] - b, g[2] + b, dy)
    }
    fn constrain(&self, g: &mut [f64], before: &[f64]) -> bool {
        limit_move(g, before, 0.25 * before[2]);
        g[2] = g[2].clamp(0.7 * before[2], 1.4 * before[2]);
        g[3] = g[3].min(0.5 * g[2]).max(S_MIN);
        g[2] > 1.0
    }
}

/// Ring: g = [cx, cy, Ro, Ri, s].
pub(crate) struct Annulus;

impl Model for Annulus {
    const G: usize = 5;
    /// The band's width (px) and the blur.
    type Pre = (f64, Blur);
    fn prepare(&self, g: &[f64], sup: &[f64]) -> (f64, Blur) {
        (band(sup[4]), Blur::new(g[4]))
    }
    #[inline(always)]
    fn eval(&self, pre: &(f64, Blur), g: &[f64], sup: &[f64], x: f64, y: f64, grad: &mut [f64]) -> Option<f64> {
        let (ex, ey) = (x - sup[0], y - sup[1]);
        let rs = (ex * ex + ey * ey).sqrt();
        if rs > sup[2] + pre.0 || rs < sup[3] - pre.0 {
            return None;
        }
        let (dx, dy) = (x - g[0], y - g[1]);
        let rho = (dx * dx + dy * dy).sqrt();
        let (ux, uy, ir) = radial(dx, dy, rho);
        let profile = pre.1.profile(ux, uy);
        let (o, i) = (profile.at(g[2] - rho), profile.at(g[3] - rho));
        let (dt, dphi) = (o.dt - i.dt, o.dphi - i.dphi);
        grad[0] = dt * ux + dphi * uy * ir;
        grad[1] = dt * uy - dphi * ux * ir;
        grad[2] = o.dt;
        grad[3] = -i.dt;
        grad[4] = o.ds - i.ds;
        Some(o.m - i.m)
    }
    fn reach(&self, g: &[f64]) -> f64 {
        g[2] + band(g[4])
    }
    fn extent(&self, g: &[f64]) -> f64 {
        g[2] + 2.0 * edge_width(g[4]).min(3.0) + 0.5
    }
    fn span(&self, g: &[f64], dy: f64) -> [(f64, f64); 2] {
        let b = band(g[4]);
        annulus_span(g[3] - b, g[2] + b, dy)
    }
    fn constrain(&self, g: &mut [f64], before: &[f64]) -> bool {
        limit_move(g, before, 0.25 * before[2]);
        g[2] = g[2].clamp(0.7 * before[2], 1.4 * before[2]);
        // The line may thin by at most half per step: a ring must not collapse into a circle.
        let lw = (before[2] - before[3]).max(0.5);
        g[3] = g[3].clamp(before[3] - 0.5 * lw, before[3] + 0.5 * lw).clamp(0.0, g[2] - 0.5 * lw);
        g[4] = g[4].min(0.5 * g[2]).min(0.75 * (g[2] - g[3]) + 1.0).max(S_MIN);
        g[2] > 1.0
    }
}

/// Cross: g = [cx, cy, θ, a, w, s] — bar half-length a, half-width w (px), first bar at θ rad.
pub(crate) struct Cross;

/// A blurred 1-D box |t| ≤ h seen through the pixel (the edges' `profile`): value and
/// derivatives by t, h, s and the edges' direction.
#[inline(always)]
fn box1(t: f64, h: f64, profile: &Profile) -> [f64; 5] {
    let (p, q): (Edge, Edge) = (profile.at(h - t), profile.at(h + t));
    [p.m + q.m - 1.0, q.dt - p.dt, p.dt + q.dt, p.ds + q.ds, p.dphi + q.dphi]
}

/// What a cross's `eval` needs per pass.
pub(crate) struct CrossPre {
    /// sin θ, cos θ of the geometry; of the support.
    sin_cos: (f64, f64),
    sup_sin_cos: (f64, f64),
    /// The band's width, px.
    band: f64,
    /// All four edges' profile: they run at θ or θ + 90°, one trapezoid for all.
    profile: Profile,
}

impl Model for Cross {
    const G: usize = 6;
    type Pre = CrossPre;
    fn prepare(&self, g: &[f64], sup: &[f64]) -> CrossPre {
        let (sn, c) = g[2].sin_cos();
        CrossPre {
            sin_cos: (sn, c),
            sup_sin_cos: sup[2].sin_cos(),
            band: band(sup[5]),
            profile: Blur::new(g[5]).profile(c, sn),
        }
    }
    #[inline]
    fn eval(&self, pre: &CrossPre, g: &[f64], sup: &[f64], x: f64, y: f64, grad: &mut [f64]) -> Option<f64> {
        let ((sn, c), (ss, sc), b) = (pre.sin_cos, pre.sup_sin_cos, pre.band);
        {
            let (ex, ey) = (x - sup[0], y - sup[1]);
            let (au, av) = ((ex * sc + ey * ss).abs(), (-ex * ss + ey * sc).abs());
            let in_bar1 = au <= sup[3] + b && av <= sup[4] + b;
            let in_bar2 = av <= sup[3] + b && au <= sup[4] + b;
            if !(in_bar1 || in_bar2) {
                return None;
            }
        }
        let (dx, dy) = (x - g[0], y - g[1]);
        let u = dx * c + dy * sn;
        let v = -dx * sn + dy * c;
        let (a, w) = (g[3], g[4]);
        let p = &pre.profile;
        let [ua, ua_t, ua_h, ua_s, ua_p] = box1(u, a, p);
        let [uw, uw_t, uw_h, uw_s, uw_p] = box1(u, w, p);
        let [va, va_t, va_h, va_s, va_p] = box1(v, a, p);
        let [vw, vw_t, vw_h, vw_s, vw_p] = box1(v, w, p);
        let m = ua * vw + uw * va - uw * vw;
        let m_u = ua_t * vw + uw_t * va - uw_t * vw;
        let m_v = ua * vw_t + uw * va_t - uw * vw_t;
        let m_p = ua_p * vw + ua * vw_p + uw_p * va + uw * va_p - uw_p * vw - uw * vw_p;
        grad[0] = -m_u * c + m_v * sn;
        grad[1] = -m_u * sn - m_v * c;
        grad[2] = m_u * v - m_v * u + m_p;
        grad[3] = ua_h * vw + uw * va_h;
        grad[4] = ua * vw_h + uw_h * va - uw_h * vw - uw * vw_h;
        grad[5] = ua_s * vw + ua * vw_s + uw_s * va + uw * va_s - uw_s * vw - uw * vw_s;
        Some(m)
    }
    fn reach(&self, g: &[f64]) -> f64 {
        let b = band(g[5]);
        (g[3] + b).hypot(g[4] + b)
    }
    fn extent(&self, g: &[f64]) -> f64 {
        g[3].hypot(g[4]) + 2.0 * edge_width(g[5]).min(3.0) + 0.5
    }
    fn constrain(&self, g: &mut [f64], before: &[f64]) -> bool {
        limit_move(g, before, 0.25 * before[3]);
        g[2] = g[2].clamp(before[2] - 0.2, before[2] + 0.2);
        g[3] = g[3].clamp(0.7 * before[3], 1.4 * before[3]);
        g[4] = g[4].clamp(0.5 * before[4], 2.0 * before[4]).clamp(0.3, 0.6 * g[3]);
        g[5] = g[5].min(g[3]).max(S_MIN);
        g[3] > 1.0
    }
}

/// The x-offsets of an annulus ri ≤ ρ ≤ ro in the row `dy`.
fn annulus_span(ri: f64, ro: f64, dy: f64) -> [(f64, f64); 2] {
    let dy2 = dy * dy;
    if dy2 > ro * ro {
        return [(1.0, 0.0), (1.0, 0.0)];
    }
    let outer = (ro * ro - dy2).sqrt();
    if ri <= 0.0 || dy2 >= ri * ri {
        return [(-outer, outer), (1.0, 0.0)];
    }
    let inner = (ri * ri - dy2).sqrt();
    [(-outer, -inner), (inner, outer)]
}

fn limit_move(g: &mut [f64], before: &[f64], max: f64) {
    let (mx, my) = (g[0] - before[0], g[1] - before[1]);
    let d = mx.hypot(my);
    if d > max {
        g[0] = before[0] + mx * max / d;
        g[1] = before[1] + my * max / d;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn model_gradients_match_finite_differences() {
        type Eval<'a> = &'a dyn Fn(&[f64], &mut [f64]) -> Option<f64>;
        let check = |model: Eval<'_>, g: &[f64]| {
            let mut grad = vec![0.0; g.len()];
            let m0 = model(g, &mut grad).expect("inside the band");
            assert!((0.0..=1.0).contains(&m0));
            for k in 0..g.len() {
                let h = 1e-6;
                let mut gp = g.to_vec();
                gp[k] += h;
                let mut gm = g.to_vec();
                gm[k] -= h;
                let mut scratch = vec![0.0; g.len()];
                let d = (model(&gp, &mut scratch).unwrap() - model(&gm, &mut scratch).unwrap()) / (2.0 * h);
                assert!((d - grad[k]).abs() < 1e-4 * (1.0 + d.abs()), "param {k}: {d} vs {}", grad[k]);
            }
        };
        let (x, y) = (13.2, 9.1);
        // The support stays put (as within a pass); the models' own geometry moves.
        #[expect(clippy::items_after_statements, reason = "the helper sits beside its one use")]
        fn at<'a, M: Model>(
            model: &'a M,
            sup: &[f64],
            x: f64,
            y: f64,
        ) -> impl Fn(&[f64], &mut [f64]) -> Option<f64> + 'a {
            let sup = sup.to_vec();
            move |g, gr| model.eval(&model.prepare(g, &sup), g, &sup, x, y, gr)
        }
        // Blurred (the Edgeworth form), slightly blurred and sharp (the closed form).
        for s in [1.3, 0.3, S_MIN] {
            let disc = [3.0, 2.0, 13.0, s];
            check(&at(&Disc, &disc, x, y), &disc);
            check(&at(&Disc, &disc, 14.6, 7.0), &[3.0, 2.0, 15.0, s]);
            let ring = [3.0, 2.0, 15.0, 12.0, s];
            check(&at(&Annulus, &ring, x, y), &ring);
            let cross = [3.0, 2.5, 0.3, 14.0, 3.0, s];
            check(&at(&Cross, &cross, x, y), &cross);
            check(&at(&Cross, &cross, 4.0, 1.7), &cross);
            check(&at(&Cross, &cross, 5.3, 0.2), &cross);
        }
    }
}
