//! The image scale at the part's height, measured from camera moves.
//!
//! A camera's pixel → length factor K is right only at the working distance it was calibrated
//! at; the image scale is proportional to the working distance (the one-parameter model of the
//! manual's "Camera Z Height & Working Distance"). With the part at `s` times the calibration's
//! working distance, a mark `v` away from the camera (true, machine units) is read as
//! `d = v / s` plus the camera's noise.
//!
//! Reading one mark `P` from two or more camera positions `Cⱼ` (the program's point, then each
//! re-centring or probe move) measures `s`: `dⱼ = t·(P − Cⱼ) + nⱼ` with `t = 1/s`, linear in
//! the unknowns `t` and `P`, the positions exact (the machine's own moves) and the readings
//! noisy. Eliminating `P`, least squares gives
//!
//! `t̂ = −Σ (Cⱼ − C̄)·(dⱼ − d̄) / Σ ‖Cⱼ − C̄‖²`, with variance `σ² / Σ ‖Cⱼ − C̄‖²`,
//!
//! unbiased for independent noise of σ per coordinate (the same σ as the fit's). Marks combine
//! by adding their sums weighted by `1/σ²` (one regression over the run). Two readings a move
//! `Δ` apart give `σ(t̂) = √2·σ/‖Δ‖`: the longer the move, the better the evidence. Offsets the
//! camera's optical centre adds to every reading cancel in the differences, so does a constant
//! error of the camera offset; a rotation error of K enters only to second order.
//!
//! The scale error `ε = s − 1 = 1/t̂ − 1` is the working distance's relative change (+ farther);
//! its 1σ is `σ(t̂)/t̂²` to first order.

use nalgebra::{Point2, Vector2};

use crate::MathError;

/// A run's evidence of the image scale: the `1/σ²`-weighted sums of the regression of the module
/// doc, over every mark read from more than one camera position. Empty: no evidence.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ScaleEvidence {
    /// `−Σ (Cⱼ − C̄)·(dⱼ − d̄) / σ²`, dimensionless.
    cross: f64,
    /// `Σ ‖Cⱼ − C̄‖² / σ²`, dimensionless: the information about `t`.
    spread: f64,
    /// Marks that contributed.
    marks: u32,
}

/// The scale a [`ScaleEvidence`] measures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScaleEstimate {
    /// `ε = s − 1`: the true length of a reading over the length K gives it, less 1 (relative
    /// working-distance change; +0.04 = the part 4 % farther from the camera).
    pub error: f64,
    /// The 1σ of `error`, dimensionless.
    pub sigma: f64,
    /// Marks the estimate is made of.
    pub marks: u32,
}

impl ScaleEvidence {
    /// Adds one mark read from several camera positions: `readings` are `(Cⱼ, dⱼ)`, the camera
    /// position and the offset it read to the mark, both in one length unit and frame, with
    /// noise `sigma` per coordinate of `dⱼ` (same unit). Fewer than two readings, or readings
    /// all from one position, add nothing.
    ///
    /// # Errors
    /// [`MathError::NonFinite`] for a non-finite reading or a `sigma` that is not positive and
    /// finite; nothing is added then.
    pub fn add_mark(&mut self, readings: &[(Point2<f64>, Vector2<f64>)], sigma: f64) -> Result<(), MathError> {
        if !(sigma.is_finite() && sigma > 0.0) {
            return Err(MathError::NonFinite { what: "the noise σ of a scale reading" });
        }
        if readings.iter().any(|(c, d)| !(c.x.is_finite() && c.y.is_finite() && d.x.is_finite() && d.y.is_finite())) {
            return Err(MathError::NonFinite { what: "a scale reading" });
        }
        if readings.len() < 2 {
            return Ok(());
        }
        let n = readings.len() as f64;
        let c_mean = readings.iter().fold(Vector2::zeros(), |a, (c, _)| a + c.coords) / n;
        let d_mean = readings.iter().fold(Vector2::zeros(), |a, (_, d)| a + d) / n;
        let (mut cross, mut spread) = (0.0, 0.0);
        for (c, d) in readings {
            let dc = c.coords - c_mean;
            cross -= dc.dot(&(d - d_mean));
            spread += dc.norm_squared();
        }
        let w = 1.0 / (sigma * sigma);
        if !(spread * w > 0.0 && (cross * w).is_finite() && (spread * w).is_finite()) {
            return Ok(());
        }
        self.cross += cross * w;
        self.spread += spread * w;
        self.marks += 1;
        Ok(())
    }

