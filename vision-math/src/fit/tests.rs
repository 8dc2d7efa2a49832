//! Proof of the fits: exact recovery, least-squares optimality, ordering of models, errors.

use super::*;
use crate::chain::AlignmentChain;
use nalgebra::{Matrix2, Point2, Vector2};
use proptest::prelude::*;

fn rot(theta: f64) -> Matrix2<f64> {
    let (s, c) = theta.sin_cos();
    Matrix2::new(c, -s, s, c)
}

/// A random, well-spread point set: a fat triangle plus `extra` random points, all scaled by
/// `spread` about `centre`.
fn points(spread: f64, centre: Vector2<f64>, turn: f64, extra: &[(f64, f64)]) -> Vec<Point2<f64>> {
    let base = [(-1.0, -0.8), (1.0, -0.6), (0.1, 1.0)];
    let r = rot(turn);
    base.iter().chain(extra).map(|&(x, y)| Point2::from(centre + r * Vector2::new(x, y) * spread)).collect()
}

fn truth_map(theta: f64, sx: f64, sy: f64, shift: Vector2<f64>) -> impl Fn(&Point2<f64>) -> Point2<f64> {
    let l = rot(theta) * Matrix2::new(sx, 0.0, 0.0, sy);
    move |p| Point2::from(l * p.coords + shift)
}

fn angle_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    d.min(std::f64::consts::TAU - d)
}

/// Rectangle objective Σ‖R·S·nᵢ + b − oᵢ‖².
fn objective(theta: f64, sx: f64, sy: f64, b: Vector2<f64>, n: &[Point2<f64>], o: &[Point2<f64>]) -> f64 {
    let l = rot(theta) * Matrix2::new(sx, 0.0, 0.0, sy);
    n.iter().zip(o).map(|(n, o)| (l * n.coords + b - o.coords).norm_squared()).sum()
}

type Case = (f64, f64, f64, Vector2<f64>, f64, Vector2<f64>, f64, Vec<(f64, f64)>);

