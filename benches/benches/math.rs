#![expect(missing_docs, reason = "criterion_group!/criterion_main! generate undocumented items.")]
//! vision-math: fits at N = 3, 4, 16, 1000, the pixel chain, and the comparisons with an
//! SVD-based Umeyama (nalgebra) and a dense QR least-squares solve (faer).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Bencher, BenchmarkId, Criterion};
use faer::linalg::solvers::SolveLstsq;
use nalgebra::{Matrix2, Point2, Vector2};
use vision_benches::marks;
use vision_math::{
    fit_affine, fit_rectangle, fit_rigid, fit_similarity, Lens, MathError, Model, PixelChain, Remap, Transform,
};

const SIZES: [usize; 4] = [3, 4, 16, 1000];

/// Times `routine`, passing its whole result through `std::hint::black_box`.
///
/// `Bencher::iter` alone would hand the result to criterion 0.5's own `black_box`, a volatile
/// read that copies it field by field: for a ~100-byte `Result<Transform, MathError>` that costs
/// more than the differences being measured (see `harness/…` and `benches/README.md`).
fn run<O>(b: &mut Bencher<'_>, mut routine: impl FnMut() -> O) {
    b.iter(|| {
        black_box(routine());
    });
}

/// What the harness itself costs: a routine that only builds a fit-sized result from its
/// input, consumed by criterion's `iter` as-is and through [`run`].
fn harness(c: &mut Criterion) {
    let (cmd, obs) = marks(4);
    let seed = Model::Similarity.transform(&cmd, &obs).expect("valid");
    let only_build = |cmd: &[Point2<f64>], obs: &[Point2<f64>]| -> Result<Transform, MathError> {
        if cmd.len() != obs.len() {
            return Err(MathError::LengthMismatch { commanded: cmd.len(), observed: obs.len() });
        }
        Ok(Transform { commanded_centroid: cmd[0], observed_centroid: obs[0], ..seed })
    };
    let mut group = c.benchmark_group("harness/build-result");
    group.bench_function("criterion-iter", |b| b.iter(|| only_build(black_box(&cmd), black_box(&obs))));
    group.bench_function("std-black-box", |b| run(b, || only_build(black_box(&cmd), black_box(&obs))));
    group.finish();
}

fn fits(c: &mut Criterion) {
    for (name, f) in [
        ("similarity", fit_similarity as fn(&[Point2<f64>], &[Point2<f64>]) -> _),
        ("rectangle", fit_rectangle),
        ("rigid", fit_rigid),
        ("affine", fit_affine),
    ] {
        let mut group = c.benchmark_group(format!("fit/{name}"));
        for n in SIZES {
            let (cmd, obs) = marks(n);
            group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
                run(b, || f(black_box(&cmd), black_box(&obs)));
            });
        }
        group.finish();
    }
    for model in [Model::Similarity, Model::Rectangle] {
        let mut group = c.benchmark_group(format!("transform/{}", model.name()));
        for n in SIZES {
            let (cmd, obs) = marks(n);
            group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
                run(b, || model.transform(black_box(&cmd), black_box(&obs)));
            });
        }
        group.finish();
    }
}

/// Umeyama's similarity through a 2×2 SVD, as Eigen's `umeyama` and most libraries do it.
fn umeyama_svd(cmd: &[Point2<f64>], obs: &[Point2<f64>]) -> (Matrix2<f64>, Vector2<f64>) {
    let inv = 1.0 / cmd.len() as f64;
    let cn = cmd.iter().fold(Vector2::zeros(), |a, p| a + p.coords) * inv;
    let co = obs.iter().fold(Vector2::zeros(), |a, p| a + p.coords) * inv;
    let mut cov = Matrix2::zeros();
    let mut var = 0.0;
    for (n, o) in cmd.iter().zip(obs) {
        let a = n.coords - cn;
        cov += (o.coords - co) * a.transpose();
        var += a.norm_squared();
    }
    let svd = cov.svd(true, true);
    let (u, v_t) = (svd.u.unwrap_or_default(), svd.v_t.unwrap_or_default());
    let mut d = Matrix2::identity();
    if (u * v_t).determinant() < 0.0 {
        d[(1, 1)] = -1.0;
    }
    let r = u * d * v_t;
    let scale = (svd.singular_values[0] + d[(1, 1)] * svd.singular_values[1]) / var;
    let l = r * scale;
    (l, co - l * cn)
}

