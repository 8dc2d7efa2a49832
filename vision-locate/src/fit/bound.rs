//! The Cramér–Rao bound of a fitted centre.

// Index loops read like the matrix algebra they implement.

use super::model::{edge_width, Model};
use super::solve::solve;
use super::MAXP;

/// Fisher information of the model at (`g`, `lin`) over the pixels it fits on, for noise of
/// `sigma` grey levels: the Cramér–Rao bound (px) on cx and cy, all other parameters unknown
/// (the blur s at least [`crate::edge::S_MIN`]).
#[expect(clippy::cast_possible_truncation, reason = "pixel indices of a mark inside the image")]
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
