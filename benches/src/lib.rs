//! Deterministic inputs shared by the benchmarks (no RNG crate: a fixed LCG), and the Keyence
//! benchmarks' emulated camera, raw client and in-memory camera ([`keyence`]).

pub mod keyence;

use vision_math::{Point2, Vector2};

/// `n` commanded points spread over a 6 × 4 unit part and their observed images under a
/// small rotation (0.5°), a shift of (0.1, 0.05) units and scales (1.001, 0.999), with
/// ±1e-4 units of deterministic noise.
#[must_use]
pub fn marks(n: usize) -> (Vec<Point2<f64>>, Vec<Point2<f64>>) {
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = move || {
        state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        #[allow(clippy::cast_precision_loss)]
        let unit = (state >> 11) as f64 / (1u64 << 53) as f64;
        unit
    };
    let corners = [(0.0, 0.0), (6.0, 0.0), (6.0, 4.0), (0.0, 4.0)];
    let (s, c) = 0.5f64.to_radians().sin_cos();
    let mut commanded = Vec::with_capacity(n);
    let mut observed = Vec::with_capacity(n);
    for i in 0..n {
        let (x, y) = corners.get(i).copied().unwrap_or_else(|| (next() * 6.0, next() * 4.0));
        let (px, py) = (1.001 * x, 0.999 * y);
        let noise = Vector2::new(next() - 0.5, next() - 0.5) * 2e-4;
        commanded.push(Point2::new(x, y));
        observed.push(Point2::new(c * px - s * py + 0.1, s * px + c * py + 0.05) + noise);
    }
    (commanded, observed)
}
