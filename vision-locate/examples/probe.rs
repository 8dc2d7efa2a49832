//! Scratch probe.
use vision_locate::render::{render, Depth, Lighting, PlacedMark, Scene, Shape};
use vision_locate::{locate, MarkKind, MarkSpec, Polarity};
fn main() {
    let a: Vec<f64> = std::env::args().skip(1).map(|s| s.parse().unwrap()).collect();
    let (d, blur, grad) = (a[0], a[1], a[2]);
    let scene = Scene {
        marks: vec![PlacedMark { shape: Shape::Dot { diameter: d }, x: 300.3, y: 400.7, reflectance: 0.1 }],
        noise_sigma: 2.0,
        blur_sigma: blur,
        lighting: Lighting { level: 0.95, gradient: grad, angle: 0.5 },
        ..Scene::blank(1280, 960, Depth::Eight)
    };
    let img = render(&scene).unwrap();
    let spec = MarkSpec::new(MarkKind::Dot, d, 0.25, Polarity::DarkOnLight).unwrap();
    println!("{:?}", locate(&img.view(), &spec));
}
