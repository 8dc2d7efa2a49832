//! The fit: damped Gauss–Newton over the normal equations, coarse to fine.

// Index loops read like the matrix algebra they implement.
#![expect(clippy::needless_range_loop, reason = "Index loops read like the matrix algebra they implement.")]

use super::model::{blur_of, edge_width, Model};
use super::{Img, MAXP};
use crate::edge::S_MIN;

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

/// Coarse to fine: while the edge is wide, every 4th (2nd) pixel each way carries the same
/// information at 1/16 (1/4) of the cost, with the blur held above what that spacing resolves;
/// the last stage uses every pixel and frees the blur. Each stage: (pixel step, least blur px,
/// convergence, iterations).
const STAGES: [(usize, f64, f64, usize); 3] = [(4, 3.0, 0.05, 4), (2, 1.5, 0.02, 3), (1, 0.0, 5e-4, MAX_ITER)];

/// Fits `model` starting from geometry `g0`; `scale` px normalises the plane slopes.
#[expect(clippy::float_cmp, reason = "the same support exactly, so the cached sums still hold")]
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
    // The first stage: the coarsest whose spacing the starting blur reaches.
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
#[expect(clippy::too_many_arguments, reason = "the pass's state, borrowed apart for the inner loop")]
#[expect(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    reason = "pixel indices, clamped to the image before"
)]
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
}
