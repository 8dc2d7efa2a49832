//! Sub-pixel refinement: a least-squares fit of a blurred-shape model to the pixels near the
//! mark's edges, by damped Gauss–Newton.
//!
//! Model of a pixel at (x, y): `I = P(x, y) + Q(x, y) · M(x, y; g)` where P (background) and Q
//! (contrast) are planes — uneven light, whether it adds or multiplies — and M ∈ [0, 1] is the
//! fraction of the pixel's square covered by the shape blurred by a Gaussian of σ = `s` px
//! (defocus). Each edge is taken as locally straight: M is the [`edge`] profile of the pixel at
//! its depth inside the edge (the Gaussian and the pixel's square, exactly). For a disc,
//! M = edge(R − ρ); for a ring the difference of two such; for a cross the sum of two blurred
//! bars less their overlap, each bar a product of two edge-pair profiles along its axes (exact
//! but at the corners). Least squares on this model is the maximum-likelihood estimate under
//! Gaussian noise, so the centre's spread sits near the Cramér–Rao bound.
//!
//! The blur enters the normal equations as the edge width √(s² + 1/12) (see `edge_width`), s
//! kept at least [`S_MIN`].

// Index loops read like the matrix algebra they implement.
#![allow(clippy::needless_range_loop)]

use crate::edge::{Blur, Edge, Profile, S_MIN};

/// Most parameters: 6 geometric + 6 linear.
pub(crate) const MAXP: usize = 12;

/// Pixel access, generic over the sample type so the inner loops have no branch on depth.
pub(crate) struct Img<'a, T> {
    pub(crate) w: usize,
    pub(crate) h: usize,
    pub(crate) data: &'a [T],
}

impl<T: Copy + Into<f64>> Img<'_, T> {
    #[inline]
    fn at(&self, x: usize, y: usize) -> f64 {
        self.data[y * self.w + x].into()
    }
}

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
fn edge_width(s: f64) -> f64 {
    (s * s + 1.0 / 12.0).sqrt()
}

/// The blur s (px, at least [`S_MIN`]) of an edge of width `width` px.
fn blur_of(width: f64) -> f64 {
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

/// The outcome of a fit.
#[derive(Clone, Debug)]
pub(crate) struct FitResult {
    /// Geometric parameters (model's layout).
    pub(crate) g: [f64; 6],
    /// Background plane [b0, bx, by] and contrast plane [a0, ax, ay] at the reference point,
    /// grey levels (per reference length for the slopes).
    pub(crate) lin: [f64; 6],
    /// Coefficient of determination over the fitted pixels, 0 … 1.
    pub(crate) r2: f64,
    /// Smallest coefficient of determination over 8 angular sectors.
    pub(crate) min_sector_r2: f64,
    /// Whether the last step was below the convergence threshold.
    pub(crate) converged: bool,
}

/// Why a fit produced nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum FitFailure {
    /// The pixels the model needs run past the image border.
    Clipped,
    /// Singular system, runaway parameters or too few pixels.
    Diverged,
}

const MAX_ITER: usize = 15;

/// An accepted estimate of a stage's fit: geometry, planes, the geometry that chose the fitted
/// pixels, and the sums there.
type Accepted = ([f64; 6], [f64; 6], [f64; 6], Acc);