    /// The evidence of `self` and `other` together.
    #[must_use]
    pub fn merged(self, other: ScaleEvidence) -> ScaleEvidence {
        ScaleEvidence {
            cross: self.cross + other.cross,
            spread: self.spread + other.spread,
            marks: self.marks + other.marks,
        }
    }

    /// Marks that contributed.
    #[must_use]
    pub fn marks(&self) -> u32 {
        self.marks
    }

    /// The 1σ of `t = 1/s` this evidence gives, dimensionless; `None` without evidence.
    #[must_use]
    pub fn sigma_t(&self) -> Option<f64> {
        (self.spread > 0.0).then(|| 1.0 / self.spread.sqrt())
    }

    /// The scale error and its 1σ; `None` without evidence, or when the readings say the image
    /// does not scale the right way round (`t̂ ≤ 0.5`: at least twice the calibration's working
    /// distance, or a reading of another mark), which is no height change this model can mend.
    #[must_use]
    pub fn estimate(&self) -> Option<ScaleEstimate> {
        let sigma_t = self.sigma_t()?;
        let t = self.cross / self.spread;
        if !(t > 0.5 && t.is_finite()) {
            return None;
        }
        Some(ScaleEstimate { error: 1.0 / t - 1.0, sigma: sigma_t / (t * t), marks: self.marks })
    }
}

/// How far the image turned against K, measured by one mark read from several camera
/// positions: a camera turned on its mount since calibration reads the mark moving the wrong
/// way round as the camera moves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageTurn {
    /// The angle from where K says the mark should have moved to where it was read, radians
    /// counter-clockwise.
    pub angle: f64,
    /// Its 1σ, radians (the readings' noise over the camera's travel).
    pub sigma: f64,
}

