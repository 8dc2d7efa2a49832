//! Deterministic normal draws for the statistical tests (Box–Muller over a 64-bit LCG), so a
//! test's noise is the same on every run and machine.

/// A seeded stream of standard normal draws.
pub(crate) struct Normal(pub(crate) u64);

impl Normal {
    /// A uniform draw in (0, 1).
    pub(crate) fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);

        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// A standard normal draw.
    pub(crate) fn draw(&mut self) -> f64 {
        let (u, v) = (self.unit(), self.unit());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}
