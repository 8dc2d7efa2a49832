//! How good a fit is beyond its residuals: the error it predicts where the part is cut, and the
//! one mark whose residual does not belong with the others.
//!
//! # Predicted error
//!
//! The fitted map is `m(p) = R(θ)·U·(p − n̄) + ō` with the model's parameters (rigid: θ;
//! similarity: θ, s; rectangle: θ, sx, sy; affine: the four entries of `L`) and the observed
//! centroid `ō`. With independent noise of standard deviation σ on every observed coordinate,
//! least squares gives the parameters the covariance `σ²·(JᵀJ)⁻¹` (`J` the Jacobian of the
//! model at the marks), and a point `p` of the part is mapped with the 2×2 covariance
//! `Σ(p) = J(p)·σ²(JᵀJ)⁻¹·J(p)ᵀ`. Reported, at the worst point of the region given:
//! * `sigma`: `√trace Σ(p)`, the root-mean-square length of the error vector (1σ);
//! * `bound99`: a radius that holds the **largest** error over the region with at least 99 %
//!   probability.
//!
//! The error is affine in `p` for a given set of noisy marks, so its largest length over a
//! convex region lies at a corner, and so do the largest `√trace Σ` and `λmax Σ`: pass the
//! corners of the part. With `m` corners, each corner's error stays inside
//! `√(λmax(Σ)·q)`, `q = −2·ln(0.01/m)` (the χ²₂ quantile at `1 − 0.01/m`), with probability
//! `1 − 0.01/m` at least (its ellipse fits in that circle), so all of them together, and the
//! largest, with at least 99 % (Bonferroni). This is the fit's own error only: a wrong K, a
//! wrong camera offset or a part that moved are not in it.
//!
//! The one mark that does not belong with the others: [`find_outlier`].

use nalgebra::{DMatrix, Matrix2, Point2, Vector2};

use super::{Model, Transform};
use crate::MathError;

/// The error a fit predicts over a region, machine units (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prediction {
    /// Root-mean-square length of the error vector at the worst point, 1σ.
    pub sigma: f64,
    /// Radius that holds the largest error over the region with ≥ 99 % probability.
    pub bound99: f64,
}

/// An error the marks of a fit share (see [`Transform::predict_shared`]): mark `i` is off by
/// `δ·along[i]`, one `δ` of standard deviation `sigma` (dimensionless) for all marks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shared<'a> {
    /// One vector per mark, in the order of the commanded points (machine units per unit `δ`).
    pub along: &'a [Vector2<f64>],
    /// The standard deviation of `δ`.
    pub sigma: f64,
}

impl Model {
    /// Free parameters of the linear part (besides the 2 of the shift).
    #[must_use]
    pub fn linear_parameters(self) -> usize {
        match self {
            Model::Rigid => 1,
            Model::Similarity => 2,
            Model::Rectangle => 3,
            Model::Affine => 4,
        }
    }

    /// Free parameters of the whole model (the shift included).
    #[must_use]
    pub fn parameters(self) -> usize {
        self.linear_parameters() + 2
    }
}

impl Transform {
    /// The derivatives of the mapped point `m(p)` by the model's parameters: one 2-vector per
    /// parameter, the shift's two last.
    fn jacobian(&self, p: Point2<f64>) -> Vec<Vector2<f64>> {
        let a = p - self.commanded_centroid;
        let r = self.rotation.to_rotation_matrix().into_inner();
        let perp = Matrix2::new(0.0, -1.0, 1.0, 0.0);
        let u = Matrix2::new(self.scale.x, self.shear, 0.0, self.scale.y);
        let d_theta = r * perp * u * a;
        let mut out = match self.model {
            Model::Rigid => vec![d_theta],
            Model::Similarity => vec![d_theta, r * a],
            Model::Rectangle => vec![d_theta, r * Vector2::new(a.x, 0.0), r * Vector2::new(0.0, a.y)],
            Model::Affine => {
                vec![Vector2::new(a.x, 0.0), Vector2::new(a.y, 0.0), Vector2::new(0.0, a.x), Vector2::new(0.0, a.y)]
            }
        };
        out.push(Vector2::new(1.0, 0.0));
        out.push(Vector2::new(0.0, 1.0));
        out
    }