/// The turn of the image the readings `(Cⱼ, dⱼ)` of one mark show (as [`ScaleEvidence::add_mark`]
/// takes them, noise `sigma` per coordinate): the least-squares `z = s·e^{iφ}` of
/// `dⱼ − d̄ = −z·(Cⱼ − C̄)`, and φ with `σ(φ) = σ / (|z|·√Σ‖Cⱼ − C̄‖²)`. `None` for fewer than two
/// readings, readings from one position, a non-finite input or readings that do not move with
/// the camera at all (`z = 0`).
#[must_use]
pub fn image_turn(readings: &[(Point2<f64>, Vector2<f64>)], sigma: f64) -> Option<ImageTurn> {
    if readings.len() < 2 || !(sigma.is_finite() && sigma > 0.0) {
        return None;
    }
    let n = readings.len() as f64;
    let c_mean = readings.iter().fold(Vector2::zeros(), |a, (c, _)| a + c.coords) / n;
    let d_mean = readings.iter().fold(Vector2::zeros(), |a, (_, d)| a + d) / n;
    // z = −Σ conj(ΔC)·Δd / Σ|ΔC|², as complex numbers.
    let (mut re, mut im, mut spread) = (0.0, 0.0, 0.0);
    for (c, d) in readings {
        let dc = c.coords - c_mean;
        let dd = d - d_mean;
        re -= dc.x * dd.x + dc.y * dd.y;
        im -= dc.x * dd.y - dc.y * dd.x;
        spread += dc.norm_squared();
    }
    let size = re.hypot(im);
    if !(spread > 0.0 && size > 0.0 && size.is_finite() && spread.is_finite()) {
        return None;
    }
    Some(ImageTurn { angle: im.atan2(re), sigma: sigma * spread.sqrt() / size })
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::normal::Normal;

    /// One mark read at its first position and after moves; `s` the true scale.
    fn readings(
        rng: &mut Normal,
        s: f64,
        sigma: f64,
        mark: Point2<f64>,
        cameras: &[Point2<f64>],
    ) -> Vec<(Point2<f64>, Vector2<f64>)> {
        cameras.iter().map(|c| (*c, (mark - c) / s + Vector2::new(sigma * rng.draw(), sigma * rng.draw()))).collect()
    }

    #[test]
    fn without_noise_the_scale_is_exact_and_one_reading_is_no_evidence() {
        let mut e = ScaleEvidence::default();
        assert_eq!(e.estimate(), None);
        let mut rng = Normal(1);
        let mark = Point2::new(3.0, 1.0);
        e.add_mark(&readings(&mut rng, 1.04, 0.0, mark, &[Point2::new(3.01, 0.98)]), 1e-4).expect("ok");
        assert_eq!(e.estimate(), None, "one reading measures no scale");
        let cams = [Point2::new(2.9, 1.05), Point2::new(3.0, 1.0), Point2::new(3.2, 0.9)];
        e.add_mark(&readings(&mut rng, 1.04, 0.0, mark, &cams), 1e-4).expect("ok");
        let est = e.estimate().expect("evidence");
        assert!((est.error - 0.04).abs() < 1e-12 && est.marks == 1, "{est:?}");
        assert_eq!(
            e.add_mark(&[(mark, Vector2::new(f64::NAN, 0.0))], 1e-4),
            Err(MathError::NonFinite { what: "a scale reading" })
        );
        assert!(e.add_mark(&[], 0.0).is_err());
    }

    /// Over random height changes (±6 %), noise levels, move lengths and mark counts, the
    /// estimate is unbiased and its stated 1σ honest: the z-scores `(ε̂ − ε)/σ̂` have mean ≈ 0
    /// and spread ≈ 1.
    #[test]
    fn the_estimate_is_unbiased_and_its_sigma_honest() {
        let mut rng = Normal(28);
        let trials = 4000;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..trials {
            let s = 1.0 + 0.06 * (2.0 * rng.unit() - 1.0);
            let sigma = 0.0001 + 0.0004 * rng.unit();
            let mut e = ScaleEvidence::default();
            #[expect(clippy::cast_possible_truncation, clippy::cast_sign_loss, reason = "a draw in [0, 4), floored")]
            let marks = 1 + (rng.unit() * 4.0) as usize;
            for _ in 0..marks {
                let mark = Point2::new(10.0 * rng.unit(), 10.0 * rng.unit());
                let first = mark + Vector2::new(0.05 * rng.draw(), 0.05 * rng.draw());
                let probe = Vector2::new(0.4 * rng.draw(), 0.4 * rng.draw());
                let cams = [first, first + probe];
                e.add_mark(&readings(&mut rng, s, sigma, mark, &cams), sigma).expect("finite");
            }
            let est = e.estimate().expect("evidence");
            let z = (est.error - (s - 1.0)) / est.sigma;
            sum += z;
            sum2 += z * z;
        }
        let n = f64::from(trials);
        let mean = sum / n;
        let spread = (sum2 / n - mean * mean).sqrt();
        println!("scale estimate over {trials} draws: z-scores mean {mean:.3}, spread {spread:.3}");
        // 4000 draws: the mean's own 1σ is 0.016, the spread's about 0.011.
        assert!(mean.abs() < 0.06, "bias {mean} σ");
        assert!((spread - 1.0).abs() < 0.05, "z spread {spread}");
    }

    #[test]
    fn image_turn_finds_a_turned_camera_and_nothing_on_a_straight_one() {
        let mark = Point2::new(2.0, 1.0);
        let cams = [Point2::new(2.0, 1.0), Point2::new(2.3, 0.9), Point2::new(1.8, 1.2)];
        for deg in [0.0_f64, 3.0, -90.0, 179.0] {
            let r = nalgebra::Rotation2::new(deg.to_radians());
            let readings: Vec<_> = cams.iter().map(|c| (*c, 1.01 * (r * (mark - c)))).collect();
            let turn = image_turn(&readings, 0.001).expect("turn");
            assert!((turn.angle.to_degrees() - deg).abs() < 1e-9, "{deg}: {turn:?}");
            assert!(turn.sigma > 0.0 && turn.sigma < 0.01, "{turn:?}");
        }
        assert_eq!(image_turn(&[(mark, Vector2::zeros())], 0.001), None);
        assert_eq!(image_turn(&[(mark, Vector2::zeros()), (mark, Vector2::x())], 0.001), None);
        let still = [(cams[0], Vector2::x()), (cams[1], Vector2::x())];
        assert_eq!(image_turn(&still, 0.001), None);
        assert_eq!(image_turn(&[(cams[0], Vector2::x()), (cams[1], Vector2::zeros())], f64::NAN), None);
    }
}
