//! The normal distribution's CDF and density (the blurred-edge profile).

const FRAC_1_SQRT_2PI: f64 = 0.398_942_280_401_432_7;

/// Standard normal density.
pub(crate) fn pdf(t: f64) -> f64 {
    FRAC_1_SQRT_2PI * (-0.5 * t * t).exp()
}

/// Standard normal CDF Φ(t), absolute error below 1e-7 (Abramowitz & Stegun 7.1.26 through
/// erf); exactly Φ(−t) = 1 − Φ(t), so symmetric marks fit without bias.
pub(crate) fn cdf(t: f64) -> f64 {
    let e = erf_pos(t.abs() * std::f64::consts::FRAC_1_SQRT_2);
    if t >= 0.0 {
        0.5 + 0.5 * e
    } else {
        0.5 - 0.5 * e
    }
}

fn erf_pos(x: f64) -> f64 {
    const P: f64 = 0.327_591_1;
    const A: [f64; 5] = [0.254_829_592, -0.284_496_736, 1.421_413_741, -1.453_152_027, 1.061_405_429];
    let k = 1.0 / (1.0 + P * x);
    let poly = k * (A[0] + k * (A[1] + k * (A[2] + k * (A[3] + k * A[4]))));
    1.0 - poly * (-x * x).exp()
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
    fn pdf_is_the_cdf_slope() {
        for t in [-2.5, -1.0, 0.0, 0.3, 1.7] {
            let h = 1e-4;
            let slope = (cdf(t + h) - cdf(t - h)) / (2.0 * h);
            assert!((slope - pdf(t)).abs() < 2e-3, "t {t}: {slope} vs {}", pdf(t));
        }
    }
}
