//! One `locate` call on one rendered 1280 × 960 8-bit frame, for instruction counts under
//! callgrind (`--toggle-collect='vision_locate::locate'` counts the finder alone):
//!
//! `valgrind --tool=callgrind --toggle-collect='vision_locate::locate' \
//!   target/release/examples/locate_once dot 60 2.0 0.3`
//!
//! Arguments: kind (dot, ring, cross, none), size px, blur σ px, light gradient (fraction).

use vision_locate::render::{render, Depth, Lighting, PlacedMark, Scene, Shape};
use vision_locate::{locate, MarkKind, MarkSpec, Polarity};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let num = |i: usize, default: f64| args.get(i).and_then(|a| a.parse().ok()).unwrap_or(default);
    let (d, blur, gradient) = (num(1, 60.0), num(2, 0.0), num(3, 0.0));
    let (kind, shape) = match args.first().map(String::as_str).unwrap_or("dot") {
        "ring" => (MarkKind::Ring, Some(Shape::Ring { diameter: d, line_width: 0.2 * d })),
        "cross" => (MarkKind::Cross, Some(Shape::Cross { length: d, bar_width: 0.2 * d, angle: 0.3 })),
        "none" => (MarkKind::Dot, None),
        _ => (MarkKind::Dot, Some(Shape::Dot { diameter: d })),
    };
    let img = render(&Scene {
        marks: shape.map(|shape| PlacedMark { shape, x: 640.37, y: 480.81, reflectance: 0.1 }).into_iter().collect(),
        blur_sigma: blur,
        noise_sigma: 2.0,
        lighting: Lighting { level: 0.95, gradient, angle: 0.4 },
        seed: 27,
        ..Scene::blank(1280, 960, Depth::Eight)
    })
    .expect("valid scene");
    let spec = MarkSpec::new(kind, d, 0.25, Polarity::DarkOnLight).expect("valid spec");
    println!("{:?}", locate(&img.view(), &spec));
}
