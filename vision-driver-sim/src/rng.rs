//! The reading-mode camera's noise: Gaussian draws (Box–Muller) on the renderer's SplitMix64,
//! so the same seed gives the same noise on every platform and in every version, which a
//! dependency could not promise.

use vision_locate::render::SplitMix64;

/// A seeded generator of uniform and Gaussian numbers.
#[derive(Debug, Clone)]
pub(crate) struct Rng {
    bits: SplitMix64,
}

impl Rng {
    pub(crate) fn new(seed: u64) -> Rng {
        Rng { bits: SplitMix64::new(seed) }
    }

    fn next_u64(&mut self) -> u64 {
        self.bits.next_u64()
    }

    /// Uniform in (0, 1].
    fn open_unit(&mut self) -> f64 {
        ((self.next_u64() >> 11) + 1) as f64 / (1u64 << 53) as f64
    }

    /// A standard normal sample.
    pub(crate) fn gaussian(&mut self) -> f64 {
        let (u1, u2) = (self.open_unit(), self.open_unit());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_has_unit_variance_and_is_reproducible() {
        let mut a = Rng::new(7);
        let samples: Vec<f64> = (0..20_000).map(|_| a.gaussian()).collect();
        let n = samples.len() as f64;
        let mean = samples.iter().sum::<f64>() / n;
        let var = samples.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
        assert!(mean.abs() < 0.03, "mean {mean}");
        assert!((var - 1.0).abs() < 0.05, "variance {var}");
        assert!(samples.iter().all(|x| x.is_finite()));
        let mut b = Rng::new(7);
        assert_eq!(samples[..5], (0..5).map(|_| b.gaussian()).collect::<Vec<_>>()[..]);
    }
}
