//! A hostile frame for the coarse search (issue 33): a field of small dots filling the view.
//!
//! `cargo run --release -p vision-locate --example locate_field -- [SIZE] [DIAMETER] [PITCH]`
//!
//! Renders a SIZE × SIZE px 8-bit frame (default 3000, 9 MP) tiled with dark dots of DIAMETER px
//! (default 6) every PITCH px (default 12), searches it for one such dot, and prints the answer
//! and the time it took. The default field took 46 s before the search kept its blobs in cells
//! (each new blob was compared with every kept one); it is now refused as cluttered in 0.2 s,
//! and `8000 6 80` (64 MP, 9801 dots, blocks of 1 px) runs to its end in about 4 s.

use std::time::Instant;

use vision_locate::render::{render, Depth, PlacedMark, Scene, Shape};
use vision_locate::{locate, MarkKind, MarkSpec, Polarity};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let size: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(3000);
    let d: f64 = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(6.0);
    let pitch: f64 = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(12.0);
    let n = ((size as f64 - pitch) / pitch).floor() as usize;
    let marks = (0..n * n)
        .map(|k| PlacedMark {
            shape: Shape::Dot { diameter: d },
            x: pitch * (1 + k % n) as f64,
            y: pitch * (1 + k / n) as f64,
            reflectance: 0.1,
        })
        .collect();
    let scene = Scene { marks, blur_sigma: 0.8, noise_sigma: 1.0, seed: 3, ..Scene::blank(size, size, Depth::Eight) };
    let t = Instant::now();
    let image = render(&scene).expect("valid scene");
    println!("{size} × {size} px, {} dots of {d} px every {pitch} px, rendered in {:.2?}", n * n, t.elapsed());
    let spec = MarkSpec::new(MarkKind::Dot, d, 0.25, Polarity::DarkOnLight).expect("valid spec");
    let t = Instant::now();
    let answer = locate(&image.view(), &spec);
    println!("{answer:?} in {:.2?}", t.elapsed());
}
