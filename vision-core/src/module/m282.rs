//! M282: solve the run's fit and emit it as modal G51 / G68 / G52.

use vision_math::fit::{find_outlier, residual_sigma, Shared};
use vision_math::{
    fit_piece, fit_rectangle, fit_similarity, AlignmentChain, Fit, LengthUnit, Model, Piece, Point2, Vector2,
};

use super::height::{self, HeightReport};
use super::m280::RunMode;
use super::{Dot, Reply, VisionModule};
use crate::controller::{Applied, HowApplied};
use crate::error::VisionError;
use crate::machine::Machine;
use crate::ser;

/// Which pieces of the fit M282 emits (`P` word).
///
/// Decision (the physically right least-squares meaning of the partial modes): each partial
/// mode emits the least-squares optimum of a transform that holds **only** that piece, not a
/// slice of the full fit — see [`vision_math::fit::partial`](vision_math::fit_piece):
/// * `Shift` (`P1`): `t = ō − n̄` (centroid difference).
/// * `Rotation` (`P2`): rotation about the commanded centroid, no shift; the angle is the rigid
///   Procrustes angle.
/// * `Scale` (`P3`): scale about the commanded centroid (one factor for a similarity run, one
///   per axis for a rectangle run), with the compensating `G52` that keeps the centroid still.
///
/// Every mode emits the same commands ([`crate::controller::modal_commands`] on Mach4) with the
/// other pieces at identity, so a later M282 always replaces, never compounds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Pieces {
    /// `P0` / omitted: shift, rotation and scale.
    All,
    /// `P1`: shift only.
    Shift,
    /// `P2`: rotation only, about the centroid.
    Rotation,
    /// `P3`: scale only, about the centroid.
    Scale,
}

impl Pieces {
    /// The selection's name (`all`, `shift`, `rotation`, `scale`), as in the JSON.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Pieces::All => "all",
            Pieces::Shift => "shift",
            Pieces::Rotation => "rotation",
            Pieces::Scale => "scale",
        }
    }
}

/// What M282 solved and emitted. Lengths in the machine's current units (`unit`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct AlignReport {
    /// The unit of every length below.
    #[serde(serialize_with = "ser::unit")]
    pub unit: LengthUnit,
    /// The run's fit model.
    pub mode: RunMode,
    /// The pieces emitted.
    pub pieces: Pieces,
    /// The full fit of the run's model over every capture (what the quality gates judged).
    #[serde(serialize_with = "ser::fit")]
    pub fit: Fit,
    /// The chain emitted (equal to `fit.transform.chain()` for [`Pieces::All`]); on LinuxCNC
    /// its rigid part ([`AlignmentChain::rigid`]), which is what runs there.
    #[serde(serialize_with = "ser::chain")]
    pub chain: AlignmentChain,
    /// Residual `chain(nᵢ) − oᵢ` of each capture under the emitted chain, in capture order.
    #[serde(serialize_with = "ser::vectors")]
    pub residuals: Vec<Vector2<f64>>,
    /// RMS residual length under the emitted chain, `sqrt(Σ‖rᵢ‖² / N)`.
    pub rms: f64,
    /// Largest residual length under the emitted chain (of the marks the fit used).
    pub max_residual: f64,
    /// The cut error the full fit (`fit`) predicts over the bounding box of the marks it used.
    pub predicted: PredictedError,
    /// The mark left out of the fit as an outlier, if any (its residual is still listed).
    pub dropped: Option<DroppedMark>,
    /// The working-distance change the run's camera moves measured (and, with
    /// `VisionHeightCorrection`, corrected the captures for); `None` when no M281 of the run
    /// read its mark from two positions.
    pub height: Option<HeightReport>,
    /// How the controller applied it: on the machine or by the host, the scale left out and
    /// why, the work-offset rotation (LinuxCNC's G5x rotation, θ₀ and the shift). In the JSON
    /// only where there is a work-offset rotation, named after the controller, and as
    /// `"applied_by": "host"` where the host maps the moves.
    #[serde(flatten)]
    pub how: HowApplied,
}