fn case() -> impl Strategy<Value = Case> {
    (
        -std::f64::consts::PI..std::f64::consts::PI,
        0.5f64..2.0,
        0.5f64..2.0,
        (-1000.0f64..1000.0, -1000.0f64..1000.0).prop_map(|(x, y)| Vector2::new(x, y)),
        -3.0f64..3.0, // log10 spread: 1e-3 .. 1e3
        (-100.0f64..100.0, -100.0f64..100.0).prop_map(|(x, y)| Vector2::new(x, y)),
        -3.2f64..3.2,
        prop::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 0..61),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn exact_data_is_recovered_by_every_model((theta, sx, sy, shift, log_spread, centre, turn, extra) in case()) {
        let spread = 10f64.powf(log_spread);
        let centre = centre * spread.min(1.0);
        let n = points(spread, centre, turn, &extra);
        let tol = 1e-9;
        for model in Model::ALL {
            let (sx, sy) = match model {
                Model::Rigid => (1.0, 1.0),
                Model::Similarity => (sx, sx),
                Model::Rectangle | Model::Affine => (sx, sy),
            };
            let map = truth_map(theta, sx, sy, shift);
            let o: Vec<_> = n.iter().map(&map).collect();
            let fit = model.fit(&n, &o).expect("well-posed");
            let t = model.transform(&n, &o).expect("well-posed");
            prop_assert_eq!(t, fit.transform);
            prop_assert!(angle_diff(fit.transform.theta_rad(), theta) <= tol, "{model}: θ {} vs {theta}", fit.transform.theta_rad());
            prop_assert!((fit.transform.scale.x - sx).abs() <= tol * sx, "{model}: sx {} vs {sx}", fit.transform.scale.x);
            prop_assert!((fit.transform.scale.y - sy).abs() <= tol * sy, "{model}: sy {} vs {sy}", fit.transform.scale.y);
            prop_assert!(fit.transform.shear.abs() <= tol, "{model}: shear {}", fit.transform.shear);
            let size = spread * sx.max(sy) + shift.norm() + centre.norm() * 2.0;
            prop_assert!((fit.transform.offset() - shift).norm() <= tol * size, "{model}: offset {:?} vs {shift:?}", fit.transform.offset());
            prop_assert!(fit.rms <= tol * spread * 2.0, "{model}: rms {}", fit.rms);
            // The G51 → G68 → G52 chain lands every commanded point on its observed point.
            if let Some(chain) = fit.transform.chain() {
                for (ni, oi) in n.iter().zip(&o) {
                    let d = (chain.apply(*ni) - oi).norm();
                    prop_assert!(d <= tol * size, "{model}: chain misses by {d}");
                }
            } else {
                prop_assert_eq!(model, Model::Affine);
            }
        }
    }

    #[test]
    fn noisy_rectangle_lies_between_affine_and_similarity_and_is_stationary(
        (theta, sx, sy, shift, _log_spread, centre, turn, extra) in case(),
        noise in prop::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 64),
        sigma in 1e-4f64..1e-1,
    ) {
        let spread = 10.0;
        let n = points(spread, centre * 0.1, turn, &extra);
        let map = truth_map(theta, sx, sy, shift);
        let o: Vec<_> = n.iter().zip(&noise).map(|(p, e)| map(p) + Vector2::new(e.0, e.1) * sigma).collect();
        let rect = fit_rectangle(&n, &o).expect("rectangle");
        let aff = fit_affine(&n, &o).expect("affine");
        let sim = fit_similarity(&n, &o).expect("similarity");
        let slack = 1e-12 * spread;
        prop_assert!(aff.rms <= rect.rms + slack, "affine {} > rectangle {}", aff.rms, rect.rms);
        prop_assert!(rect.rms <= sim.rms + slack, "rectangle {} > similarity {}", rect.rms, sim.rms);
        // Gradient of the rectangle objective at the solution, each component normalised by its
        // Cauchy–Schwarz bound, is zero.
        let (c, s) = (rect.transform.rotation.re, rect.transform.rotation.im);
        let l = rect.transform.linear();
        let dr = Matrix2::new(-s, -c, c, -s) * Matrix2::new(rect.transform.scale.x, 0.0, 0.0, rect.transform.scale.y);
        let (mut g_theta, mut g_sx, mut g_sy, mut g_b) = (0.0, 0.0, 0.0, Vector2::zeros());
        let (mut r_norm2, mut a_norm2, mut ax2, mut ay2) = (0.0, 0.0, 0.0, 0.0);
        for (ni, oi) in n.iter().zip(&o) {
            let a = ni - rect.transform.commanded_centroid;
            let r = l * a - (oi - rect.transform.observed_centroid);
            g_theta += r.dot(&(dr * a));
            g_sx += a.x * r.dot(&Vector2::new(c, s));
            g_sy += a.y * r.dot(&Vector2::new(-s, c));
            g_b += r;
            r_norm2 += r.norm_squared();
            a_norm2 += (dr * a).norm_squared();
            ax2 += a.x * a.x;
            ay2 += a.y * a.y;
        }
        let rn = r_norm2.sqrt();
        prop_assert!(g_theta.abs() <= 1e-9 * rn * a_norm2.sqrt(), "dF/dθ = {g_theta}");
        prop_assert!(g_sx.abs() <= 1e-9 * rn * ax2.sqrt(), "dF/dsx = {g_sx}");
        prop_assert!(g_sy.abs() <= 1e-9 * rn * ay2.sqrt(), "dF/dsy = {g_sy}");
        let root_n = (n.len() as f64).sqrt();
        prop_assert!(g_b.norm() <= 1e-9 * rn * root_n + 1e-12 * spread, "dF/db = {g_b:?}");
    }

    /// The RMS and the largest residual, whichever loop computed them (a plain one below eight
    /// points, a paired one from eight, odd counts with a last single pair), are those of
    /// `Fit::residuals`, up to rounding.
    #[test]
    fn rms_and_largest_residual_match_the_residuals(
        (theta, sx, sy, shift, _log_spread, centre, turn, extra) in case(),
        noise in prop::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 64),
        sigma in 1e-4f64..1e-1,
    ) {
        let n = points(10.0, centre * 0.1, turn, &extra);
        let map = truth_map(theta, sx, sy, shift);
        let o: Vec<_> = n.iter().zip(&noise).map(|(p, e)| map(p) + Vector2::new(e.0, e.1) * sigma).collect();
        for model in Model::ALL {
            let fit = model.fit(&n, &o).expect("well-posed");
            let r: Vec<f64> = fit.residuals(&n, &o).iter().map(nalgebra::Matrix::norm).collect();
            let rms = (r.iter().map(|r| r * r).sum::<f64>() / r.len() as f64).sqrt();
            let largest = r.iter().fold(0.0, |m: f64, &r| m.max(r));
            let tol = 1e-9 * (sigma + 1e-9);
            prop_assert!((fit.rms - rms).abs() <= tol, "{model}, {} points: rms {} vs {rms}", n.len(), fit.rms);
            prop_assert!((fit.max_residual - largest).abs() <= tol, "{model}, {} points: largest {} vs {largest}", n.len(), fit.max_residual);
        }
    }

    #[test]
    fn linear_solve_recovers_any_well_conditioned_matrix(
        m in prop::array::uniform4(-2.0f64..2.0),
        p in prop::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 0..30),
    ) {
        let m = Matrix2::new(m[0], m[1], m[2], m[3]);
        let mut ps = vec![Vector2::new(1.0, 0.1), Vector2::new(-0.2, 1.0)];
        ps.extend(p.iter().map(|&(x, y)| Vector2::new(x, y)));
        let qs: Vec<_> = ps.iter().map(|p| m * p).collect();
        let fit = solve_linear(&ps, &qs).expect("spanning");
        prop_assert!((fit.m - m).norm() <= 1e-12 * (1.0 + m.norm()), "{:?} vs {m:?}", fit.m);
        prop_assert!(fit.rms <= 1e-12 * (1.0 + m.norm()));
    }

    #[test]
    fn emitted_text_executes_within_a_micro_unit(
        (theta, sx, sy, shift, _log_spread, centre, turn, extra) in case(),
    ) {
        // Parts up to ±1000 units: rounding the emitted words moves no point by more than 1e-6.
        let n = points(300.0, centre, turn, &extra);
        let map = truth_map(theta, sx, sy, shift);
        let o: Vec<_> = n.iter().map(&map).collect();
        let fit = fit_rectangle(&n, &o).expect("rectangle");
        let chain = fit.transform.chain().expect("chain");
        let parsed = written(&chain);
        for (ni, oi) in n.iter().zip(&o) {
            let d = (parsed.apply(*ni) - oi).norm();
            prop_assert!(d <= 1e-6, "rounded chain misses by {d}: {chain:?}");
        }
    }
}

