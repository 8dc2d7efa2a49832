//! Sub-pixel refinement: a least-squares fit of a blurred-shape model to the pixels near the
//! mark's edges, by damped Gauss–Newton.
//!
//! Model of a pixel at (x, y): `I = P(x, y) + Q(x, y) · M(x, y; g)` where P (background) and Q
//! (contrast) are planes — uneven light, whether it adds or multiplies — and M ∈ [0, 1] is the
//! shape's indicator blurred by a Gaussian of σ = `s` px (defocus and the pixel's own area). For a
//! disc, M = Φ((R − ρ)/s); for a ring the difference of two such; for a cross the sum of two
//! blurred bars less their blurred overlap, which is exact for a Gaussian blur. Least squares on
//! this model is the maximum-likelihood estimate under Gaussian noise, so the centre's spread
//! sits near the Cramér–Rao bound; symmetric model errors (the pixel is a box, not a Gaussian)
//! move no centre.

// Index loops read like the matrix algebra they implement.
#![allow(clippy::needless_range_loop)]

use crate::special::cdf_pdf;

/// Most parameters: 6 geometric + 6 linear.
const MAXP: usize = 12;

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

/// A blurred shape: geometric parameters `g`, always `g[0]` = cx, `g[1]` = cy (px).
pub(crate) trait Model {
    /// Number of geometric parameters.
    const G: usize;
    /// M at (x, y) px and its gradient with respect to `g` written into `grad`; `None` outside
    /// the pixels fitted on, which are chosen by the geometry `sup` (held fixed over several
    /// steps: a pixel set that followed every step made the fit flip between two states).
    fn eval(&self, g: &[f64], sup: &[f64], x: f64, y: f64, grad: &mut [f64]) -> Option<f64>;
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

/// Width (px) of the band on each side of an edge that is fitted, for edge blur `s` px.
fn band(s: f64) -> f64 {
    2.5 * s + 2.0
}

/// Filled disc: g = [cx, cy, R, s].
pub(crate) struct Disc;

impl Model for Disc {
    const G: usize = 4;
    #[inline]
    fn eval(&self, g: &[f64], sup: &[f64], x: f64, y: f64, grad: &mut [f64]) -> Option<f64> {
        let (dx, dy) = (x - g[0], y - g[1]);
        let rho = (dx * dx + dy * dy).sqrt();
        let (r, s) = (g[2], g[3]);
        // sqrt of the squares, not hypot: this runs per pixel and libm's hypot is slow.
        let (ex, ey) = (x - sup[0], y - sup[1]);
        if ((ex * ex + ey * ey).sqrt() - sup[2]).abs() > band(sup[3]) {
            return None;
        }
        let t = (r - rho) / s;
        let (m, p) = cdf_pdf(t);
        let p = p / s;
        let (ux, uy) = if rho > 1e-9 { (dx / rho, dy / rho) } else { (0.0, 0.0) };
        grad[0] = p * ux;
        grad[1] = p * uy;
        grad[2] = p;
        grad[3] = -p * t;
        Some(m)
    }
    fn reach(&self, g: &[f64]) -> f64 {
        g[2] + band(g[3])
    }
    fn extent(&self, g: &[f64]) -> f64 {
        g[2] + 2.0 * g[3].min(3.0) + 0.5
    }
    fn span(&self, g: &[f64], dy: f64) -> [(f64, f64); 2] {
        let b = band(g[3]);
        annulus_span(g[2] - b, g[2] + b, dy)
    }
    fn constrain(&self, g: &mut [f64], before: &[f64]) -> bool {
        limit_move(g, before, 0.25 * before[2]);
        g[2] = g[2].clamp(0.7 * before[2], 1.4 * before[2]);
        g[3] = g[3].clamp(0.25 * before[3], 2.0 * before[3]).clamp(0.15, 0.5 * g[2]);
        g[2] > 1.0
    }
}

/// Ring: g = [cx, cy, Ro, Ri, s].
pub(crate) struct Annulus;

impl Model for Annulus {
    const G: usize = 5;
    #[inline]
    fn eval(&self, g: &[f64], sup: &[f64], x: f64, y: f64, grad: &mut [f64]) -> Option<f64> {
        let (dx, dy) = (x - g[0], y - g[1]);
        let rho = (dx * dx + dy * dy).sqrt();
        let (ro, ri, s) = (g[2], g[3], g[4]);
        let (ex, ey) = (x - sup[0], y - sup[1]);
        let (rs, b) = ((ex * ex + ey * ey).sqrt(), band(sup[4]));
        if rs > sup[2] + b || rs < sup[3] - b {
            return None;
        }
        let (to, ti) = ((ro - rho) / s, (ri - rho) / s);
        let ((co, po), (ci, pi)) = (cdf_pdf(to), cdf_pdf(ti));
        let (po, pi) = (po / s, pi / s);
        let (ux, uy) = if rho > 1e-9 { (dx / rho, dy / rho) } else { (0.0, 0.0) };
        grad[0] = (po - pi) * ux;
        grad[1] = (po - pi) * uy;
        grad[2] = po;
        grad[3] = -pi;
        grad[4] = -po * to + pi * ti;
        Some(co - ci)
    }
    fn reach(&self, g: &[f64]) -> f64 {
        g[2] + band(g[4])
    }
    fn extent(&self, g: &[f64]) -> f64 {
        g[2] + 2.0 * g[4].min(3.0) + 0.5
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
        g[4] = g[4].clamp(0.25 * before[4], 2.0 * before[4]).clamp(0.15, 0.5 * g[2]).min(0.75 * (g[2] - g[3]) + 1.0);
        g[2] > 1.0
    }
}

/// Cross: g = [cx, cy, θ, a, w, s] — bar half-length a, half-width w (px), first bar at θ rad.
pub(crate) struct Cross;

/// A Gaussian-blurred 1-D box |t| ≤ h: value and derivatives by t, h, s.
#[inline]
fn box1(t: f64, h: f64, s: f64) -> [f64; 4] {
    let (p, q) = ((h - t) / s, (h + t) / s);
    let ((cp, dp), (cq, dq)) = (cdf_pdf(p), cdf_pdf(q));
    [cp + cq - 1.0, (dq - dp) / s, (dp + dq) / s, -(p * dp + q * dq) / s]
}

impl Model for Cross {
    const G: usize = 6;
    #[inline]
    fn eval(&self, g: &[f64], sup: &[f64], x: f64, y: f64, grad: &mut [f64]) -> Option<f64> {
        let (dx, dy) = (x - g[0], y - g[1]);
        let (sn, c) = g[2].sin_cos();
        let u = dx * c + dy * sn;
        let v = -dx * sn + dy * c;
        let (a, w, s) = (g[3], g[4], g[5]);
        {
            let (ss, sc) = sup[2].sin_cos();
            let (ex, ey) = (x - sup[0], y - sup[1]);
            let (au, av) = ((ex * sc + ey * ss).abs(), (-ex * ss + ey * sc).abs());
            let b = band(sup[5]);
            let in_bar1 = au <= sup[3] + b && av <= sup[4] + b;
            let in_bar2 = av <= sup[3] + b && au <= sup[4] + b;
            if !(in_bar1 || in_bar2) {
                return None;
            }
        }
        let [ua, ua_t, ua_h, ua_s] = box1(u, a, s);
        let [uw, uw_t, uw_h, uw_s] = box1(u, w, s);
        let [va, va_t, va_h, va_s] = box1(v, a, s);
        let [vw, vw_t, vw_h, vw_s] = box1(v, w, s);
        let m = ua * vw + uw * va - uw * vw;
        let m_u = ua_t * vw + uw_t * va - uw_t * vw;
        let m_v = ua * vw_t + uw * va_t - uw * vw_t;
        grad[0] = -m_u * c + m_v * sn;
        grad[1] = -m_u * sn - m_v * c;
        grad[2] = m_u * v - m_v * u;
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
        g[3].hypot(g[4]) + 2.0 * g[5].min(3.0) + 0.5
    }
    fn constrain(&self, g: &mut [f64], before: &[f64]) -> bool {
        limit_move(g, before, 0.25 * before[3]);
        g[2] = g[2].clamp(before[2] - 0.2, before[2] + 0.2);
        g[3] = g[3].clamp(0.7 * before[3], 1.4 * before[3]);
        g[4] = g[4].clamp(0.5 * before[4], 2.0 * before[4]).clamp(0.3, 0.6 * g[3]);
        g[5] = g[5].clamp(0.25 * before[5], 2.0 * before[5]).clamp(0.15, g[3]);
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
    // information at 1/16 (1/4) of the cost, with the edge width held above what that spacing
    // resolves; the last stage uses every pixel and frees the edge width.
    const STAGES: [(usize, f64, f64, usize); 3] = [(4, 3.0, 0.05, 4), (2, 1.5, 0.02, 3), (1, 0.0, 1e-4, MAX_ITER)];
    let first = STAGES.iter().position(|&(st, ..)| g0[ng - 1] >= 1.5 * st as f64).unwrap_or(2);
    let mut iter = 0;
    for (stage, &(stride, s_floor, tol, max_iter)) in STAGES.iter().enumerate().skip(first) {
        let last = stage == STAGES.len() - 1;
        g[ng - 1] = g[ng - 1].max(s_floor);
        let mut sup = g;
        for _ in 0..max_iter {
            // Re-choose the fitted pixels only when the estimate has really moved.
            let drift = (0..ng).map(|k| (g[k] - sup[k]).abs()).fold(0.0, f64::max);
            if drift > 0.1 || (g[ng - 1] - sup[ng - 1]).abs() > 0.2 * sup[ng - 1] {
                sup = g;
            }
            let acc = accumulate::<M, T, N>(img, model, &g, &sup, &lin, xr, yr, inv, n, stride, false)?;
            // First step: only the planes (the geometry guess is coarse, the planes unknown).
            let free: Vec<usize> = if iter == 0 { (ng..n).collect() } else { (0..n).collect() };
            let mut step = solve(&acc.h, &acc.b, &free).ok_or(FitFailure::Diverged)?;
            // The edge width moves at most ×4 down or ×2 up per step and not below the stage's floor; when it
            // hits a bound it is held there and the others solved for given it, so the step
            // stays consistent (clamping it alone made the centre overshoot and oscillate).
            let si = ng - 1;
            let (s_lo, s_hi) = ((0.25 * g[si]).max(s_floor).max(0.15), 2.0 * g[si]);
            let s_new = g[si] + step[si];
            if iter > 0 && !(s_lo..=s_hi).contains(&s_new) {
                let ds = s_new.clamp(s_lo, s_hi) - g[si];
                let mut b = acc.b;
                for (k, bk) in b.iter_mut().enumerate().take(n) {
                    *bk -= acc.h[k][si] * ds;
                }
                let rest: Vec<usize> = free.iter().copied().filter(|&k| k != si).collect();
                step = solve(&acc.h, &b, &rest).ok_or(FitFailure::Diverged)?;
                step[si] = ds;
            }
            let before = g;
            for k in 0..ng {
                g[k] += step[k];
            }
            for k in 0..6 {
                lin[k] += step[ng + k];
            }
            if !model.constrain(&mut g[..ng], &before[..ng]) || g.iter().chain(&lin).any(|v| !v.is_finite()) {
                return Err(FitFailure::Diverged);
            }
            g[ng - 1] = g[ng - 1].max(s_floor);
            let moved = (g[0] - before[0]).hypot(g[1] - before[1]);
            let sized = (0..ng).skip(2).map(|k| (g[k] - before[k]).abs()).fold(0.0, f64::max);
            iter += 1;
            if iter > 1 && moved < tol && sized < 100.0 * tol.max(1e-5) {
                if last {
                    let e = model.extent(&g[..ng]);
                    let (xmax, ymax) = ((img.w - 1) as f64, (img.h - 1) as f64);
                    if !(g[0] - e >= 0.0 && g[1] - e >= 0.0 && g[0] + e <= xmax && g[1] + e <= ymax) {
                        return Err(FitFailure::Clipped);
                    }
                    let acc = accumulate::<M, T, N>(img, model, &g, &g, &lin, xr, yr, inv, n, 1, true)?;
                    let (r2, min_sector_r2) = acc.r2();
                    return Ok(FitResult { g, lin, r2, min_sector_r2, converged: true });
                }
                break;
            }
        }
    }
    Err(FitFailure::Diverged)
}

struct Acc {
    h: [[f64; MAXP]; MAXP],
    b: [f64; MAXP],
    count: usize,
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
    n: usize,
    stride: usize,
    sectors: bool,
) -> Result<Acc, FitFailure> {
    let ng = M::G;
    let reach = model.reach(&sup[..ng]);
    let (xmax, ymax) = ((img.w - 1) as f64, (img.h - 1) as f64);
    // The band may run off the image: the model needs no particular pixels (whether the mark
    // itself is cut is judged on the final estimate).
    let (x0, x1) = ((sup[0] - reach).max(0.0), (sup[0] + reach).min(xmax));
    let (y0, y1) = ((sup[1] - reach).max(0.0), (sup[1] + reach).min(ymax));
    let mut acc = Acc { h: [[0.0; MAXP]; MAXP], b: [0.0; MAXP], count: 0, sectors: [[0.0; 4]; 8] };
    let mut j = [0.0; MAXP];
    let mut grad = [0.0; 6];
    let (sa, ca) = if ng == 6 { g[2].sin_cos() } else { (0.0, 1.0) };
    // A grid fixed in the image (not following the estimate), so the sampled pixels do not
    // change under the fit from one iteration to the next.
    let on_grid = |v: f64| (v.ceil() as usize).div_ceil(stride) * stride;
    for yi in (on_grid(y0)..=y1.floor() as usize).step_by(stride) {
        let y = yi as f64;
        let v = (y - yr) * inv;
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
                let Some(m) = model.eval(&g[..ng], &sup[..ng], x, y, &mut grad) else { continue };
                let u = (x - xr) * inv;
                let q = lin[3] + lin[4] * u + lin[5] * v;
                let pred = lin[0] + lin[1] * u + lin[2] * v + q * m;
                let r = img.at(xi, yi) - pred;
                for k in 0..ng {
                    j[k] = q * grad[k];
                }
                j[ng..ng + 6].copy_from_slice(&[1.0, u, v, m, m * u, m * v]);
                // N is a constant here: the loops unroll without bounds checks.
                for a in 0..N {
                    let ja = j[a];
                    acc.b[a] += ja * r;
                    let row = &mut acc.h[a];
                    for c in a..N {
                        row[c] += ja * j[c];
                    }
                }
                acc.count += 1;
                if !sectors {
                    continue;
                }
                // Sectors in the mark's own frame (for a cross: rotated with it).
                let (dx, dy) = (x - g[0], y - g[1]);
                let (rx, ry) = (dx * ca + dy * sa, -dx * sa + dy * ca);
                let sector = sector_of(rx, ry);
                let val = img.at(xi, yi);
                let s = &mut acc.sectors[sector];
                s[0] += 1.0;
                s[1] += val;
                s[2] += val * val;
                s[3] += r * r;
            }
        }
    }
    if acc.count < 4 * n {
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

/// Solves (H + λ·diag H) δ = b over the parameters `idx` by Cholesky; the rest stay 0.
fn solve(h: &[[f64; MAXP]; MAXP], b: &[f64; MAXP], idx: &[usize]) -> Option<[f64; MAXP]> {
    let m = idx.len();
    let mut l = [[0.0; MAXP]; MAXP];
    for i in 0..m {
        for jj in 0..=i {
            let mut sum = h[idx[i]][idx[jj]];
            if i == jj {
                sum *= 1.0 + 1e-6;
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
/// `sigma` grey levels: the Cramér–Rao bound (px) on cx and cy, all other parameters unknown.
pub(crate) fn crb<M: Model>(model: &M, g: &[f64], lin: &[f64; 6], scale: f64, sigma: f64) -> Option<(f64, f64)> {
    let ng = M::G;
    let n = ng + 6;
    let reach = model.reach(g).ceil() as i64 + 1;
    let mut h = [[0.0; MAXP]; MAXP];
    let mut grad = [0.0; 6];
    let mut j = [0.0; MAXP];
    let (cx, cy) = (g[0].round() as i64, g[1].round() as i64);
    for yi in cy - reach..=cy + reach {
        for xi in cx - reach..=cx + reach {
            let (x, y) = (xi as f64, yi as f64);
            let Some(m) = model.eval(g, g, x, y, &mut grad) else { continue };
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
                let h = 1e-5;
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
        check(&|g, gr| Disc.eval(g, g, x, y, gr), &[3.0, 2.0, 13.0, 1.3]);
        check(&|g, gr| Annulus.eval(g, g, x, y, gr), &[3.0, 2.0, 15.0, 12.0, 1.3]);
        check(&|g, gr| Cross.eval(g, g, x, y, gr), &[3.0, 2.5, 0.3, 14.0, 3.0, 1.1]);
        check(&|g, gr| Cross.eval(g, g, 4.0, 1.7, gr), &[3.0, 2.5, 0.3, 14.0, 3.0, 1.1]);
    }
}