/// The cut error a fit predicts over the part (see [`vision_math::fit::Prediction`]): from the
/// parameters' covariance given a per-coordinate noise σ, at the worst corner of the marks'
/// bounding box. When the run measured the working distance ([`AlignReport::height`]) it also
/// holds what of K's scale error there remains (its 1σ once corrected, all of it with
/// `VisionHeightCorrection` off) and the shift a misplaced optical centre makes at that height
/// (`VisionCenterUncertaintyPx`); a wrong camera offset is not in it. Lengths in the report's
/// unit.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PredictedError {
    /// The noise σ per observed coordinate used: the larger of the camera's
    /// (`VisionCameraNoisePx` through K) and the residuals' own.
    pub noise: f64,
    /// The camera's part of it: `VisionCameraNoisePx` × K's largest singular value.
    pub camera_noise: f64,
    /// Root-mean-square length of the cut error at the worst corner, 1σ.
    pub sigma: f64,
    /// A radius holding the largest cut error over the region with ≥ 99 % probability.
    pub bound99: f64,
}

/// A mark M282 left out of the fit (see [`vision_math::fit::find_outlier`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DroppedMark {
    /// Its 1-based index in the run's dot list.
    pub mark: usize,
    /// Its distance from the fit of the other marks, the report's unit.
    pub residual: f64,
    /// The noise it was judged against (`VisionOutlierFactor` × this was exceeded).
    pub noise: f64,
}