/// The chain as its lines write it: each number through its fixed decimals and read back (a
/// reader independent of [`AlignmentChain::as_emitted`]).
fn written(chain: &AlignmentChain) -> AlignmentChain {
    use crate::chain::{fixed, ANGLE_DECIMALS, POSITION_DECIMALS, SCALE_DECIMALS};
    let read = |v: f64, decimals: usize| fixed(v, decimals).parse::<f64>().expect("a number");
    let p = |v: f64| read(v, POSITION_DECIMALS);
    AlignmentChain {
        shift: Vector2::new(p(chain.shift.x), p(chain.shift.y)),
        center: Point2::new(p(chain.center.x), p(chain.center.y)),
        rotation_deg: read(chain.rotation_deg, ANGLE_DECIMALS),
        scale: Vector2::new(read(chain.scale.x, SCALE_DECIMALS), read(chain.scale.y, SCALE_DECIMALS)),
    }
}

#[test]
fn rectangle_is_the_global_minimum_over_theta() {
    // Noisy, anisotropic data where "affine with the shear dropped" is visibly worse.
    let n = [
        Point2::new(0.0, 0.0),
        Point2::new(6.0, 0.0),
        Point2::new(6.0, 4.0),
        Point2::new(0.0, 4.0),
        Point2::new(3.0, 2.2),
    ];
    let o = [
        Point2::new(0.11, 0.04),
        Point2::new(6.13, 0.21),
        Point2::new(5.99, 4.26),
        Point2::new(-0.05, 4.09),
        Point2::new(3.06, 2.31),
    ];
    // The rectangle objective at a solution's θ, scales and offset (its shear left out).
    let at = |t: &Transform| objective(t.theta_rad(), t.scale.x, t.scale.y, t.offset(), &n, &o);
    let fit = fit_rectangle(&n, &o).expect("rectangle");
    let best = at(&fit.transform);
    // For every θ on a fine grid, the best sx, sy, b (linear least squares) do no better.
    let (cn, co) = (fit.transform.commanded_centroid.coords, fit.transform.observed_centroid.coords);
    for i in 0..36_000 {
        let theta = f64::from(i) * std::f64::consts::TAU / 36_000.0;
        let r = rot(theta);
        let (mut nx, mut ny, mut dx, mut dy) = (0.0, 0.0, 0.0, 0.0);
        for (p, q) in n.iter().zip(&o) {
            let a = p.coords - cn;
            let u = r.transpose() * (q.coords - co);
            nx += a.x * u.x;
            ny += a.y * u.y;
            dx += a.x * a.x;
            dy += a.y * a.y;
        }
        let (sx, sy) = (nx / dx, ny / dy);
        let b = co - r * Matrix2::new(sx, 0.0, 0.0, sy) * cn;
        assert!(objective(theta, sx, sy, b, &n, &o) >= best - 1e-12, "θ = {theta} beats the closed form");
    }
    // Dropping the shear of the affine fit is not the rectangle minimum.
    let aff = fit_affine(&n, &o).expect("affine");
    assert!(at(&aff.transform) > best);
}