    /// The error this fit predicts over `region` (machine units; pass the corners of the part)
    /// when every observed coordinate of the `commanded` marks it was solved from carries noise
    /// of standard deviation `sigma` (machine units). An empty `region` means the marks
    /// themselves.
    ///
    /// # Errors
    /// [`MathError::NonFinite`] for a negative or non-finite `sigma` or a non-finite point;
    /// [`MathError::CollinearPoints`] when the marks do not determine the parameters.
    pub fn predict(
        &self,
        commanded: &[Point2<f64>],
        sigma: f64,
        region: &[Point2<f64>],
    ) -> Result<Prediction, MathError> {
        self.predict_shared(commanded, sigma, region, &[])
    }

    /// [`Transform::predict`] with errors the marks share besides their independent noise:
    /// for each [`Shared`], observed point `i` is off by `δ·along[i]` with one `δ` of standard
    /// deviation `sigma` for all marks (a scale error of K acting on each mark's offset from
    /// the camera; a shift of every capture). Each adds the fit's linear response `g(p)` to
    /// its perturbation as `sigma²·g·gᵀ` to the covariance at `p`. No shared error is exactly
    /// [`Transform::predict`].
    ///
    /// # Errors
    /// As [`Transform::predict`]; [`MathError::LengthMismatch`] when a shared error has not one
    /// vector per mark; [`MathError::NonFinite`] for a negative or non-finite shared σ or a
    /// non-finite vector.
    pub fn predict_shared(
        &self,
        commanded: &[Point2<f64>],
        sigma: f64,
        region: &[Point2<f64>],
        shared: &[Shared<'_>],
    ) -> Result<Prediction, MathError> {
        if !(sigma.is_finite() && sigma >= 0.0) {
            return Err(MathError::NonFinite { what: "the noise σ" });
        }
        for e in shared {
            if !(e.sigma.is_finite() && e.sigma >= 0.0) {
                return Err(MathError::NonFinite { what: "a shared error's σ" });
            }
            if e.along.len() != commanded.len() {
                return Err(MathError::LengthMismatch { commanded: commanded.len(), observed: e.along.len() });
            }
            if e.along.iter().any(|v| !(v.x.is_finite() && v.y.is_finite())) {
                return Err(MathError::NonFinite { what: "a shared error vector" });
            }
        }
        let k = self.model.parameters();
        let mut normal = DMatrix::<f64>::zeros(k, k);
        for n in commanded {
            let j = self.jacobian(*n);
            for (i, ji) in j.iter().enumerate() {
                for (l, jl) in j.iter().enumerate() {
                    normal[(i, l)] += ji.dot(jl);
                }
            }
        }
        if !normal.iter().all(|v| v.is_finite()) {
            return Err(MathError::NonFinite { what: "a commanded point" });
        }
        let singular = MathError::CollinearPoints { model: self.model.name() };
        let largest = normal.diagonal().max();
        let cholesky = normal.cholesky().ok_or(singular.clone())?;
        // Rounding can let a rank-deficient matrix through with a tiny pivot.
        let pivot = cholesky.l_dirty().diagonal().min();
        if !(pivot * pivot > 1e-12 * largest) {
            return Err(singular);
        }
        let inverse = cholesky.inverse();
        // The parameters' response to each shared perturbation: (JᵀJ)⁻¹·Σ Jᵢᵀ·alongᵢ.
        let responses: Vec<(Vec<f64>, f64)> = shared
            .iter()
            .map(|e| {
                let mut pull = vec![0.0; k];
                for (n, v) in commanded.iter().zip(e.along) {
                    for (l, jl) in self.jacobian(*n).iter().enumerate() {
                        pull[l] += jl.dot(v);
                    }
                }
                ((0..k).map(|i| (0..k).map(|l| inverse[(i, l)] * pull[l]).sum()).collect(), e.sigma)
            })
            .collect();
        let points = if region.is_empty() { commanded } else { region };
        let quantile = -2.0 * (0.01 / points.len().max(1) as f64).ln();
        let mut worst = Prediction { sigma: 0.0, bound99: 0.0 };
        for p in points {
            let j = self.jacobian(*p);
            let mut cov = Matrix2::<f64>::zeros();
            for (i, ji) in j.iter().enumerate() {
                for (l, jl) in j.iter().enumerate() {
                    cov += ji * jl.transpose() * inverse[(i, l)];
                }
            }
            cov *= sigma * sigma;
            for (response, shared_sigma) in &responses {
                let g = j.iter().zip(response).fold(Vector2::zeros(), |a, (jl, r)| a + jl * *r);
                cov += g * g.transpose() * (shared_sigma * shared_sigma);
            }
            let half_tr = 0.5 * (cov[(0, 0)] + cov[(1, 1)]);
            let det = cov[(0, 0)] * cov[(1, 1)] - cov[(0, 1)] * cov[(1, 0)];
            let lmax = half_tr + (half_tr * half_tr - det).max(0.0).sqrt();
            let here = Prediction { sigma: (2.0 * half_tr).max(0.0).sqrt(), bound99: (lmax * quantile).sqrt() };
            if !(here.sigma.is_finite() && here.bound99.is_finite()) {
                return Err(MathError::NonFinite { what: "a region point" });
            }
            worst.sigma = worst.sigma.max(here.sigma);
            worst.bound99 = worst.bound99.max(here.bound99);
        }
        Ok(worst)
    }
}

/// The noise σ a fit's residuals imply, machine units: `√(Σ‖rᵢ‖² / (2N − k))` with `k` the
/// model's parameters; `None` when the marks leave no degree of freedom.
#[must_use]
pub fn residual_sigma(model: Model, marks: usize, rms: f64) -> Option<f64> {
    let dof = (2 * marks).checked_sub(model.parameters()).filter(|d| *d > 0)?;
    Some((rms * rms * marks as f64 / dof as f64).sqrt())
}

/// A mark that does not belong with the others (see [`find_outlier`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outlier {
    /// Its index in the points given.
    pub index: usize,
    /// Its distance from the fit of the other marks, machine units.
    pub residual: f64,
    /// The noise it was judged against, machine units.
    pub noise: f64,
}