/// Fits `model` starting from geometry `g0`; `scale` px normalises the plane slopes.
pub(crate) fn fit<M: Model, T: Copy + Into<f64>, const N: usize>(
    img: &Img<'_, T>,
    model: &M,
    g0: &[f64],
    scale: f64,
) -> Result<FitResult, FitFailure> {
    let ng = M::G;
    let n = ng + 6;
    debug_assert_eq!(N, n, "N is the model's parameter count");
    let mut g = [0.0; 6];
    g[..ng].copy_from_slice(&g0[..ng]);
    let (xr, yr) = (g0[0], g0[1]);
    let inv = 1.0 / scale;
    let mut lin = [0.0; 6];
    // Coarse to fine: while the edge is wide, every 4th (2nd) pixel each way carries the same
    // information at 1/16 (1/4) of the cost, with the blur held above what that spacing
    // resolves; the last stage uses every pixel and frees the blur. The first stage is the
    // coarsest whose spacing the starting blur reaches.
    const STAGES: [(usize, f64, f64, usize); 3] = [(4, 3.0, 0.05, 4), (2, 1.5, 0.02, 3), (1, 0.0, 5e-4, MAX_ITER)];
    let first = STAGES.iter().position(|&(st, ..)| g0[ng - 1] >= st as f64).unwrap_or(2);
    let mut iter = 0;
    let si = ng - 1;
    // Whether the last step held a coarse stage's blur above what the image asked for.
    let mut pinned = false;
    for (stage, &(stride, s_floor, tol, max_iter)) in STAGES.iter().enumerate().skip(first) {
        let last = stage == STAGES.len() - 1;
        // An image sharper than the last stage allowed: start this one halfway down.
        if pinned {
            g[si] *= 0.5;
        }
        g[si] = g[si].max(s_floor);
        let mut sup = g;
        // Arrivals of the blur at its bound in this stage (see the step below).
        let (mut floor_visits, mut was_at_floor) = (0usize, false);
        // In the coarse stages, Levenberg–Marquardt damping, and the last accepted estimate with
        // its sums: a step that raised the sum of squared residuals is rolled back and retried
        // damped harder (λ ×10), an accepted one lowers λ (÷10, to 0 below 10⁻³). Across
        // re-chosen pixels the sums do not compare: there a step is rolled back when it doubled
        // the mean square. Undamped Gauss–Newton swung a sharp ring's radii and blur back and
        // forth with growing amplitude over the stages until it diverged. Not in the last stage:
        // there a sharp cross along the pixel axes, its blur at the bound (see below), raises the
        // cost on the way to the minimum, and rolling back left it stuck 0.08 px off.
        let mut lambda: f64 = 0.0;
        let mut prev: Option<Accepted> = None;
        for _ in 0..max_iter {
            // Re-choose the fitted pixels only when the estimate has really moved.
            let drift = (0..si).map(|k| (g[k] - sup[k]).abs()).fold(0.0, f64::max);
            if drift > 0.1 || (edge_width(g[si]) - edge_width(sup[si])).abs() > 0.2 * edge_width(sup[si]) {
                sup = g;
            }
            // The last stage also scores the fit (R² overall and by sector): at convergence the
            // residuals before the final, tiny step are the answer's.
            let mut acc = accumulate::<M, T, N>(img, model, &g, &sup, &lin, xr, yr, inv, stride, last)?;
            // The sums at the new estimate are its cost: no extra pass for an accepted step.
            let worse = |(_, _, psup, pacc): &Accepted| {
                if *psup == sup {
                    acc.sse > pacc.sse
                } else {
                    acc.sse * pacc.count as f64 > 2.0 * pacc.sse * acc.count as f64
                }
            };
            match prev.take() {
                Some(p) if !last && worse(&p) => {
                    (g, lin, sup, acc) = p;
                    lambda = (10.0 * lambda).max(1e-3);
                }
                _ => lambda = if lambda > 1e-3 { 0.1 * lambda } else { 0.0 },
            }
            if !last {
                prev = Some((g, lin, sup, acc.clone()));
            }
            // First step: only the planes (the geometry guess is coarse, the planes unknown);
            // second: the geometry at the starting blur (a blur freed from a coarse guess grows
            // to cover the misfit, and the next step overshoots).
            let free: Vec<usize> = match iter {
                0 => (ng..n).collect(),
                1 => (0..n).filter(|&k| k != si).collect(),
                _ => (0..n).collect(),
            };
            // Below a pixel the model is not smooth in the blur: a sharp edge along a pixel axis
            // is the pixel's ramp, whose corners round off in proportion to s, so the blur's
            // column is near zero but for spikes at the corners. On a sharp image whose edges
            // run along the axes (a cross at 0°) the system is then singular at the bound (as
            // sharp as can be), or the freed blur jumps off the bound and back on, round and
            // round, without converging. So the blur is held when the system with it is
            // singular, and once it has come back to the bound.
            let at_floor = free.contains(&si) && g[si] <= S_MIN;
            floor_visits += usize::from(at_floor && !was_at_floor);
            was_at_floor = at_floor;
            let full = if at_floor && floor_visits > 1 { None } else { solve_damped(&acc.h, &acc.b, &free, lambda) };
            let mut step = match full {
                Some(step) => step,
                None if free.contains(&si) => {
                    let rest: Vec<usize> = free.iter().copied().filter(|&k| k != si).collect();
                    solve_damped(&acc.h, &acc.b, &rest, lambda).ok_or(FitFailure::Diverged)?
                }
                None => return Err(FitFailure::Diverged),
            };
            // The step is in the edge width σₑ = √(s² + 1/12) (see `edge_width`). It moves at most
            // ×4 down, not below the stage's floor, or ×2 up; when it hits a bound it is held
            // there and the others solved for given it, so the step stays consistent (clamping
            // it alone made the centre overshoot and oscillate).
            let width = edge_width(g[si]);
            let (w_lo, w_hi) = (edge_width(s_floor.max(S_MIN)).max(0.25 * width), 2.0 * width);
            let w_new = width + step[si];
            if iter > 1 && !(w_lo..=w_hi).contains(&w_new) {
                let dw = w_new.clamp(w_lo, w_hi) - width;
                let mut b = acc.b;
                for (k, bk) in b.iter_mut().enumerate().take(n) {
                    *bk -= acc.h[k][si] * dw;
                }
                let rest: Vec<usize> = free.iter().copied().filter(|&k| k != si).collect();
                step = solve_damped(&acc.h, &b, &rest, lambda).ok_or(FitFailure::Diverged)?;
                step[si] = dw;
            }
            // A model held blurrier than the image (in a coarse stage) sees an edge's shift spread
            // over its own width and overshoots it by up to √2: the geometry steps by 1/√2.
            pinned = s_floor > 0.0 && iter > 1 && w_new < w_lo;
            let gain = if pinned { std::f64::consts::FRAC_1_SQRT_2 } else { 1.0 };
            let before = g;
            for k in 0..si {
                g[k] += gain * step[k];
            }
            g[si] = blur_of((width + step[si]).max(w_lo));
            for k in 0..6 {
                lin[k] += step[ng + k];
            }
            if !model.constrain(&mut g[..ng], &before[..ng]) || g.iter().chain(&lin).any(|v| !v.is_finite()) {
                return Err(FitFailure::Diverged);
            }
            g[si] = g[si].max(s_floor);
            let moved = (g[0] - before[0]).hypot(g[1] - before[1]);
            let sized = (2..si)
                .map(|k| (g[k] - before[k]).abs())
                .fold((edge_width(g[si]) - edge_width(before[si])).abs(), f64::max);
            iter += 1;
            if iter > 1 && moved < tol && sized < 100.0 * tol.max(1e-5) {
                if last {
                    let e = model.extent(&g[..ng]);
                    let (xmax, ymax) = ((img.w - 1) as f64, (img.h - 1) as f64);
                    if !(g[0] - e >= 0.0 && g[1] - e >= 0.0 && g[0] + e <= xmax && g[1] + e <= ymax) {
                        return Err(FitFailure::Clipped);
                    }
                    let (r2, min_sector_r2) = acc.r2();
                    return Ok(FitResult { g, lin, r2, min_sector_r2, converged: true });
                }
                break;
            }
        }
    }
    Err(FitFailure::Diverged)
}

