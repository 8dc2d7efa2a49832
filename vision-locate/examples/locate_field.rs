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

use vision_locate::render::{render, Scene};
use vision_locate::{locate, MarkKind, MarkSpec, Polarity};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let size: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(3000);
    let d: f64 = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(6.0);
    let pitch: f64 = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(12.0);
    let scene = Scene::dot_field(size, d, pitch);
    let n2 = scene.marks.len();
    let t = Instant::now();
    let image = render(&scene).expect("valid scene");
    println!("{size} × {size} px, {n2} dots of {d} px every {pitch} px, rendered in {:.2?}", t.elapsed());
    let spec = MarkSpec::new(MarkKind::Dot, d, 0.25, Polarity::DarkOnLight).expect("valid spec");
    let t = Instant::now();
    let answer = locate(&image.view(), &spec);
    println!("{answer:?} in {:.2?}", t.elapsed());
}
