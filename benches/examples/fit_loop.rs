//! Calls one fit in a tight loop, for instruction counts under callgrind or perf. The whole
//! result goes through `black_box`, so no part of the fit can be optimised away.
use std::hint::black_box;
use vision_benches::marks;

fn main() {
    let model = std::env::args().nth(1).unwrap_or_else(|| "similarity".into());
    let n: usize = std::env::args().nth(2).and_then(|s| s.parse().ok()).unwrap_or(4);
    let iters: u32 = std::env::args().nth(3).and_then(|s| s.parse().ok()).unwrap_or(1_000_000);
    let model = vision_math::Model::from_name(&model).expect("model name");
    let (c, o) = marks(n);
    let t = std::time::Instant::now();
    let params_only = std::env::args().nth(4).is_some_and(|s| s == "transform");
    let mut acc = 0.0;
    for _ in 0..iters {
        if params_only {
            let t = black_box(model.transform(black_box(&c), black_box(&o)));
            if let Ok(t) = t {
                acc += t.scale.x;
            }
        } else if let Ok(f) = black_box(model.fit(black_box(&c), black_box(&o))) {
            acc += f.rms;
        }
    }
    let ns = t.elapsed().as_secs_f64() * 1e9 / f64::from(iters);
    println!("{model} N={n}: {ns:.2} ns/fit (acc {acc:.3e})");
}