#[derive(Clone)]
struct Acc {
    h: [[f64; MAXP]; MAXP],
    b: [f64; MAXP],
    count: usize,
    /// Σ residual² over the fitted pixels.
    sse: f64,
    /// Per sector: count, Σ I, Σ I², Σ residual².
    sectors: [[f64; 4]; 8],
}

impl Acc {
    fn r2(&self) -> (f64, f64) {
        let mut tot = [0.0; 4];
        let mut min_r2: f64 = 1.0;
        for s in &self.sectors {
            for k in 0..4 {
                tot[k] += s[k];
            }
            min_r2 = min_r2.min(r2_of(s));
        }
        (r2_of(&tot), min_r2)
    }
}

fn r2_of(s: &[f64; 4]) -> f64 {
    if s[0] < 2.0 {
        return 0.0;
    }
    let sst = s[2] - s[1] * s[1] / s[0];
    if sst <= 0.0 {
        return 0.0;
    }
    (1.0 - s[3] / sst).clamp(0.0, 1.0)
}

/// The columns of the Jacobian row without v: [q·∂M/∂g, 1, u, M, M·u]. The v columns (v,
/// M·v) are v times the 1 and M ones: full column `k` is column `SRC.0` times v^`SRC.1`.
fn source(k: usize, ng: usize) -> (usize, usize) {
    match k.checked_sub(ng) {
        None | Some(0) | Some(1) => (k, 0),
        Some(2) => (ng, 1),
        Some(3) => (ng + 2, 0),
        Some(4) => (ng + 3, 0),
        _ => (ng + 2, 1),
    }
}