#[test]
fn manual_example_4_geometry() {
    // Marks at (0,0), (6,0), (6,4), (0,4); part shifted (0.1, 0.05), turned 0.5°, 0.1 % long in X.
    let n = [Point2::new(0.0, 0.0), Point2::new(6.0, 0.0), Point2::new(6.0, 4.0), Point2::new(0.0, 4.0)];
    let map = truth_map(0.5f64.to_radians(), 1.001, 1.0, Vector2::new(0.1, 0.05));
    let o: Vec<_> = n.iter().map(&map).collect();
    let fit = fit_rectangle(&n, &o).expect("rectangle");
    assert!((fit.transform.theta_deg() - 0.5).abs() < 1e-12);
    assert!((fit.transform.scale.x - 1.001).abs() < 1e-12 && (fit.transform.scale.y - 1.0).abs() < 1e-12);
    let chain = fit.transform.chain().expect("chain");
    assert!((chain.center - Point2::new(3.0, 2.0)).norm() < 1e-15, "G68 centre is the commanded centroid");
    for (ni, oi) in n.iter().zip(&o) {
        assert!((chain.apply(*ni) - oi).norm() < 1e-12);
    }
    assert_eq!(fit.residuals(&n, &o).len(), 4);
    assert!(fit.residuals(&n, &o).iter().all(|r| r.norm() < 1e-12));
}

#[test]
fn seed_sheet_1_under_a_small_rotation() {
    // Calibration sheet 1 (inches): dots at (±2.5, ±4) and the centre, lying 0.3° off square.
    let n = [
        Point2::new(-2.5, -4.0),
        Point2::new(-2.5, 4.0),
        Point2::new(2.5, 4.0),
        Point2::new(2.5, -4.0),
        Point2::new(0.0, 0.0),
    ];
    let map = truth_map(0.3f64.to_radians(), 1.0, 1.0, Vector2::new(0.02, -0.01));
    let o: Vec<_> = n.iter().map(&map).collect();
    let rigid = fit_rigid(&n, &o).expect("rigid");
    assert!((rigid.transform.theta_deg() - 0.3).abs() < 1e-12);
    assert!((rigid.transform.apply(n[4]) - o[4]).norm() < 1e-14, "the centre dot lands");
}

