//! Deterministic inputs shared by the benchmarks (no RNG crate: a fixed LCG), the Keyence
//! benchmarks' emulated camera, raw client and in-memory camera (`keyence`), and the path
//! planner's programs (`path`); those two modules come with the `bench` feature only (the
//! `guard` build of `speed-guard` needs neither).

#[cfg(feature = "bench")]
pub mod keyence;
#[cfg(feature = "bench")]
pub mod path;

use std::fmt::Write as _;

use vision_math::{Point2, Vector2};

/// A deterministic generator of uniform numbers in [0, 1).
fn lcg(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);

        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `n` commanded points spread over a 6 × 4 unit part and their observed images under a
/// small rotation (0.5°), a shift of (0.1, 0.05) units and scales (1.001, 0.999), with
/// ±1e-4 units of deterministic noise.
#[must_use]
pub fn marks(n: usize) -> (Vec<Point2<f64>>, Vec<Point2<f64>>) {
    let mut next = lcg(0x9E37_79B9_7F4A_7C15);
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

/// A G-code program of `lines` lines in inches, for the interpreter benchmarks: a CAM-like mix of
/// `G1` moves (about 60 %), `G2`/`G3` arcs with I/J centres (20 %, valid geometry to 4 decimals),
/// comment lines and trailing comments (10 %), and parameter lines that assign and use `#1`/`#2`
/// in `[expressions]` (10 %). With `literal_only`, the parameter lines are replaced by plain
/// `G1` moves (for parsers without parameters). Every line starts with an `N` number.
#[must_use]
pub fn gcode_program(lines: usize, literal_only: bool) -> String {
    let mut next = lcg(0x2545_F491_4F6C_DD1D);
    let mut s = String::with_capacity(lines * 34);
    s.push_str("N1 G90 G20 G17 G64 P0.001 F40 (generated for the benchmarks)\n");
    s.push_str("N2 #1 = 0.5 #2 = 0.25\n");
    let (mut x, mut y) = (0.0f64, 0.0f64);
    // The generator tracks #1 and #2 so that arcs after a parameter move start where it ended.
    let (mut p1, mut p2) = (0.5f64, 0.25f64);
    for n in 3..=lines {
        let kind = next();
        // Writing to a String cannot fail.
        let _ = if kind < 0.6 || (literal_only && kind >= 0.9) {
            x = (x + next() * 2.0 - 1.0).clamp(-20.0, 20.0);
            y = (y + next() * 2.0 - 1.0).clamp(-20.0, 20.0);
            writeln!(s, "N{n} G1 X{x:.4} Y{y:.4} Z{:.4}", -next() * 0.1)
        } else if kind < 0.8 {
            // A quarter-ish arc about a centre at (I, J) from the current point, ending on the circle.
            let (i, j) = (next() * 2.0 - 1.0, next() * 2.0 - 1.0);
            let (cx, cy) = (x + i, y + j);
            let r = i.hypot(j);
            let a = (-j).atan2(-i) + 0.3 + next();
            x = cx + r * a.cos();
            y = cy + r * a.sin();
            let code = if kind < 0.7 { "G2" } else { "G3" };
            writeln!(s, "N{n} {code} X{x:.4} Y{y:.4} I{i:.4} J{j:.4}")
        } else if kind < 0.85 {
            writeln!(s, "N{n} (pocket {n}: finishing pass, climb milling)")
        } else if kind < 0.9 {
            x = (x + 0.01).min(20.0);
            writeln!(s, "N{n} G1 X{x:.4} ; nudge")
        } else if kind < 0.95 {
            p1 += 0.001;
            p2 = p2 * 0.5 + 0.125;
            writeln!(s, "N{n} #1 = [#1 + 0.001] #2 = [#2 * 0.5 + 0.125]")
        } else {
            x = p1;
            y = p2 * 2.0 - 0.25;
            writeln!(s, "N{n} G1 X#1 Y[#2 * 2 - 0.25]")
        };
    }
    s
}