/// The fewest marks [`find_outlier`] judges.
pub const MIN_MARKS_FOR_OUTLIERS: usize = 5;

/// The mark whose leave-one-out residual exceeds `factor` × the noise (the larger of `sigma`
/// and the residual σ of the fit without it), if any; `None` below
/// [`MIN_MARKS_FOR_OUTLIERS`] marks. Lengths in machine units.
///
/// It refits without each mark in turn and measures how far that mark lies from the fit of the
/// others (its leave-one-out residual, which a single displaced mark cannot hide by pulling the
/// fit towards itself). It needs five marks or more, so that the others still over-determine
/// the fit.
///
/// # Errors
/// As [`Model::fit`] for the input (mismatched lengths, non-finite or degenerate points).
pub fn find_outlier(
    model: Model,
    commanded: &[Point2<f64>],
    observed: &[Point2<f64>],
    sigma: f64,
    factor: f64,
) -> Result<Option<Outlier>, MathError> {
    model.fit(commanded, observed)?;
    if commanded.len() < MIN_MARKS_FOR_OUTLIERS.max(model.min_points() + 2) {
        return Ok(None);
    }
    let mut worst: Option<Outlier> = None;
    let (mut n, mut o) = (Vec::with_capacity(commanded.len()), Vec::with_capacity(commanded.len()));
    for i in 0..commanded.len() {
        n.clear();
        o.clear();
        for j in (0..commanded.len()).filter(|j| *j != i) {
            n.push(commanded[j]);
            o.push(observed[j]);
        }
        // The others may be degenerate on their own (e.g. collinear without this mark): then
        // this mark is needed, not an outlier.
        let Ok(rest) = model.fit(&n, &o) else { continue };
        let residual = (rest.transform.apply(commanded[i]) - observed[i]).norm();
        let spread = residual_sigma(model, rest.len, rest.rms).unwrap_or(0.0);
        let noise = sigma.max(spread);
        // The most extreme relative to its own noise: the others' leave-one-out fits still
        // hold the outlier, so their spread (and noise) is large.
        let beyond = |w: &Outlier| residual * w.noise > w.residual * noise;
        if residual > factor * noise && worst.as_ref().is_none_or(beyond) {
            worst = Some(Outlier { index: i, residual, noise });
        }
    }
    Ok(worst)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitComplex;

    /// A small deterministic Gaussian source (xorshift64* and Box–Muller).
    struct Noise(u64);

    impl Noise {
        fn uniform(&mut self) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            let v = (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64;
            v.max(f64::MIN_POSITIVE)
        }
        fn gauss(&mut self) -> f64 {
            (-2.0 * self.uniform().ln()).sqrt() * (std::f64::consts::TAU * self.uniform()).cos()
        }
    }

    /// The true part: rotated 0.3°, printed `scale` large, shifted.
    fn truth_scaled(p: Point2<f64>, scale: (f64, f64)) -> Point2<f64> {
        let r = UnitComplex::new(0.3f64.to_radians());
        let c = Point2::new(3.0, 2.0);
        let scaled = Vector2::new((p.x - c.x) * scale.0, (p.y - c.y) * scale.1);
        c + r * scaled + Vector2::new(-0.01, 0.015)
    }

    /// A part the model describes exactly (uniform scale for similarity, none for rigid).
    fn truth_for(model: Model) -> impl Fn(Point2<f64>) -> Point2<f64> {
        let scale = match model {
            Model::Rigid => (1.0, 1.0),
            Model::Similarity => (1.001, 1.001),
            Model::Rectangle | Model::Affine => (1.0008, 1.0012),
        };
        move |p| truth_scaled(p, scale)
    }

    fn truth(p: Point2<f64>) -> Point2<f64> {
        truth_for(Model::Rectangle)(p)
    }

    /// Marks on the part's outline: corners first, then the middles of the long sides.
    fn marks(n: usize) -> Vec<Point2<f64>> {
        let outline = [(0.0, 0.0), (6.0, 0.0), (6.0, 4.0), (0.0, 4.0), (3.0, 0.0), (3.0, 4.0)];
        outline.iter().take(n).map(|&(x, y)| Point2::new(x, y)).collect()
    }

    fn noisy_by(
        truth: &dyn Fn(Point2<f64>) -> Point2<f64>,
        noise: &mut Noise,
        commanded: &[Point2<f64>],
        sigma: f64,
    ) -> Vec<Point2<f64>> {
        commanded.iter().map(|p| truth(*p) + Vector2::new(noise.gauss(), noise.gauss()) * sigma).collect()
    }

    fn noisy(noise: &mut Noise, commanded: &[Point2<f64>], sigma: f64) -> Vec<Point2<f64>> {
        noisy_by(&truth, noise, commanded, sigma)
    }

    fn map(t: &Transform, p: Point2<f64>) -> Point2<f64> {
        let u = Matrix2::new(t.scale.x, t.shear, 0.0, t.scale.y);
        t.observed_centroid + t.rotation.to_rotation_matrix().into_inner() * u * (p - t.commanded_centroid)
    }

    /// A shared error (one scale error δ of σ 0.5 % acting on each mark's offset from the
    /// camera) beside the independent noise: the prediction with it matches the measured error
    /// and covers the largest error over the region; without it, it does not.
    #[test]
    fn a_shared_error_widens_the_prediction_by_what_it_does() {
        let (sigma, common_sigma) = (0.0002, 0.005);
        let region = [Point2::new(0.0, 0.0), Point2::new(6.0, 0.0), Point2::new(6.0, 4.0), Point2::new(0.0, 4.0)];
        let commanded = marks(4);
        let reach =
            [Vector2::new(0.06, 0.01), Vector2::new(-0.02, 0.05), Vector2::new(0.08, -0.07), Vector2::new(0.0, 0.03)];
        let mut noise = Noise(0x28);
        let trials = 4000;
        let (mut inside, mut inside_without, mut sum2) = (0u32, 0u32, [0.0; 4]);
        let mut predicted = None;
        for _ in 0..trials {
            let delta = common_sigma * noise.gauss();
            let observed: Vec<Point2<f64>> =
                noisy(&mut noise, &commanded, sigma).iter().zip(&reach).map(|(o, r)| o + r * delta).collect();
            let t = Model::Rectangle.transform(&commanded, &observed).expect("fit");
            let p = t
                .predict_shared(&commanded, sigma, &region, &[Shared { along: &reach, sigma: common_sigma }])
                .expect("prediction");
            let without = t.predict(&commanded, sigma, &region).expect("prediction");
            predicted.get_or_insert(p);
            let errors: Vec<f64> = region.iter().map(|q| (map(&t, *q) - truth(*q)).norm()).collect();
            let worst = errors.iter().copied().fold(0.0, f64::max);
            inside += u32::from(worst <= p.bound99);
            inside_without += u32::from(worst <= without.bound99);
            for (s, e) in sum2.iter_mut().zip(&errors) {
                *s += e * e;
            }
        }
        let p = predicted.expect("trials ran");
        let rms = sum2.iter().map(|s| (s / f64::from(trials)).sqrt()).fold(0.0, f64::max);
        assert!((rms / p.sigma - 1.0).abs() < 0.05, "measured {rms} vs predicted {}", p.sigma);
        let (coverage, without) =
            (f64::from(inside) / f64::from(trials), f64::from(inside_without) / f64::from(trials));
        assert!(coverage >= 0.985 && without < 0.97, "coverage {coverage} with the shared error, {without} without");
        let t = Model::Rectangle.transform(&commanded, &noisy(&mut noise, &commanded, sigma)).expect("fit");
        assert_eq!(
            t.predict_shared(&commanded, sigma, &region, &[Shared { along: &reach, sigma: 0.0 }]),
            t.predict(&commanded, sigma, &region)
        );
        assert!(matches!(
            t.predict_shared(&commanded, sigma, &region, &[Shared { along: &reach[..2], sigma: 0.01 }]),
            Err(MathError::LengthMismatch { .. })
        ));
    }

    #[test]
    fn the_prediction_matches_the_error_of_noisy_fits() {
        let sigma = 0.0003;
        let region = [Point2::new(-1.0, -1.0), Point2::new(7.0, -1.0), Point2::new(7.0, 5.0), Point2::new(-1.0, 5.0)];
        let cases = [
            (Model::Rectangle, 4),
            (Model::Similarity, 3),
            (Model::Rigid, 3),
            (Model::Rectangle, 6),
            (Model::Affine, 5),
        ];
        for (model, n) in cases {
            let truth = truth_for(model);
            let commanded = marks(n);
            let mut noise = Noise(0x9e37_79b9_7f4a_7c15 ^ n as u64);
            let trials = 4000;
            let (mut inside, mut sum2) = (0u32, [0.0; 4]);
            let mut predicted = None;
            for _ in 0..trials {
                let observed = noisy_by(&truth, &mut noise, &commanded, sigma);
                let t = model.transform(&commanded, &observed).expect("fit");
                let p = t.predict(&commanded, sigma, &region).expect("prediction");
                predicted.get_or_insert(p);
                let errors: Vec<f64> = region.iter().map(|q| (map(&t, *q) - truth(*q)).norm()).collect();
                let worst = errors.iter().copied().fold(0.0, f64::max);
                inside += u32::from(worst <= p.bound99);
                for (s, e) in sum2.iter_mut().zip(&errors) {
                    *s += e * e;
                }
            }
            let p = predicted.expect("trials ran");
            // The worst corner's 1σ against the measured RMS error at the worst corner, and
            // the 99 % bound's coverage of the largest error over the region.
            let rms = sum2.iter().map(|s| (s / f64::from(trials)).sqrt()).fold(0.0, f64::max);
            assert!((rms / p.sigma - 1.0).abs() < 0.05, "{model} {n}: rms {rms} vs 1σ {}", p.sigma);
            let coverage = f64::from(inside) / f64::from(trials);
            // ≥ 99 % by construction; 0.985 leaves three standard errors of 4000 trials.
            assert!(coverage >= 0.985, "{model} {n}: 99 % bound covers {coverage}");
            assert!(p.bound99 > p.sigma && p.sigma > sigma / 10.0, "{p:?}");
        }
    }

    #[test]
    fn the_prediction_grows_with_the_noise_and_away_from_the_marks() {
        let commanded = marks(4);
        let t = Model::Rectangle
            .transform(&commanded, &commanded.iter().map(|p| truth(*p)).collect::<Vec<_>>())
            .expect("fit");
        let at_marks = t.predict(&commanded, 0.001, &[]).expect("at the marks");
        let far = t.predict(&commanded, 0.001, &[Point2::new(30.0, 20.0)]).expect("far away");
        let double = t.predict(&commanded, 0.002, &[]).expect("twice the noise");
        assert!(far.sigma > 3.0 * at_marks.sigma, "{far:?} {at_marks:?}");
        assert!((double.sigma / at_marks.sigma - 2.0).abs() < 1e-12);
        assert_eq!(t.predict(&commanded, 0.0, &[]).map(|p| p.bound99), Ok(0.0));
        assert!(t.predict(&commanded, f64::NAN, &[]).is_err());
        assert!(t.predict(&commanded, -1.0, &[]).is_err());
        let collinear = [Point2::new(0.0, 0.0), Point2::new(1.0, 0.0), Point2::new(2.0, 0.0)];
        assert!(t.predict(&collinear, 0.001, &[]).is_err(), "three collinear marks cannot fix a rectangle");
    }

    #[test]
    fn residual_sigma_needs_a_degree_of_freedom() {
        assert_eq!(residual_sigma(Model::Rectangle, 2, 0.1), None, "4 coordinates, 5 parameters");
        assert!(residual_sigma(Model::Rectangle, 3, 0.1).is_some(), "6 coordinates, 5 parameters: 1 dof");
        assert_eq!(residual_sigma(Model::Similarity, 2, 0.1), None, "4 coordinates, 4 parameters");
        let s = residual_sigma(Model::Rectangle, 4, 0.1).expect("3 dof");
        assert!((s - (0.01 * 4.0 / 3.0f64).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn a_displaced_mark_among_six_is_found_and_clean_marks_are_kept() {
        let sigma = 0.0003;
        let commanded = marks(6);
        let mut noise = Noise(7);
        let mut false_alarms = 0;
        for trial in 0..500 {
            let mut observed = noisy(&mut noise, &commanded, sigma);
            if find_outlier(Model::Rectangle, &commanded, &observed, sigma, 6.0).expect("fit").is_some() {
                false_alarms += 1;
            }
            let bad = trial % 6;
            observed[bad] += Vector2::new(0.05 * (trial as f64).cos(), 0.05 * (trial as f64).sin());
            let found = find_outlier(Model::Rectangle, &commanded, &observed, sigma, 6.0).expect("fit");
            assert_eq!(found.map(|o| o.index), Some(bad), "trial {trial}: {found:?}");
        }
        assert!(false_alarms <= 5, "{false_alarms} false alarms in 500 clean runs");
        // Four marks leave too few to judge.
        let observed = noisy(&mut noise, &marks(4), sigma);
        assert_eq!(find_outlier(Model::Rectangle, &marks(4), &observed, sigma, 6.0), Ok(None));
    }
}
