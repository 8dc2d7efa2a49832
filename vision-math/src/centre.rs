//! The optical centre from a height change: the pixel that sees the same table point at every
//! working distance.
//!
//! A camera on the head images a table point `v` away from where the machine's Z direction
//! meets the table at native pixel `p = c + (K·R)⁻¹·v`, with `K ∝` the working distance. Raise
//! the head by `h` (working distance `w → w + h`) without moving X/Y and the same point images
//! at `p' = c + r·(p − c)` with `r = w / (w + h)`: the image shrinks about `c`, the one pixel
//! that does not move. Reading marks at several X/Y positions at both heights gives pairs
//! `(pᵢ, p'ᵢ)` and the linear model `p' = r·p + t`, `t = (1 − r)·c`, solved here by least
//! squares over both pixel axes (three unknowns: `r`, `tₓ`, `t_y`):
//!
//! `r = Σ (pᵢ − p̄)·(p'ᵢ − p̄') / Σ ‖pᵢ − p̄‖²`, `c = p̄ + (p̄' − p̄) / (1 − r)`.
//!
//! The centre's 1σ per axis: the pair noise σₚ (the residuals' σ, or the camera's `σ·√(1 + r²)`
//! when larger: both readings are noisy) over the means, amplified by `1/(1 − r)`, plus the
//! slope's share: `σ²(cₖ) = σₚ² / (1 − r)² · (1/N + (cₖ − p̄ₖ)² / Σ ‖pᵢ − p̄‖²)`. A lift of 4 % of
//! the working distance makes `1/(1 − r)` ≈ 25: twenty-five pairs at 0.1 px give about 0.7 px.

use nalgebra::{Point2, Vector2};

use crate::MathError;

/// The fewest pairs [`fit_centre`] accepts (three unknowns, and a σ from the residuals).
pub const MIN_CENTRE_PAIRS: usize = 3;

/// What [`fit_centre`] found. Pixels are native camera pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CentreFit {
    /// The pixel that sees the same table point at both heights, native pixels.
    pub centre: Point2<f64>,
    /// Its 1σ per pixel axis, pixels.
    pub sigma: Vector2<f64>,
    /// The image scale at the second height over the first's (`w / (w + h)`: < 1 when the
    /// camera rose), dimensionless.
    pub ratio: f64,
    /// RMS distance of the pairs from the model, pixels.
    pub rms: f64,
    /// Pairs used.
    pub pairs: usize,
}