impl VisionModule {
    /// **M282**: solves the fit commanded → observed over every capture of the run (least
    /// squares when there are more marks than the minimum), checks the quality gates, writes
    /// `Run_*` (the emitted chain: `Run_Tx/Ty` = G52, `Run_Theta` = G68 R in radians,
    /// `Run_Sx/Sy` = G51, `Run_CenterX/Y` = G68 X/Y), closes the run (`Run_Active` = 0) and runs
    /// the controller's alignment commands on the machine (on Mach4 the four lines of
    /// [`crate::controller::modal_commands`]); the reply lists the lines.
    ///
    /// With five marks or more, the one mark whose distance from the fit of the others exceeds
    /// `VisionOutlierFactor` × the noise is left out first ([`AlignReport::dropped`]). Every
    /// accepted fit predicts its cut error over the marks' bounding box
    /// ([`AlignReport::predicted`]); the height change the captures measured is in
    /// [`AlignReport::height`]. The gates, LinuxCNC's lines and the height correction:
    /// `docs/vision-module.md` (M282).
    ///
    /// Works after a run's M282 too (the dot list stays until the next M280), so a second M282
    /// can emit another selection from the same captures; the output replaces, never compounds.
    ///
    /// # Errors
    /// [`VisionError::NotEnabled`], [`VisionError::WrongTool`], [`VisionError::TooFewDots`],
    /// [`VisionError::Math`] (degenerate marks), [`VisionError::FitRejected`]; nothing is
    /// emitted and nothing changes. [`VisionError::Machine`] when the machine refuses a line:
    /// the run stays open and the telemetry unchanged, but the lines before the refused one have
    /// run (the first is the cancel line, so at worst the machine is left unaligned); run M282
    /// again once the machine accepts G-code.
    pub fn m282(&mut self, machine: &mut dyn Machine, pieces: Pieces) -> Result<Reply<AlignReport>, VisionError> {
        self.check_enabled()?;
        self.check_tool(machine)?;
        self.check_calibration_record(machine)?;
        let mode = self.run.mode;
        let needed = mode.min_marks();
        if self.run.dots.len() < needed {
            return Err(VisionError::TooFewDots { mode: mode.name(), needed, got: self.run.dots.len() });
        }
        let unit = machine.units()?;
        let (all_commanded, as_read): (Vec<Point2<f64>>, Vec<Point2<f64>>) =
            self.run.dots.iter().map(|d| d.in_unit(unit)).unzip();
        let all_reach: Vec<Vector2<f64>> = self.run.dots.iter().map(|d| d.reach_in(unit)).collect();
        // The image scale the camera moves measured at the part's height: each capture's
        // offset from the camera is K's length times (1 + ε) (scale ∝ working distance).
        let scale = self.run.scale.estimate();
        let correct = self.params.height_correction();
        let all_observed: Vec<Point2<f64>> = match scale.filter(|_| correct) {
            Some(e) => as_read.iter().zip(&all_reach).map(|(o, r)| o + r * e.error).collect(),
            None => as_read,
        };
        // What of the scale the captures still carry: its 1σ once corrected, else all of it.
        let scale_sigma = scale.map_or(0.0, |e| if correct { e.sigma } else { e.error.hypot(e.sigma) });
        // And the shift a misplaced optical centre makes at this height (unmeasurable: it moves
        // every capture alike, as the part's own shift would): ε × the centre's uncertainty,
        // the calibration lift's 1σ when it measured the centre, else the allowance.
        let centre_px = self.params.calibration.center_sigma().unwrap_or(self.params.center_uncertainty_px());
        let shift_sigma = scale.map_or(0.0, |e| e.error.hypot(e.sigma) * centre_px * self.k_largest(unit));
        let model = match mode {
            RunMode::Rectangle => Model::Rectangle,
            RunMode::Similarity => Model::Similarity,
        };
        let camera_noise = self.camera_noise(unit);
        let dropped = self.find_dropped(model, &all_commanded, &all_observed, camera_noise)?;
        let kept_mark = |i: usize| dropped.is_none_or(|d| d.mark != i + 1);
        let kept = |v: &[Point2<f64>]| -> Vec<Point2<f64>> {
            v.iter().enumerate().filter(|(i, _)| kept_mark(*i)).map(|(_, p)| *p).collect()
        };
        let (commanded, observed) = (kept(&all_commanded), kept(&all_observed));
        let kept_dots: Vec<&Dot> =
            self.run.dots.iter().enumerate().filter(|(i, _)| kept_mark(*i)).map(|(_, d)| d).collect();
        let reach: Vec<Vector2<f64>> = kept_dots.iter().map(|d| d.reach_in(unit)).collect();
        let fit = match mode {
            RunMode::Rectangle => fit_rectangle(&commanded, &observed)?,
            RunMode::Similarity => fit_similarity(&commanded, &observed)?,
        };
        let controller = machine.controller();
        // The controller's own refusal comes first (LinuxCNC cannot scale at all).
        let full = fit.transform.chain().ok_or(VisionError::Math(vision_math::MathError::DegenerateObserved))?;
        controller.check_fit(&full, self.params.fit_max_scale_dev_pct())?;
        self.check_gates(&fit, &commanded, &observed, unit)?;
        // The lens's uncertainty: one shared error per coefficient, moving each capture by what
        // that coefficient's 1σ moves the pixel it was read at.
        let lens_sigma = self.params.calibration.lens_sigma();
        let lens_along: Vec<[Vector2<f64>; 4]> = kept_dots.iter().map(|d| d.lens_along_in(unit)).collect();
        let lens = Lens { along: &lens_along, sigma: lens_sigma };
        let predicted = predict(&fit, &commanded, camera_noise, &reach, [scale_sigma, shift_sigma], &lens)?;
        let chain = match pieces {
            Pieces::All => {
                fit.transform.chain().ok_or(VisionError::Math(vision_math::MathError::DegenerateObserved))?
            }
            Pieces::Shift => fit_piece(Piece::Shift, &commanded, &observed)?.chain,
            Pieces::Rotation => fit_piece(Piece::Rotation, &commanded, &observed)?.chain,
            Pieces::Scale => {
                fit_piece(Piece::Scale { uniform: mode == RunMode::Similarity }, &commanded, &observed)?.chain
            }
        };
        let Applied { gcode, chain, how } = controller.apply_alignment(machine, &chain)?;
        // What the machine runs: the chain as its G-code's decimals write it (a controller that
        // keeps the alignment itself, LinuxCNC, is read back instead at the next call).
        self.alignment = chain.as_emitted();
        let residuals: Vec<Vector2<f64>> =
            all_commanded.iter().zip(&all_observed).map(|(n, o)| chain.apply(*n) - o).collect();
        let used: Vec<f64> = residuals
            .iter()
            .enumerate()
            .filter(|(i, _)| dropped.is_none_or(|d| d.mark != i + 1))
            .map(|(_, r)| r.norm())
            .collect();
        let max_residual = used.iter().copied().fold(0.0, f64::max);
        let rms = (used.iter().map(|r| r * r).sum::<f64>() / used.len() as f64).sqrt();

        let sizes: Vec<f64> = self.run.dots.iter().map(|d| d.mark_size * d.unit.factor_to(unit)).collect();
        let height =
            scale.map(|e| height::report(&self.params, e, unit, &sizes, machine.controller().sheet_calibration()));

        self.run.active = false;
        self.publish_run();
        self.dro.write(|p| {
            p.run_tx = chain.shift.x;
            p.run_ty = chain.shift.y;
            p.run_theta = chain.rotation_deg.to_radians();
            p.run_sx = chain.scale.x;
            p.run_sy = chain.scale.y;
            p.run_center_x = chain.center.x;
            p.run_center_y = chain.center.y;
            p.run_predicted_sigma = predicted.sigma;
            p.run_predicted_bound = predicted.bound99;
            p.run_height_change_pct = height.as_ref().map_or(0.0, |h| h.change_pct);
            p.run_height_change = height.as_ref().map_or(0.0, |h| h.change);
            p.run_height_sigma_pct = height.as_ref().map_or(0.0, |h| h.sigma_pct);
        });
        // A height warning reaches the host's status line as M281's do.
        if let Some(w) = height.as_ref().and_then(|h| h.warning.as_deref()) {
            self.dro.ok(Some(w));
        }
        Ok(Reply {
            gcode,
            report: AlignReport {
                unit,
                mode,
                pieces,
                fit,
                chain,
                residuals,
                rms,
                max_residual,
                predicted,
                dropped,
                height,
                how,
            },
        })
    }