#[test]
fn every_error_is_typed_and_nothing_is_nan() {
    let sq = [Point2::new(0.0, 0.0), Point2::new(1.0, 0.0), Point2::new(1.0, 1.0), Point2::new(0.0, 1.0)];
    assert_eq!(
        fit_rectangle(&sq[..2], &sq[..2]),
        Err(MathError::TooFewPoints { model: "rectangle", needed: 3, got: 2 })
    );
    assert_eq!(
        fit_similarity(&sq[..1], &sq[..1]),
        Err(MathError::TooFewPoints { model: "similarity", needed: 2, got: 1 })
    );
    assert_eq!(fit_similarity(&sq, &sq[..3]), Err(MathError::LengthMismatch { commanded: 4, observed: 3 }));
    let mut bad = sq;
    bad[2].x = f64::NAN;
    assert_eq!(fit_similarity(&bad, &sq), Err(MathError::NonFinite { what: "a commanded point" }));
    assert_eq!(fit_rectangle(&sq, &bad), Err(MathError::NonFinite { what: "an observed point" }));
    bad[2].x = f64::INFINITY;
    assert_eq!(fit_affine(&sq, &bad), Err(MathError::NonFinite { what: "an observed point" }));
    let same = [Point2::new(5.0, 5.0); 4];
    for model in Model::ALL {
        assert_eq!(model.fit(&same, &sq), Err(MathError::CoincidentPoints), "{model}");
    }
    let line = [Point2::new(0.0, 0.0), Point2::new(1.0, 1.0), Point2::new(2.0, 2.0), Point2::new(3.0, 3.0 + 1e-9)];
    assert_eq!(fit_rectangle(&line, &sq), Err(MathError::CollinearPoints { model: "rectangle" }));
    assert_eq!(fit_affine(&line, &sq), Err(MathError::CollinearPoints { model: "affine" }));
    // Two marks determine a similarity; collinear marks are fine for it.
    assert!(fit_similarity(&line, &line).is_ok());
    // Observed points that collapse to one point carry no rotation.
    assert_eq!(fit_similarity(&sq, &same), Err(MathError::DegenerateObserved));
    assert_eq!(fit_rigid(&sq, &same), Err(MathError::DegenerateObserved));
    assert_eq!(fit_rectangle(&sq, &same), Err(MathError::DegenerateObserved));
    let v = [Vector2::new(1.0, 0.0), Vector2::new(2.0, 0.0)];
    assert_eq!(solve_linear(&v, &v), Err(MathError::CollinearPoints { model: "2x2 linear" }));
    assert_eq!(solve_linear(&v[..1], &v[..1]), Err(MathError::TooFewPoints { model: "2x2 linear", needed: 2, got: 1 }));
    assert_eq!(solve_linear(&[Vector2::zeros(); 2], &v), Err(MathError::CoincidentPoints));
}

proptest! {
    #[test]
    fn arbitrary_input_gives_a_fit_or_an_error_never_nan(
        n in prop::collection::vec((prop::num::f64::ANY, prop::num::f64::ANY), 0..8),
        o in prop::collection::vec((prop::num::f64::ANY, prop::num::f64::ANY), 0..8),
    ) {
        let n: Vec<_> = n.into_iter().map(|(x, y)| Point2::new(x, y)).collect();
        let o: Vec<_> = o.into_iter().map(|(x, y)| Point2::new(x, y)).collect();
        for model in Model::ALL {
            match model.transform(&n, &o) {
                Ok(t) => prop_assert!(t.scale.iter().all(|v| v.is_finite()) && t.rotation.re.is_finite()),
                Err(e) => prop_assert!(model.fit(&n, &o).is_err(), "transform refused ({e}) what fit accepted"),
            }
            if let Ok(fit) = model.fit(&n, &o) {
                prop_assert!(fit.rms.is_finite() && fit.max_residual.is_finite());
                prop_assert!(fit.transform.theta_rad().is_finite() && fit.transform.scale.iter().all(|v| v.is_finite()));
                if let Some(chain) = fit.transform.chain() {
                    prop_assert!(chain.check().is_ok());
                }
            }
        }
    }
}

#[test]
fn model_names_round_trip() {
    for m in Model::ALL {
        assert_eq!(Model::from_name(m.name()), Some(m));
        assert_eq!(Model::from_name(&m.name().to_uppercase()), Some(m));
    }
    assert_eq!(Model::from_name("projective"), None);
}

