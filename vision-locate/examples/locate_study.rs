//! Accuracy study of `vision-locate` on rendered 1280 × 960 8-bit frames with known truth.
//!
//! `cargo run --release -p vision-locate --example locate_study -- [N] [DIR]`
//!
//! For each condition, N frames (default 100) with a random sub-pixel centre, diameter and
//! (where the condition says so) blur, light gradient and JPEG q75. Prints bias and RMS of the
//! centre per condition beside the Cramér–Rao bound of the rendered noise, and the time per
//! frame. With DIR, also writes every frame as PGM (the JPEG round trip already applied) and
//! `truth.csv`, for `benches/locate/opencv_study.py` to run OpenCV on the same images.

use std::io::Write;
use std::time::Instant;

use image::codecs::jpeg::JpegEncoder;
use vision_locate::render::{render, Depth, Lighting, PlacedMark, Scene, Shape, SplitMix64};
use vision_locate::{dot_crb, locate, GrayImage, Located, MarkKind, MarkSpec, OwnedPixels, Pixels, Polarity};

struct Condition {
    name: &'static str,
    diameter: (f64, f64),
    blur: (f64, f64),
    gradient: f64,
    jpeg: bool,
}

const W: usize = 1280;
const H: usize = 960;
const NOISE: f64 = 2.0;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(100);
    let dir = args.get(2).map(std::path::PathBuf::from);
    let conditions = [
        Condition { name: "clean d30", diameter: (30.0, 30.0), blur: (0.0, 0.0), gradient: 0.0, jpeg: false },
        Condition { name: "clean d60", diameter: (60.0, 60.0), blur: (0.0, 0.0), gradient: 0.0, jpeg: false },
        Condition { name: "clean d120", diameter: (120.0, 120.0), blur: (0.0, 0.0), gradient: 0.0, jpeg: false },
        Condition { name: "clean d200", diameter: (200.0, 200.0), blur: (0.0, 0.0), gradient: 0.0, jpeg: false },
        Condition { name: "blur1 d30-200", diameter: (30.0, 200.0), blur: (1.0, 1.0), gradient: 0.0, jpeg: false },
        Condition { name: "blur0-3 grad30", diameter: (30.0, 200.0), blur: (0.0, 3.0), gradient: 0.3, jpeg: false },
        Condition {
            name: "hard: blur0-3 grad30 jpeg75",
            diameter: (30.0, 200.0),
            blur: (0.0, 3.0),
            gradient: 0.3,
            jpeg: true,
        },
        Condition { name: "hard d30", diameter: (30.0, 30.0), blur: (0.0, 3.0), gradient: 0.3, jpeg: true },
        Condition { name: "hard d200", diameter: (200.0, 200.0), blur: (0.0, 3.0), gradient: 0.3, jpeg: true },
    ];
    let mut truth = dir.as_ref().map(|d| {
        std::fs::create_dir_all(d).expect("create the image folder");
        let mut f = std::fs::File::create(d.join("truth.csv")).expect("create truth.csv");
        writeln!(f, "file,condition,x,y,diameter,blur,gradient,jpeg").unwrap();
        f
    });
    println!(
        "{:<30} {:>5} {:>9} {:>9} {:>9} {:>9} {:>7} {:>9} {:>8}",
        "condition", "found", "bias x", "bias y", "rms", "crb", "rms/crb", "max err", "ms/frame"
    );
    let mut rng = SplitMix64::new(27);
    for (ci, c) in conditions.iter().enumerate() {
        let (mut ex, mut ey, mut e2, mut crb2, mut emax) = (0.0, 0.0, 0.0, 0.0, 0.0f64);
        let (mut found, mut time) = (0usize, 0.0);
        let mut misses = Vec::new();
        for k in 0..n {
            let d = rng.range(c.diameter.0, c.diameter.1);
            let blur = rng.range(c.blur.0, c.blur.1);
            let m = d / 2.0 + 10.0;
            let (x, y) = (rng.range(m, W as f64 - m), rng.range(m, H as f64 - m));
            let scene = Scene {
                marks: vec![PlacedMark { shape: Shape::Dot { diameter: d }, x, y, reflectance: 0.1 }],
                blur_sigma: blur,
                noise_sigma: NOISE,
                lighting: Lighting {
                    level: 0.95,
                    gradient: c.gradient,
                    angle: rng.range(-std::f64::consts::PI, std::f64::consts::PI),
                },
                seed: rng.next_u64(),
                ..Scene::blank(W, H, Depth::Eight)
            };
            let img = render(&scene).expect("valid scene");
            let OwnedPixels::Gray8(mut px) = img.into_pixels() else { unreachable!("8-bit scene") };
            if c.jpeg {
                px = jpeg_round_trip(&px, 75);
            }
            if let Some(f) = truth.as_mut() {
                let name = format!("c{ci}_{k:04}.pgm");
                write_pgm(&dir.as_ref().unwrap().join(&name), &px);
                writeln!(f, "{name},{},{x},{y},{d},{blur},{},{}", c.name, c.gradient, c.jpeg).unwrap();
            }
            let view = GrayImage::new(W, H, Pixels::Gray8(&px)).unwrap();
            let spec = MarkSpec::new(MarkKind::Dot, d, 0.25, Polarity::DarkOnLight).unwrap();
            let t0 = Instant::now();
            let res = locate(&view, &spec).unwrap();
            time += t0.elapsed().as_secs_f64();
            // CRB of the rendered noise for this frame (the pixel's square is in the model; the
            // blur is the renderer's, see `rendered_blur`).
            let contrast = 0.95 * 255.0 * (0.1 - 0.8);
            let (cx, _) = dot_crb(d, rendered_blur(blur), 0.8 * 0.95 * 255.0, contrast, NOISE).unwrap();
            crb2 += cx * cx;
            match res {
                Located::Found(mk) => {
                    found += 1;
                    let (dx, dy) = (mk.x - x, mk.y - y);
                    ex += dx;
                    ey += dy;
                    e2 += (dx * dx + dy * dy) / 2.0;
                    emax = emax.max(dx.hypot(dy));
                }
                Located::NotFound(r) => misses.push(format!("d {d:.1} blur {blur:.2}: {r:?}")),
            }
        }
        let nf = found.max(1) as f64;
        let rms = (e2 / nf).sqrt();
        let crb = (crb2 / n as f64).sqrt();
        println!(
            "{:<30} {:>5} {:>9.5} {:>9.5} {:>9.5} {:>9.5} {:>7.2} {:>9.5} {:>8.2}",
            c.name,
            format!("{found}/{n}"),
            ex / nf,
            ey / nf,
            rms,
            crb,
            rms / crb,
            emax,
            1e3 * time / n as f64
        );
        for m in misses.iter().take(3) {
            println!("    miss: {m}");
        }
    }
}