    /// The camera's noise per observed coordinate in `unit`: `VisionCameraNoisePx` times K's
    /// largest singular value (the worst direction), 0 while K is unset.
    fn camera_noise(&self, unit: LengthUnit) -> f64 {
        self.params.camera_noise_px() * self.k_largest(unit)
    }

    /// K's largest singular value in `unit` per pixel, 0 while K is unset or not finite.
    fn k_largest(&self, unit: LengthUnit) -> f64 {
        let largest = self.params.cal_k().singular_values().max() * self.params.cal_units().factor_to(unit);
        if largest.is_finite() {
            largest
        } else {
            0.0
        }
    }

    /// The outlier to leave out (`VisionOutlierFactor`, 0 disables; five marks or more).
    fn find_dropped(
        &self,
        model: Model,
        commanded: &[Point2<f64>],
        observed: &[Point2<f64>],
        camera_noise: f64,
    ) -> Result<Option<DroppedMark>, VisionError> {
        let factor = self.params.outlier_factor();
        if factor <= 0.0 {
            return Ok(None);
        }
        Ok(find_outlier(model, commanded, observed, camera_noise, factor)?.map(|o| DroppedMark {
            mark: o.index + 1,
            residual: o.residual,
            noise: o.noise,
        }))
    }

    /// The `VisionFitMax*` gates (see [`VisionModule::m282`]).
    fn check_gates(
        &self,
        fit: &Fit,
        commanded: &[Point2<f64>],
        observed: &[Point2<f64>],
        unit: LengthUnit,
    ) -> Result<(), VisionError> {
        let u = unit.short_name();
        let max_dev = self.params.fit_max_scale_dev_pct();
        let dev = (fit.transform.scale.x - 1.0).abs().max((fit.transform.scale.y - 1.0).abs()) * 100.0;
        if max_dev > 0.0 && dev > max_dev {
            return Err(VisionError::FitRejected {
                reason: format!(
                    "scale X {:.5} / Y {:.5} deviates {dev:.3} % from 1, more than VisionFitMaxScaleDev = {max_dev} %",
                    fit.transform.scale.x, fit.transform.scale.y
                ),
            });
        }
        let max_shift = LengthUnit::Inch.convert(self.params.fit_max_shift_in(), unit);
        let shift = (fit.transform.observed_centroid - fit.transform.commanded_centroid).norm();
        if max_shift > 0.0 && shift > max_shift {
            return Err(VisionError::FitRejected {
                reason: format!("shift {shift:.4} {u} exceeds VisionFitMaxShift = {max_shift:.4} {u}"),
            });
        }
        let max_res = LengthUnit::Inch.convert(self.params.fit_max_residual_in(), unit);
        if max_res > 0.0 && fit.max_residual > max_res {
            return Err(VisionError::FitRejected {
                reason: format!(
                    "worst mark residual {:.4} {u} exceeds VisionFitMaxResidual = {max_res:.4} {u}",
                    fit.max_residual
                ),
            });
        }
        let gate = LengthUnit::Inch.convert(self.params.fit_max_axis_scale_error_in(), unit);
        match axis_scale_miss(fit, commanded, observed) {
            Some((sx, sy, miss)) if gate > 0.0 && miss > gate => Err(VisionError::FitRejected {
                reason: format!(
                    "the marks show X and Y scaled differently (X {sx:.5}, Y {sy:.5}): a similarity fit \
                     misses by up to {miss:.4} {u}, more than VisionFitMaxAxisScaleError = {gate:.4} {u}; \
                     align this part in rectangle mode (M280 P4) with four marks"
                ),
            }),
            _ => Ok(()),
        }
    }
}