#[test]
fn collinear_observed_points_tiny_spreads_and_huge_coordinates_are_refused_for_their_reason() {
    let p = |v: &[(f64, f64)]| v.iter().map(|(x, y)| Point2::new(*x, *y)).collect::<Vec<_>>();
    let square = p(&[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]);
    // Observed on a line: X or Y scale 0 (was `G51 X0.0000000000`). A similarity fit keeps
    // its scale and shows the mismatch as residuals instead.
    let line = p(&[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)]);
    for model in [Model::Rectangle, Model::Affine] {
        let e = model.fit(&square, &line).expect_err("collinear observed");
        assert!(matches!(e, MathError::DegenerateScale { .. }), "{model:?}: {e:?}");
        assert!(model.transform(&square, &line).is_err(), "{model:?}");
    }
    // Observed 1e-15 apart: every scaling model collapses the part.
    let dot = p(&[(0.0, 0.0), (1e-15, 0.0), (0.0, 1e-15)]);
    for model in [Model::Similarity, Model::Rectangle, Model::Affine] {
        assert!(model.fit(&square, &dot).is_err(), "{model:?}");
    }
    for model in Model::ALL {
        // Commanded 1e-15 apart, near the origin: coincident, not a fit.
        assert_eq!(model.fit(&dot, &square).expect_err("coincident"), MathError::CoincidentPoints, "{model:?}");
        // Huge but finite: named as too large, not as "not a finite number".
        let huge = p(&[(0.0, 0.0), (1e200, 0.0), (0.0, 1e200)]);
        let e = model.fit(&huge, &square).expect_err("huge");
        assert!(matches!(e, MathError::CoordinateTooLarge { what: "a commanded point", .. }), "{model:?}: {e:?}");
        let e = model.fit(&square, &huge).expect_err("huge");
        assert!(matches!(e, MathError::CoordinateTooLarge { what: "an observed point", .. }), "{model:?}: {e:?}");
        assert!(e.to_string().contains("1e200"), "{e}");
    }
}

/// A coordinate for [`input_checks_keep_their_order_and_reasons`]: ordinary, huge (beyond
/// `MAX_COORDINATE`, up to near `f64::MAX`, where a sum of two overflows: still "too large",
/// never "not a finite number"), NaN or ±∞.
fn coordinate() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => -100.0..100.0f64,
        1 => (1e9f64..1e300).prop_map(|v| v * 1.000_000_1),
        1 => (1e9f64..1e300).prop_map(|v| -v * 1.000_000_1),
        1 => 1e307f64..1.7e308,
        1 => (1e307f64..1.7e308).prop_map(|v| -v),
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
    ]
}

proptest! {
    /// The input checks are one combined test with the error picked afterwards; this checks it
    /// against the rules written out one by one: a non-finite commanded point, then a
    /// non-finite observed point, then a commanded coordinate beyond `MAX_COORDINATE` (with the
    /// largest one), then an observed one; and accepted parameters have a scale in range.
    #[test]
    fn input_checks_keep_their_order_and_reasons(
        points in prop::collection::vec(((coordinate(), coordinate()), (coordinate(), coordinate())), 3..8),
    ) {
        let n: Vec<_> = points.iter().map(|((x, y), _)| Point2::new(*x, *y)).collect();
        let o: Vec<_> = points.iter().map(|(_, (x, y))| Point2::new(*x, *y)).collect();
        let finite = |p: &[Point2<f64>]| p.iter().all(|p| p.x.is_finite() && p.y.is_finite());
        let largest = |p: &[Point2<f64>]| p.iter().fold(0.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()));
        let expected = if !finite(&n) {
            Some(MathError::NonFinite { what: "a commanded point" })
        } else if !finite(&o) {
            Some(MathError::NonFinite { what: "an observed point" })
        } else if largest(&n) > MAX_COORDINATE {
            Some(MathError::CoordinateTooLarge { what: "a commanded point", value: largest(&n), limit: MAX_COORDINATE })
        } else if largest(&o) > MAX_COORDINATE {
            Some(MathError::CoordinateTooLarge { what: "an observed point", value: largest(&o), limit: MAX_COORDINATE })
        } else {
            None
        };
        for model in Model::ALL {
            let (fit, transform) = (model.fit(&n, &o), model.transform(&n, &o));
            match &expected {
                Some(e) => {
                    prop_assert_eq!(fit.as_ref().err(), Some(e), "{}", model);
                    prop_assert_eq!(transform.as_ref().err(), Some(e), "{}", model);
                }
                None => {
                    for r in [fit.map(|f| f.transform), transform] {
                        match r {
                            Ok(t) => prop_assert!(t.scale.iter().all(|s| (MIN_SCALE..=1.0 / MIN_SCALE).contains(&s.abs()))),
                            Err(e) => prop_assert!(!matches!(e, MathError::NonFinite { .. } | MathError::CoordinateTooLarge { .. }), "{model}: {e}"),
                        }
                    }
                }
            }
        }
    }
}