/// The σ (px) of the blur the renderer really applies for `sigma`: its Gaussian is sampled at
/// whole pixels out to 4σ and normalised, which below σ ≈ 0.7 px blurs less than the continuous
/// Gaussian (σ = 0.5 → 0.46, 0.3 → 0.09). The bound takes the Gaussian of the same variance.
#[expect(clippy::cast_possible_truncation, reason = "study values are small and whole")]
fn rendered_blur(sigma: f64) -> f64 {
    if sigma <= 0.0 {
        return 0.0;
    }
    let r = (4.0 * sigma).ceil() as i64;
    let (mut sum, mut second) = (0.0, 0.0);
    for i in -r..=r {
        let k = (-((i * i) as f64) / (2.0 * sigma * sigma)).exp();
        sum += k;
        second += (i * i) as f64 * k;
    }
    (second / sum).sqrt()
}

#[expect(clippy::cast_possible_truncation, reason = "study values are small and whole")]
fn jpeg_round_trip(px: &[u8], quality: u8) -> Vec<u8> {
    let mut buf = Vec::new();
    JpegEncoder::new_with_quality(&mut buf, quality)
        .encode(px, W as u32, H as u32, image::ExtendedColorType::L8)
        .expect("encode JPEG");
    let img = image::load_from_memory_with_format(&buf, image::ImageFormat::Jpeg).expect("decode JPEG");
    img.into_luma8().into_raw()
}

fn write_pgm(path: &std::path::Path, px: &[u8]) {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).expect("create PGM"));
    write!(f, "P5\n{W} {H}\n255\n").unwrap();
    f.write_all(px).unwrap();
}