/// Fits the centre of the scale change from `before` (native pixels at the first height) to
/// `after` (the same marks and camera X/Y at the second height); `noise_px` is the camera's σ
/// per reading and axis (pixels), the σ floor when the residuals show less.
///
/// # Errors
/// [`MathError::LengthMismatch`], [`MathError::TooFewPoints`] (fewer than
/// [`MIN_CENTRE_PAIRS`]), [`MathError::NonFinite`], [`MathError::CoincidentPoints`] (the marks
/// were all read at one pixel), [`MathError::NoScaleChange`] (the image did not change scale
/// measurably: the height change did not reach the camera, or was too small for the noise).
pub fn fit_centre(before: &[Point2<f64>], after: &[Point2<f64>], noise_px: f64) -> Result<CentreFit, MathError> {
    if before.len() != after.len() {
        return Err(MathError::LengthMismatch { commanded: before.len(), observed: after.len() });
    }
    let n = before.len();
    if n < MIN_CENTRE_PAIRS {
        return Err(MathError::TooFewPoints { model: "optical centre", needed: MIN_CENTRE_PAIRS, got: n });
    }
    if !before.iter().chain(after).all(|p| p.x.is_finite() && p.y.is_finite() && p.coords.amax() < 1e9) {
        return Err(MathError::NonFinite { what: "a pixel reading" });
    }
    if !(noise_px.is_finite() && noise_px >= 0.0) {
        return Err(MathError::NonFinite { what: "the camera noise" });
    }
    let nf = n as f64;
    let mean = |v: &[Point2<f64>]| v.iter().fold(Vector2::zeros(), |s, p| s + p.coords) / nf;
    let (m0, m1) = (mean(before), mean(after));
    let (mut sxx, mut sxy) = (0.0, 0.0);
    for (p, q) in before.iter().zip(after) {
        let d = p.coords - m0;
        sxx += d.norm_squared();
        sxy += d.dot(&(q.coords - m1));
    }
    if sxx <= 1e-12 {
        return Err(MathError::CoincidentPoints);
    }
    let r = sxy / sxx;
    let sum2: f64 = before.iter().zip(after).map(|(p, q)| (q.coords - m1 - r * (p.coords - m0)).norm_squared()).sum();
    let rms = (sum2 / nf).sqrt();
    let sigma_pair = (sum2 / (2.0 * nf - 3.0)).sqrt().max(noise_px * r.hypot(1.0));
    let sigma_r = sigma_pair / sxx.sqrt();
    let gap = 1.0 - r;
    // Ten σ of the slope: below it the centre is noise amplified past any use.
    if !(r > 0.0 && gap.abs() > 10.0 * sigma_r && gap.abs() > 1e-6) {
        return Err(MathError::NoScaleChange { ratio: r, sigma: sigma_r });
    }
    let centre = m0 + (m1 - m0) / gap;
    let sigma = (centre - m0).map(|dc| sigma_pair / gap.abs() * (1.0 / nf + dc * dc / sxx).sqrt());
    Ok(CentreFit { centre: Point2::from(centre), sigma, ratio: r, rms, pairs: n })
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::normal::Normal;

    /// A 4 × 4 grid of readings ±350 px about `centre`'s neighbourhood, and the same marks
    /// after a lift that scales the image by `r` about `c`.
    fn pairs(c: Point2<f64>, r: f64) -> (Vec<Point2<f64>>, Vec<Point2<f64>>) {
        let steps = [-350.0, -117.0, 117.0, 350.0];
        let before: Vec<Point2<f64>> =
            steps.iter().flat_map(|x| steps.iter().map(move |y| Point2::new(888.0 + x, 890.0 + y))).collect();
        let after = before.iter().map(|p| c + r * (p - c)).collect();
        (before, after)
    }

    #[test]
    fn exact_pairs_give_the_centre_exactly() {
        let c = Point2::new(891.7, 884.2);
        let (before, after) = pairs(c, 6.0 / 6.25);
        let fit = fit_centre(&before, &after, 0.0).expect("fit");
        assert!((fit.centre - c).norm() < 1e-9, "{fit:?}");
        assert!((fit.ratio - 0.96).abs() < 1e-12 && fit.rms < 1e-9);
        // A lower lift (r > 1: the camera came closer) works the same.
        let fit = fit_centre(&before, &pairs(c, 1.03).1, 0.0).expect("fit");
        assert!((fit.centre - c).norm() < 1e-9);
    }

    #[test]
    fn the_sigma_is_honest_with_noise() {
        let mut g = Normal(7);
        let (mut sum2, mut n) = (0.0, 0.0);
        for trial in 0..2000 {
            let c = Point2::new(888.0 + 5.0 * g.draw(), 888.0 + 5.0 * g.draw());
            let (mut before, mut after) = pairs(c, 6.0 / 6.25);
            let noise = 0.05 + 0.1 * f64::from(trial % 3);
            for p in before.iter_mut().chain(after.iter_mut()) {
                *p += Vector2::new(g.draw(), g.draw()) * noise;
            }
            let fit = fit_centre(&before, &after, noise).expect("fit");
            let z = (fit.centre - c).component_div(&fit.sigma);
            sum2 += z.norm_squared();
            n += 2.0;
        }
        // The z-scores' spread is 1 within sampling (4000 draws: ±0.02), a little under 1
        // because the σ floor is the camera's and the residuals rarely exceed it.
        let spread = (sum2 / n).sqrt();
        assert!((0.85..1.1).contains(&spread), "z spread {spread}");
    }

    #[test]
    fn no_scale_change_and_bad_input_are_refused() {
        let c = Point2::new(888.0, 888.0);
        let (before, _) = pairs(c, 1.0);
        let mut g = Normal(3);
        let same: Vec<Point2<f64>> = before.iter().map(|p| p + Vector2::new(g.draw(), g.draw()) * 0.1).collect();
        assert!(matches!(fit_centre(&before, &same, 0.1), Err(MathError::NoScaleChange { .. })));
        assert!(matches!(fit_centre(&before[..2], &same[..2], 0.1), Err(MathError::TooFewPoints { .. })));
        assert!(matches!(fit_centre(&before, &same[..3], 0.1), Err(MathError::LengthMismatch { .. })));
        let mut nan = before.clone();
        nan[0].x = f64::NAN;
        assert!(matches!(fit_centre(&nan, &same, 0.1), Err(MathError::NonFinite { .. })));
        let one = vec![c; 5];
        assert_eq!(fit_centre(&one, &one, 0.1), Err(MathError::CoincidentPoints));
    }
}