/// The affine fit as a dense least-squares problem (2N × 6) solved by faer's QR.
fn affine_faer(cmd: &[Point2<f64>], obs: &[Point2<f64>]) -> faer::Mat<f64> {
    let n = cmd.len();
    let a = faer::Mat::from_fn(2 * n, 6, |i, j| {
        let p = cmd[i / 2];
        match (i % 2, j) {
            (0, 0) | (1, 3) => p.x,
            (0, 1) | (1, 4) => p.y,
            (0, 2) | (1, 5) => 1.0,
            _ => 0.0,
        }
    });
    let b = faer::Mat::from_fn(2 * n, 1, |i, _| if i % 2 == 0 { obs[i / 2].x } else { obs[i / 2].y });
    a.qr().solve_lstsq(&b)
}

fn comparisons(c: &mut Criterion) {
    let mut group = c.benchmark_group("compare/similarity");
    for n in SIZES {
        let (cmd, obs) = marks(n);
        group.bench_with_input(BenchmarkId::new("closed_form", n), &n, |b, _| {
            run(b, || fit_similarity(black_box(&cmd), black_box(&obs)));
        });
        group.bench_with_input(BenchmarkId::new("nalgebra_svd_umeyama", n), &n, |b, _| {
            run(b, || umeyama_svd(black_box(&cmd), black_box(&obs)));
        });
    }
    group.finish();
    let mut group = c.benchmark_group("compare/affine");
    for n in SIZES {
        let (cmd, obs) = marks(n);
        group.bench_with_input(BenchmarkId::new("closed_form", n), &n, |b, _| {
            run(b, || fit_affine(black_box(&cmd), black_box(&obs)));
        });
        group.bench_with_input(BenchmarkId::new("faer_qr_lstsq", n), &n, |b, _| {
            run(b, || affine_faer(black_box(&cmd), black_box(&obs)));
        });
    }
    group.finish();
}

fn pixel_chain(c: &mut Criterion) {
    let k = Matrix2::new(0.002_03, 0.000_01, -0.000_01, 0.002_02);
    let remap = Remap { swap_xy: true, invert_x: false, invert_y: true };
    let chain = PixelChain::new(k, remap, Vector2::new(1776.0, 1776.0), Vector2::new(1.5, -2.0)).expect("valid");
    let px = Point2::new(912.25, 801.5);
    let at = Point2::new(6.0, 4.0);
    c.bench_function("pixel_chain/observed", |b| run(b, || chain.observed(black_box(at), black_box(px))));
    c.bench_function("pixel_chain/delta", |b| run(b, || chain.delta(black_box(px))));
    // The same chain with a barrel lens on the built-in camera (f = 6 in / 0.00203 in/px): the
    // undistortion's Newton steps are the whole difference.
    let lens = Lens::new([-0.10, 0.01, 0.002, -0.001], 2956.0).expect("valid lens");
    let lensed = chain.with_lens(lens).expect("the lens does not fold over the image");
    c.bench_function("pixel_chain/delta_lens", |b| run(b, || lensed.delta(black_box(px))));
    c.bench_function("pixel_chain/observed_lens", |b| run(b, || lensed.observed(black_box(at), black_box(px))));
    c.bench_function("pixel_chain/native_pixels", |b| {
        run(b, || chain.native_pixels(black_box(Vector2::new(0.1, -0.2))));
    });
    c.bench_function("pixel_chain/new", |b| {
        run(b, || PixelChain::new(black_box(k), remap, Vector2::new(1776.0, 1776.0), Vector2::zeros()));
    });
}

criterion_group!(benches, harness, fits, comparisons, pixel_chain);
criterion_main!(benches);