proptest! {
    /// Four pairs take their own straight-line moments pass; the same four pairs twice over (eight,
    /// the general pass) have the same fit, every model, up to rounding — also for coordinates
    /// near `MAX_COORDINATE`, which the four-pair pass leaves to the exact checks.
    #[test]
    fn four_pairs_fit_as_the_general_pass_does(
        (theta, sx, sy, shift, log_spread, centre, turn, _) in case(),
        fourth in (-1.0f64..1.0, -1.0f64..1.0),
        near_bound in prop::bool::ANY,
    ) {
        let (spread, centre) = if near_bound {
            (10f64.powf(log_spread + 4.0), Vector2::new(0.9 * MAX_COORDINATE, -0.7 * MAX_COORDINATE))
        } else {
            (10f64.powf(log_spread), centre)
        };
        let n = points(spread, centre, turn, &[fourth]);
        prop_assert_eq!(n.len(), 4);
        for model in Model::ALL {
            let map = truth_map(theta, sx, if model == Model::Similarity { sx } else { sy }, shift);
            // Turned about the centre, so that the observed points stay as near the bound.
            let o: Vec<_> = n.iter().map(|p| map(&(p - centre)) + centre).collect();
            let twice = |p: &[Point2<f64>]| p.iter().chain(p).copied().collect::<Vec<_>>();
            let (four, eight) = match (model.fit(&n, &o), model.fit(&twice(&n), &twice(&o))) {
                (Ok(four), Ok(eight)) => (four.transform, eight.transform),
                (four, eight) => {
                    prop_assert_eq!(four.err(), eight.err(), "{}", model);
                    continue;
                }
            };
            prop_assert_eq!(model.transform(&n, &o), Ok(four), "{}", model);
            let near = |a: Point2<f64>, b: Point2<f64>| (a - b).norm() <= 1e-15 * (a.coords.norm() + spread);
            prop_assert!(near(four.commanded_centroid, eight.commanded_centroid), "{}", model);
            prop_assert!(near(four.observed_centroid, eight.observed_centroid), "{}", model);
            // Centring against the centroid or against the first point leaves errors of the
            // order of ε·|centroid|/spread in the parameters.
            let tol = 1e-13 * (1.0 + centre.norm() / spread);
            prop_assert!(angle_diff(four.theta_rad(), eight.theta_rad()) <= tol, "{}: θ {} vs {}", model, four.theta_rad(), eight.theta_rad());
            prop_assert!((four.scale - eight.scale).norm() <= tol, "{}: scale {} vs {}", model, four.scale, eight.scale);
            prop_assert!((four.shear - eight.shear).abs() <= tol, "{}: shear {} vs {}", model, four.shear, eight.shear);
        }
    }
}

#[test]
fn four_pairs_at_the_coordinate_bound() {
    let p = |v: &[(f64, f64)]| v.iter().map(|(x, y)| Point2::new(*x, *y)).collect::<Vec<_>>();
    let m = MAX_COORDINATE;
    // Every coordinate at ±MAX_COORDINATE: beyond the four-pair pass's quick bound, accepted by
    // the exact check.
    let corners = p(&[(-m, -m), (m, -m), (m, m), (-m, m)]);
    let half = p(&[(-0.5 * m, -0.5 * m), (0.5 * m, -0.5 * m), (0.5 * m, 0.5 * m), (-0.5 * m, 0.5 * m)]);
    let t = Model::Similarity.transform(&corners, &half).expect("at the bound");
    assert!((t.scale.x - 0.5).abs() < 1e-15 && t.theta_rad().abs() < 1e-15, "{t:?}");
    assert_eq!(Model::Similarity.transform(&half, &corners).map(|t| t.scale.x), Ok(2.0));
    // One coordinate past it, commanded then observed.
    let mut over = corners.clone();
    over[2].y = m * (1.0 + f64::EPSILON);
    for model in Model::ALL {
        let e = model.transform(&over, &half).expect_err("commanded too large");
        assert!(matches!(e, MathError::CoordinateTooLarge { what: "a commanded point", .. }), "{model}: {e:?}");
        let e = model.fit(&half, &over).expect_err("observed too large");
        assert!(matches!(e, MathError::CoordinateTooLarge { what: "an observed point", .. }), "{model}: {e:?}");
    }
}
