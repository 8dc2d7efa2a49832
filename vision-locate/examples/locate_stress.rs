//! Random stress of `locate` on sharp rendered marks (the regression cases in
//! `tests/locate.rs` came from it):
//!
//! `cargo run --release -p vision-locate --example locate_stress -- [N] [NOISE] [SEED]`
//!
//! N frames per kind (default 2000) of 400 × 400 px, 8-bit, blur 0, noise NOISE grey levels
//! (default 0), seed SEED (default 49), each with a random centre, diameter 30–200 px, polarity and (cross) angle.
//! Prints per kind how many were not found or found more than 0.05 px off, and the first few
//! such cases with everything needed to render them again.

use vision_locate::render::{render, Depth, PlacedMark, Scene, Shape, SplitMix64};
use vision_locate::{locate, Located, MarkKind, MarkSpec, Polarity};

const SIZE: usize = 400;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(2000);
    let noise: f64 = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(0.0);
    let seed: u64 = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(49);
    let mut rng = SplitMix64::new(seed);
    let mut total = 0;
    for kind in [MarkKind::Dot, MarkKind::Ring, MarkKind::Cross] {
        let mut failures = Vec::new();
        for _ in 0..n {
            let d = rng.range(30.0, 200.0);
            let m = d / 2.0 + 10.0;
            let (x, y) = (rng.range(m, SIZE as f64 - m), rng.range(m, SIZE as f64 - m));
            let angle = rng.range(-0.78, 0.78);
            let polarity = if rng.uniform() < 0.5 { Polarity::DarkOnLight } else { Polarity::LightOnDark };
            let frame_seed = rng.next_u64();
            let (bg, ink) = match polarity {
                Polarity::DarkOnLight => (0.8, 0.1),
                Polarity::LightOnDark => (0.15, 0.9),
            };
            let shape = match kind {
                MarkKind::Dot => Shape::Dot { diameter: d },
                MarkKind::Ring => Shape::Ring { diameter: d, line_width: 0.2 * d },
                MarkKind::Cross => Shape::Cross { length: d, bar_width: 0.2 * d, angle },
            };
            let scene = Scene {
                background: bg,
                marks: vec![PlacedMark { shape, x, y, reflectance: ink }],
                noise_sigma: noise,
                seed: frame_seed,
                ..Scene::blank(SIZE, SIZE, Depth::Eight)
            };
            let img = render(&scene).expect("valid scene");
            let spec = MarkSpec::new(kind, d, 0.2, polarity).expect("valid spec");
            let bad = match locate(&img.view(), &spec).expect("valid spec") {
                Located::Found(mk) if (mk.x - x).hypot(mk.y - y) < 0.05 => None,
                other => Some(other),
            };
            if let Some(r) = bad {
                failures.push(format!(
                    "{kind:?} {polarity:?} x {x:?} y {y:?} d {d:?} angle {angle:?} seed {frame_seed}: {r:?}"
                ));
            }
        }
        println!("{kind:?}: {} of {n} failed (noise {noise})", failures.len());
        for f in failures.iter().take(10) {
            println!("    {f}");
        }
        total += failures.len();
    }
    println!("total: {total} of {} failed", 3 * n);
}
