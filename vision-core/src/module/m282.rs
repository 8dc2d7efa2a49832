//! M282: solve the run's fit and emit it as modal G51 / G68 / G52.

use vision_math::{fit_piece, fit_rectangle, fit_similarity, AlignmentChain, Fit, LengthUnit, Piece, Point2, Vector2};

use super::m280::RunMode;
use super::{Reply, VisionModule};
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
/// Every mode emits the same four lines ([`AlignmentChain::gcode`]) with the other pieces at
/// identity, so a later M282 always replaces, never compounds.
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
    /// The chain emitted (equal to `fit.transform.chain()` for [`Pieces::All`]).
    #[serde(serialize_with = "ser::chain")]
    pub chain: AlignmentChain,
    /// Residual `chain(nᵢ) − oᵢ` of each capture under the emitted chain, in capture order.
    #[serde(serialize_with = "ser::vectors")]
    pub residuals: Vec<Vector2<f64>>,
    /// RMS residual length under the emitted chain, `sqrt(Σ‖rᵢ‖² / N)`.
    pub rms: f64,
    /// Largest residual length under the emitted chain.
    pub max_residual: f64,
}

impl VisionModule {
    /// **M282**: solves the fit commanded → observed over every capture of the run (least
    /// squares when there are more marks than the minimum), checks the quality gates, writes
    /// `Run_*` (the emitted chain: `Run_Tx/Ty` = G52, `Run_Theta` = G68 R in radians,
    /// `Run_Sx/Sy` = G51, `Run_CenterX/Y` = G68 X/Y), closes the run (`Run_Active` = 0) and runs
    /// the four lines of [`AlignmentChain::gcode`] on the machine; the reply lists them.
    ///
    /// Quality gates, judged on the full fit of the run's model whatever `pieces` is emitted
    /// (0 disables a gate): X or Y scale off 1 by more than `VisionFitMaxScaleDev` percent;
    /// shift ‖observed centroid − commanded centroid‖ above `VisionFitMaxShift`; worst mark
    /// residual above `VisionFitMaxResidual` (both inches, ×25.4 under G21).
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
        let mode = self.run.mode;
        let needed = mode.min_marks();
        if self.run.dots.len() < needed {
            return Err(VisionError::TooFewDots { mode: mode.name(), needed, got: self.run.dots.len() });
        }
        let unit = machine.units();
        let (commanded, observed): (Vec<Point2<f64>>, Vec<Point2<f64>>) =
            self.run.dots.iter().map(|d| d.in_unit(unit)).unzip();
        let fit = match mode {
            RunMode::Rectangle => fit_rectangle(&commanded, &observed)?,
            RunMode::Similarity => fit_similarity(&commanded, &observed)?,
        };
        self.check_gates(&fit, unit)?;
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
        let gcode = chain.gcode()?.to_vec();
        machine.run_gcode(&gcode)?;
        let residuals: Vec<Vector2<f64>> = commanded.iter().zip(&observed).map(|(n, o)| chain.apply(*n) - o).collect();
        let max_residual = residuals.iter().map(|r| r.norm()).fold(0.0, f64::max);
        #[allow(clippy::cast_precision_loss)] // a handful of marks
        let rms = (residuals.iter().map(Vector2::norm_squared).sum::<f64>() / residuals.len() as f64).sqrt();

        self.run.active = false;
        self.publish_run();
        let p = &mut self.telemetry;
        p.run_tx = chain.shift.x;
        p.run_ty = chain.shift.y;
        p.run_theta = chain.rotation_deg.to_radians();
        p.run_sx = chain.scale.x;
        p.run_sy = chain.scale.y;
        p.run_center_x = chain.center.x;
        p.run_center_y = chain.center.y;
        Ok(Reply { gcode, report: AlignReport { unit, mode, pieces, fit, chain, residuals, rms, max_residual } })
    }

    /// The `VisionFitMax*` gates (see [`VisionModule::m282`]).
    fn check_gates(&self, fit: &Fit, unit: LengthUnit) -> Result<(), VisionError> {
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
        Ok(())
    }
}