/// For a similarity fit: the per-axis scales `(sx, sy)` the rectangle fit of the same marks
/// measures, and how far the similarity misses a mark because it can follow only their mean
/// (`|sx − sy| / 2` times the mark's distance from the centroid, the farthest mark's).
/// `None` for other models and for marks that determine no per-axis scale.
fn axis_scale_miss(fit: &Fit, commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> Option<(f64, f64, f64)> {
    if fit.transform.model != Model::Similarity || commanded.len() < Model::Rectangle.min_points() {
        return None;
    }
    let rectangle = fit_rectangle(commanded, observed).ok()?;
    let (sx, sy) = (rectangle.transform.scale.x, rectangle.transform.scale.y);
    let reach = commanded.iter().map(|n| (n - fit.transform.commanded_centroid).norm()).fold(0.0, f64::max);
    Some((sx, sy, (sx - sy).abs() / 2.0 * reach))
}

/// The prediction of `fit` over the bounding box of `commanded`, with the larger of the camera's
/// noise and the residuals' own σ, and two errors the marks share: a scale error of 1σ
/// `scale_sigma` acting on each mark's `reach` (its offset from the camera), and a shift of 1σ
/// `shift_sigma` (report unit) per axis.
/// The lens's share of the prediction: per kept capture, what each coefficient moves it
/// (program units per unit coefficient), and the coefficients' 1σ.
struct Lens<'a> {
    along: &'a [[Vector2<f64>; 4]],
    sigma: [f64; 4],
}

fn predict(
    fit: &Fit,
    commanded: &[Point2<f64>],
    camera_noise: f64,
    reach: &[Vector2<f64>],
    [scale_sigma, shift_sigma]: [f64; 2],
    lens: &Lens<'_>,
) -> Result<PredictedError, VisionError> {
    let model = fit.transform.model;
    let noise = residual_sigma(model, fit.len, fit.rms).map_or(camera_noise, |s| s.max(camera_noise));
    let (lo, hi) = commanded.iter().fold(
        (Point2::new(f64::INFINITY, f64::INFINITY), Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY)),
        |(lo, hi), p| (Point2::new(lo.x.min(p.x), lo.y.min(p.y)), Point2::new(hi.x.max(p.x), hi.y.max(p.y))),
    );
    let corners = [lo, Point2::new(hi.x, lo.y), hi, Point2::new(lo.x, hi.y)];
    let (x, y) = (vec![Vector2::x(); commanded.len()], vec![Vector2::y(); commanded.len()]);
    let per_coefficient: Vec<Vec<Vector2<f64>>> = (0..4).map(|c| lens.along.iter().map(|a| a[c]).collect()).collect();
    let mut shared = vec![
        Shared { along: reach, sigma: scale_sigma },
        Shared { along: &x, sigma: shift_sigma },
        Shared { along: &y, sigma: shift_sigma },
    ];
    for (along, sigma) in per_coefficient.iter().zip(lens.sigma) {
        shared.push(Shared { along, sigma });
    }
    let p = fit.transform.predict_shared(commanded, noise, &corners, &shared)?;
    Ok(PredictedError { noise, camera_noise, sigma: p.sigma, bound99: p.bound99 })
}