/// The normal equations (and with `sectors` the R² sums) over the fitted pixels.
#[allow(clippy::too_many_arguments)]
fn accumulate<M: Model, T: Copy + Into<f64>, const N: usize>(
    img: &Img<'_, T>,
    model: &M,
    g: &[f64; 6],
    sup: &[f64; 6],
    lin: &[f64; 6],
    xr: f64,
    yr: f64,
    inv: f64,
    stride: usize,
    sectors: bool,
) -> Result<Acc, FitFailure> {
    let ng = M::G;
    // Within a row v is constant, so the row's sums need only the N − 2 columns without v; the
    // v columns are folded in at the row's end (a third fewer products per pixel).
    let nr = N - 2;
    let reach = model.reach(&sup[..ng]);
    let (xmax, ymax) = ((img.w - 1) as f64, (img.h - 1) as f64);
    // The band may run off the image: the model needs no particular pixels (whether the mark
    // itself is cut is judged on the final estimate).
    let (x0, x1) = ((sup[0] - reach).max(0.0), (sup[0] + reach).min(xmax));
    let (y0, y1) = ((sup[1] - reach).max(0.0), (sup[1] + reach).min(ymax));
    let mut acc = Acc { h: [[0.0; MAXP]; MAXP], b: [0.0; MAXP], count: 0, sse: 0.0, sectors: [[0.0; 4]; 8] };
    let mut j = [0.0; MAXP];
    let (mut hr, mut br) = ([[0.0; MAXP]; MAXP], [0.0; MAXP]);
    let mut grad = [0.0; 6];
    let pre = model.prepare(&g[..ng], &sup[..ng]);
    // The blur's column is by the edge width: ∂/∂σₑ = ∂/∂s · σₑ/s.
    let to_width = edge_width(g[ng - 1]) / g[ng - 1];
    let (sa, ca) = if ng == 6 { g[2].sin_cos() } else { (0.0, 1.0) };
    // A grid fixed in the image (not following the estimate), so the sampled pixels do not
    // change under the fit from one iteration to the next.
    let on_grid = |v: f64| (v.ceil() as usize).div_ceil(stride) * stride;
    for yi in (on_grid(y0)..=y1.floor() as usize).step_by(stride) {
        let y = yi as f64;
        let v = (y - yr) * inv;
        let before = acc.count;
        for (lo, hi) in model.span(&sup[..ng], y - sup[1]) {
            if lo > hi {
                continue;
            }
            let (xa, xb) = ((sup[0] + lo).max(x0), (sup[0] + hi).min(x1));
            if xa > xb {
                continue;
            }
            for xi in (on_grid(xa)..=xb.floor() as usize).step_by(stride) {
                let x = xi as f64;
                let Some(m) = model.eval(&pre, &g[..ng], &sup[..ng], x, y, &mut grad) else { continue };
                grad[ng - 1] *= to_width;
                let u = (x - xr) * inv;
                let q = lin[3] + lin[4] * u + lin[5] * v;
                let pred = lin[0] + lin[1] * u + lin[2] * v + q * m;
                let val = img.at(xi, yi);
                let r = val - pred;
                for k in 0..ng {
                    j[k] = q * grad[k];
                }
                j[ng..ng + 4].copy_from_slice(&[1.0, u, m, m * u]);
                // N is a constant here: the loops unroll without bounds checks.
                for a in 0..nr {
                    let ja = j[a];
                    br[a] += ja * r;
                    let row = &mut hr[a];
                    for c in a..nr {
                        row[c] += ja * j[c];
                    }
                }
                acc.count += 1;
                acc.sse += r * r;
                if !sectors {
                    continue;
                }
                // Sectors in the mark's own frame (for a cross: rotated with it).
                let (dx, dy) = (x - g[0], y - g[1]);
                let (rx, ry) = (dx * ca + dy * sa, -dx * sa + dy * ca);
                let s = &mut acc.sectors[sector_of(rx, ry)];
                s[0] += 1.0;
                s[1] += val;
                s[2] += val * val;
                s[3] += r * r;
            }
        }
        if acc.count == before {
            continue;
        }
        let pow = [1.0, v, v * v];
        for a in 0..N {
            let (sa, pa) = source(a, ng);
            acc.b[a] += pow[pa] * br[sa];
            for c in a..N {
                let (sc, pc) = source(c, ng);
                acc.h[a][c] += pow[pa + pc] * hr[sa.min(sc)][sa.max(sc)];
            }
        }
        for a in 0..nr {
            br[a] = 0.0;
            hr[a][..nr].fill(0.0);
        }
    }
    if acc.count < 4 * N {
        return Err(FitFailure::Diverged);
    }
    for a in 0..N {
        for c in 0..a {
            acc.h[a][c] = acc.h[c][a];
        }
    }
    Ok(acc)
}

/// One of 8 angular sectors, without trigonometry.
#[inline]
fn sector_of(x: f64, y: f64) -> usize {
    let q = match (x >= 0.0, y >= 0.0) {
        (true, true) => 0,
        (false, true) => 2,
        (false, false) => 4,
        (true, false) => 6,
    };
    let half = if (x.abs() >= y.abs()) == (q == 0 || q == 4) { 0 } else { 1 };
    q + half
}

