#![expect(missing_docs, reason = "criterion_group!/criterion_main! generate undocumented items.")]
//! vision-locate: time per 1280 × 960 8-bit frame (issue 27's budget: ≤ 3 ms on one core), for
//! a dot of 30, 60, 120 and 200 px, sharp and blurred (σ = 2 px) with a 30 % light gradient,
//! and a mark-free frame (the coarse search alone); a ring and a cross of 60 px.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use vision_locate::render::{render, Depth, Lighting, PlacedMark, Scene, Shape};
use vision_locate::{locate, Located, MarkKind, MarkSpec, OwnedImage, Polarity};

fn frame(shape: Option<Shape>, blur: f64, gradient: f64) -> OwnedImage {
    render(&Scene {
        marks: shape.map(|shape| PlacedMark { shape, x: 640.37, y: 480.81, reflectance: 0.1 }).into_iter().collect(),
        blur_sigma: blur,
        noise_sigma: 2.0,
        lighting: Lighting { level: 0.95, gradient, angle: 0.4 },
        seed: 27,
        ..Scene::blank(1280, 960, Depth::Eight)
    })
    .expect("valid scene")
}

fn dots(c: &mut Criterion) {
    let mut group = c.benchmark_group("locate/dot-1280x960");
    for d in [30.0, 60.0, 120.0, 200.0] {
        let spec = MarkSpec::new(MarkKind::Dot, d, 0.25, Polarity::DarkOnLight).expect("valid spec");
        for (label, blur, gradient) in [("sharp", 0.0, 0.0), ("blur2-grad30", 2.0, 0.3)] {
            let img = frame(Some(Shape::Dot { diameter: d }), blur, gradient);
            assert!(matches!(locate(&img.view(), &spec), Ok(Located::Found(_))));
            group.bench_with_input(BenchmarkId::new(label, d), &img, |b, img| {
                b.iter(|| black_box(locate(black_box(&img.view()), &spec)))
            });
        }
        let blank = frame(None, 1.0, 0.3);
        group.bench_with_input(BenchmarkId::new("no-mark", d), &blank, |b, img| {
            b.iter(|| black_box(locate(black_box(&img.view()), &spec)))
        });
    }
    group.finish();
}

fn other_kinds(c: &mut Criterion) {
    let mut group = c.benchmark_group("locate/kinds-1280x960");
    for (kind, shape) in [
        (MarkKind::Ring, Shape::Ring { diameter: 60.0, line_width: 12.0 }),
        (MarkKind::Cross, Shape::Cross { length: 60.0, bar_width: 12.0, angle: 0.3 }),
    ] {
        let spec = MarkSpec::new(kind, 60.0, 0.25, Polarity::DarkOnLight).expect("valid spec");
        let img = frame(Some(shape), 1.0, 0.3);
        assert!(matches!(locate(&img.view(), &spec), Ok(Located::Found(_))));
        group.bench_function(format!("{kind:?}-60"), |b| b.iter(|| black_box(locate(black_box(&img.view()), &spec))));
    }
    group.finish();
}

criterion_group!(benches, dots, other_kinds);
criterion_main!(benches);
