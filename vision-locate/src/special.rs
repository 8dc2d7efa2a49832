//! The normal distribution's CDF and density (what the edge profiles are made of).

const FRAC_1_SQRT_2PI: f64 = 0.398_942_280_401_432_7;

/// Standard normal density.
#[cfg(test)]
pub(crate) fn pdf(t: f64) -> f64 {
    FRAC_1_SQRT_2PI * (-0.5 * t * t).exp()
}

/// Φ(t) and the density φ(t) together, sharing one exponential.
#[inline]
pub(crate) fn cdf_pdf(t: f64) -> (f64, f64) {
    let g = (-0.5 * t * t).exp();
    let x = t.abs() * std::f64::consts::FRAC_1_SQRT_2;
    let e = 1.0 - erf_poly(x) * g;
    let c = if t >= 0.0 { 0.5 + 0.5 * e } else { 0.5 - 0.5 * e };
    (c, FRAC_1_SQRT_2PI * g)
}

/// Standard normal CDF Φ(t), absolute error below 1e-7 (Abramowitz & Stegun 7.1.26 through
/// erf); exactly Φ(−t) = 1 − Φ(t), so symmetric marks fit without bias.
#[cfg(test)]
pub(crate) fn cdf(t: f64) -> f64 {
    let e = erf_pos(t.abs() * std::f64::consts::FRAC_1_SQRT_2);
    if t >= 0.0 {
        0.5 + 0.5 * e
    } else {
        0.5 - 0.5 * e
    }
}

#[cfg(test)]
fn erf_pos(x: f64) -> f64 {
    1.0 - erf_poly(x) * (-x * x).exp()
}

/// erf(x) = 1 − poly(x)·e^(−x²) for x ≥ 0.
#[inline]
fn erf_poly(x: f64) -> f64 {
    const P: f64 = 0.327_591_1;
    const A: [f64; 5] = [0.254_829_592, -0.284_496_736, 1.421_413_741, -1.453_152_027, 1.061_405_429];
    let k = 1.0 / (1.0 + P * x);
    k * (A[0] + k * (A[1] + k * (A[2] + k * (A[3] + k * A[4]))))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cdf_matches_known_values() {
        // Φ(1) = 0.841344746…, Φ(−2) = 0.022750131…
        assert!((cdf(1.0) - 0.841_344_746).abs() < 2e-7);
        assert!((cdf(-2.0) - 0.022_750_131_9).abs() < 2e-7);
        assert!((cdf(0.0) - 0.5).abs() < 1e-8);
        assert!((cdf(0.7) + cdf(-0.7) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn the_pair_matches_the_singles() {
        for t in [-3.0, -0.4, 0.0, 1.2, 5.0] {
            let (c, p) = cdf_pdf(t);
            assert!((c - cdf(t)).abs() < 1e-15 && (p - pdf(t)).abs() < 1e-15);
        }
    }

    #[test]
    fn pdf_is_the_cdf_slope() {
        for t in [-2.5, -1.0, 0.0, 0.3, 1.7] {
            let h = 1e-4;
            let slope = (cdf(t + h) - cdf(t - h)) / (2.0 * h);
            assert!((slope - pdf(t)).abs() < 2e-3, "t {t}: {slope} vs {}", pdf(t));
        }
    }
}