/// Solves H δ = b over the parameters `idx` by Cholesky (a hair of damping, 10⁻⁶·diag H); the
/// rest stay 0.
pub(crate) fn solve(h: &[[f64; MAXP]; MAXP], b: &[f64; MAXP], idx: &[usize]) -> Option<[f64; MAXP]> {
    solve_damped(h, b, idx, 0.0)
}

/// Solves (H + (λ + 10⁻⁶)·diag H) δ = b over the parameters `idx` by Cholesky; the rest stay 0.
fn solve_damped(h: &[[f64; MAXP]; MAXP], b: &[f64; MAXP], idx: &[usize], lambda: f64) -> Option<[f64; MAXP]> {
    let m = idx.len();
    let mut l = [[0.0; MAXP]; MAXP];
    for i in 0..m {
        for jj in 0..=i {
            let mut sum = h[idx[i]][idx[jj]];
            if i == jj {
                sum *= 1.0 + 1e-6 + lambda;
            }
            for k in 0..jj {
                sum -= l[i][k] * l[jj][k];
            }
            if i == jj {
                if !(sum > 0.0) {
                    return None;
                }
                l[i][i] = sum.sqrt();
            } else {
                l[i][jj] = sum / l[jj][jj];
            }
        }
    }
    let mut z = [0.0; MAXP];
    for i in 0..m {
        let mut sum = b[idx[i]];
        for k in 0..i {
            sum -= l[i][k] * z[k];
        }
        z[i] = sum / l[i][i];
    }
    let mut x = [0.0; MAXP];
    for i in (0..m).rev() {
        let mut sum = z[i];
        for k in i + 1..m {
            sum -= l[k][i] * x[k];
        }
        x[i] = sum / l[i][i];
    }
    let mut out = [0.0; MAXP];
    for (i, &k) in idx.iter().enumerate() {
        out[k] = x[i];
    }
    Some(out)
}

/// Fisher information of the model at (`g`, `lin`) over the pixels it fits on, for noise of
/// `sigma` grey levels: the Cramér–Rao bound (px) on cx and cy, all other parameters unknown
/// (the blur s at least [`S_MIN`]).
pub(crate) fn crb<M: Model>(model: &M, g: &[f64], lin: &[f64; 6], scale: f64, sigma: f64) -> Option<(f64, f64)> {
    let ng = M::G;
    let n = ng + 6;
    let reach = model.reach(g).ceil() as i64 + 1;
    let mut h = [[0.0; MAXP]; MAXP];
    let mut grad = [0.0; 6];
    let mut j = [0.0; MAXP];
    let (cx, cy) = (g[0].round() as i64, g[1].round() as i64);
    let pre = model.prepare(g, g);
    for yi in cy - reach..=cy + reach {
        for xi in cx - reach..=cx + reach {
            let (x, y) = (xi as f64, yi as f64);
            let Some(m) = model.eval(&pre, g, g, x, y, &mut grad) else { continue };
            // As in the fit, the blur by the edge width: the same bound on the centre for any
            // s > 0, and a regular matrix as s → 0 (where ∂M/∂s vanishes).
            grad[ng - 1] *= edge_width(g[ng - 1]) / g[ng - 1];
            let (u, v) = ((x - g[0]) / scale, (y - g[1]) / scale);
            let q = lin[3] + lin[4] * u + lin[5] * v;
            for k in 0..ng {
                j[k] = q * grad[k];
            }
            j[ng..n].copy_from_slice(&[1.0, u, v, m, m * u, m * v]);
            for a in 0..n {
                for bb in 0..n {
                    h[a][bb] += j[a] * j[bb] / (sigma * sigma);
                }
            }
        }
    }
    // Invert via solving for the unit vectors e0, e1.
    let mut out = [0.0; 2];
    for (axis, o) in out.iter_mut().enumerate() {
        let mut e = [0.0; MAXP];
        e[axis] = 1.0;
        let x = solve(&h, &e, &(0..n).collect::<Vec<_>>())?;
        *o = x[axis].sqrt();
    }
    Some((out[0], out[1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sectors_split_the_plane_in_eight() {
        let mut seen = [0; 8];
        for k in 0..64 {
            let a = (k as f64 + 0.5) * std::f64::consts::TAU / 64.0;
            let s = sector_of(a.cos(), a.sin());
            assert_eq!(s, (k * 8) / 64, "angle {a}");
            seen[s] += 1;
        }
        assert!(seen.iter().all(|&c| c == 8));
    }

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
