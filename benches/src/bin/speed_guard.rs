//! The workloads `scripts/speed-guard` counts instructions of under callgrind: each runs in its
//! own `#[inline(never)]` function `guard_<case>` (the script collects only inside those, with
//! `--toggle-collect`), and the binary prints each case's name and how many operations its
//! function performs, so the script can divide. Build with
//! `cargo build --release -p vision-benches --features guard --bin speed-guard`.
//!
//! Wall-clock time is not measured here: an instruction count does not move with the load of
//! other processes, so it can fail a build without a timing assertion.

use std::hint::black_box;

use vision_benches::{gcode_program, marks};
use vision_gcode::parse::Parser;
use vision_gcode::{Event, Interpreter, InterpreterConfig};
use vision_math::{fit_rectangle, fit_similarity, Lens, Matrix2, Model, PixelChain, Point2, Remap, Vector2};

/// Fits per fit case (the loop's own cost, a few instructions, is part of each budget).
const FITS: usize = 1_000;
/// Pixel-chain conversions.
const PIXELS: usize = 10_000;
/// Lines of the generated G-code program (`vision_benches::gcode_program`, as in the
/// benchmarks).
const LINES: usize = 20_000;

#[inline(never)]
fn guard_similarity_transform(c: &[Point2<f64>], o: &[Point2<f64>]) {
    for _ in 0..FITS {
        let _ = black_box(Model::Similarity.transform(black_box(c), black_box(o)));
    }
}

#[inline(never)]
fn guard_similarity_fit(c: &[Point2<f64>], o: &[Point2<f64>]) {
    for _ in 0..FITS {
        let _ = black_box(fit_similarity(black_box(c), black_box(o)));
    }
}

#[inline(never)]
fn guard_rectangle_fit(c: &[Point2<f64>], o: &[Point2<f64>]) {
    for _ in 0..FITS {
        let _ = black_box(fit_rectangle(black_box(c), black_box(o)));
    }
}

#[inline(never)]
fn guard_pixel_chain(chain: &PixelChain, at: Point2<f64>, px: Point2<f64>) {
    for _ in 0..PIXELS {
        black_box(chain.observed(black_box(at), black_box(px)));
    }
}

/// `delta`, not `observed`: a body identical to [`guard_pixel_chain`]'s would be merged with
/// it by the compiler, and the script would find no function of this name.
#[inline(never)]
fn guard_pixel_chain_lens(chain: &PixelChain, px: Point2<f64>) {
    for _ in 0..PIXELS {
        black_box(chain.delta(black_box(px)));
    }
}

#[inline(never)]
fn guard_gcode_parse(parser: &mut Parser, text: &str) -> u64 {
    let mut words = 0u64;
    for (i, line) in text.lines().enumerate() {
        let n = u32::try_from(i + 1).unwrap_or(u32::MAX);
        words += parser.parse_line(black_box(line), n).map_or(0, |b| b.words().len() as u64);
    }
    words
}

#[inline(never)]
fn guard_gcode_interpret(interp: &mut Interpreter, text: &str) -> u64 {
    let mut events = 0u64;
    interp
        .run(black_box(text), None, &mut |e: &Event| {
            events += 1;
            black_box(e);
        })
        .expect("the generated program runs");
    events
}

fn main() {
    let (c, o) = marks(4);
    guard_similarity_transform(&c, &o);
    println!("similarity-transform {FITS}");
    guard_similarity_fit(&c, &o);
    println!("similarity-fit {FITS}");
    guard_rectangle_fit(&c, &o);
    println!("rectangle-fit {FITS}");

    // The chain of `benches/math.rs` (`pixel_chain/observed`).
    let k = Matrix2::new(0.002_03, 0.000_01, -0.000_01, 0.002_02);
    let remap = Remap { swap_xy: true, invert_x: false, invert_y: true };
    let chain = PixelChain::new(k, remap, Vector2::new(1776.0, 1776.0), Vector2::new(1.5, -2.0)).expect("valid chain");
    guard_pixel_chain(&chain, Point2::new(6.0, 4.0), Point2::new(912.25, 801.5));
    println!("pixel-chain {PIXELS}");
    // The same chain with a lens (`pixel_chain/delta_lens`).
    let lens = Lens::new([-0.10, 0.01, 0.002, -0.001], 2956.0).expect("valid lens");
    let lensed = chain.with_lens(lens).expect("the lens does not fold over the image");
    guard_pixel_chain_lens(&lensed, Point2::new(912.25, 801.5));
    println!("pixel-chain-lens {PIXELS}");

    let text = gcode_program(LINES, false);
    let mut parser = Parser::new();
    black_box(guard_gcode_parse(&mut parser, &text));
    println!("gcode-parse {LINES}");
    let mut interp = Interpreter::new(InterpreterConfig::default());
    black_box(guard_gcode_interpret(&mut interp, &text));
    println!("gcode-interpret {LINES}");
}
