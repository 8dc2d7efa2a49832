//! Inputs for the path planner benchmarks (`benches/path.rs`, `examples/path_loop.rs`).

use vision_path::{Item, Limits, PathMode, PlanConfig, Rate, Segment, Shape, Xyz};

/// An inch machine like the manual's router: 20 in/s² path acceleration, every axis at
/// 10 in/s and 20 in/s², 1 ms setpoints, starting at the origin.
#[must_use]
pub fn router(start: Xyz) -> PlanConfig {
    PlanConfig::new(Limits::uniform(20.0, 10.0, 20.0), 0.001, start)
}

/// `n` feed segments of about `step` inch along an Archimedean spiral (radius from 0.5 in,
/// growing 0.02 in per turn) at `feed` in/min under `mode`, then the end: a CAM-style dense
/// polyline, generated lazily (nothing is collected).
pub fn spiral(n: usize, step: f64, feed: f64, mode: PathMode) -> impl Iterator<Item = Item> + Clone {
    let at = |theta: f64| {
        let r = 0.5 + 0.02 * theta / std::f64::consts::TAU;
        Xyz::new(r * theta.cos(), r * theta.sin(), 0.0)
    };
    let mut theta = 0.0f64;
    (0..=n).map(move |k| {
        if k == n {
            return Item::End { line: n + 1 };
        }
        let start = at(theta);
        let r = 0.5 + 0.02 * theta / std::f64::consts::TAU;
        theta += step / r;
        Item::Move(Segment { line: k + 1, start, end: at(theta), shape: Shape::Line, rate: Rate::Feed(feed), mode })
    })
}

/// Where [`spiral`] starts.
#[must_use]
pub fn spiral_start() -> Xyz {
    Xyz::new(0.5, 0.0, 0.0)
}
