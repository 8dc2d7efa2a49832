//! M283: calibrate K (and, for `Cn`, the camera tool offset).

use vision_math::chain::fixed;
use vision_math::{AlignmentChain, Point2, Vector2};

use super::capture::pixel_chain;
use super::{Reply, VisionModule};
use crate::calibrate::{absolute_move, quick, sheet_walk, CalReport, Calibrate, Solution, Walker};
use crate::error::VisionError;
use crate::machine::{Machine, MachineError};
use crate::params::Params;
use crate::sheets::{cal_sheet, known_sheets};

/// True when `chain` moves no point (within 1e-12).
fn is_identity(chain: &AlignmentChain) -> bool {
    let eps = 1e-12;
    (chain.scale - Vector2::new(1.0, 1.0)).norm() < eps && chain.rotation_deg.abs() < eps && chain.shift.norm() < eps
}

impl VisionModule {
    /// **M283**: calibrates. Both modes start with the axis-detect bump (+0.1″ X, trigger,
    /// +0.1″ Y, trigger, back; 2.54 mm under G21) that finds `VisionCameraSwapXY` /
    /// `InvertX` / `InvertY`.
    ///
    /// * [`Calibrate::Quick`]: K = diag(d/width_px, d/height_px) (width and height along the
    ///   remapped axes), then re-triggers to confirm; no tool offset is written.
    /// * [`Calibrate::Sheet`]: walks the sheet, solves the full K, the sheet pose and the camera
    ///   tool's X/Y offset by least squares, re-walks every dot in G90 and reports (see
    ///   [`crate::calibrate`]). The offset goes to `VisionCameraToolNumber`, or to the active
    ///   tool when that is 0.
    ///
    /// The walk writes nothing; its solution is applied here, in one place, or not at all:
    /// 1. the new [`crate::Calibration`] (K11..K22, the remap flags, `Cal_Date` from the machine
    ///    clock, `Cal_Units` = the machine's unit; the pixel centre offset is kept) is built and
    ///    validated;
    /// 2. the camera tool's offset is written to the machine's tool table (sheet walk only);
    /// 3. the profile is saved atomically, and only then the module takes the new calibration.
    ///
    /// Decision: the tool table goes first because undoing it is one write of a value we hold;
    /// when the save then fails, the old offset is written back and the error is the save's. If
    /// that restore fails too, the error says so and gives the offset to set by hand. The G-code
    /// runs through [`Machine::run_gcode`] as the walk goes; the reply lists every line run.
    ///
    /// Telemetry: every trigger writes the `Last*` values as it happens (through the best K
    /// known at that moment: the old calibration's, then each one the walk solves; the offsets
    /// in units are 0 while there is none), a failed one clears the offsets and size; at the end
    /// the last trigger is shown through the new K and `LastStatus` is `OK` (`OK (warning: …)`
    /// with the report's warning), or the error.
    ///
    /// # Errors
    /// [`VisionError::NotEnabled`], [`VisionError::WrongTool`], [`VisionError::UnknownSheet`],
    /// [`VisionError::AlignmentActive`] (calibration moves must not be scaled or rotated),
    /// [`VisionError::NoDriver`], an unwritable profile — nothing changes but `LastStatus`; then [`VisionError::Calibration`],
    /// [`VisionError::Driver`], [`VisionError::Machine`] or [`VisionError::Profile`] during the
    /// routine: K, the remap flags, `Cal_*` and the tool offset keep their values, the machine is
    /// sent back to its start position (best effort) and `LastStatus` holds the error.
    pub fn m283(&mut self, machine: &mut dyn Machine, mode: Calibrate) -> Result<Reply<CalReport>, VisionError> {
        if let Err(e) = self.check_calibration(machine, mode) {
            // The DRO shows why nothing was triggered.
            self.publish_failure(None, &e);
            return Err(e);
        }
        let tool = self.params.camera_tool().unwrap_or_else(|| machine.active_tool());
        let start: Point2<f64> = machine.program_position();

        let (outcome, ran) = {
            let Some(driver) = self.driver.as_deref_mut() else {
                return Err(VisionError::NoDriver { name: self.params.driver().to_string() });
            };
            let mut walker = Walker::new(machine, driver, &self.params, &mut self.dro);
            let outcome = match mode {
                Calibrate::Quick { diameter } => quick(&mut walker, &self.params, diameter),
                Calibrate::Sheet { n } => sheet_walk(&mut walker, &self.params, n, tool),
            };
            (outcome, walker.into_ran())
        };
        let (ran, last) = ran;
        match outcome.and_then(|solution| self.apply_calibration(machine, solution)) {
            Ok(report) => {
                // The last trigger again, as M281 would show it with the K just written.
                if let Some(reading) = last.filter(crate::driver::Reading::found) {
                    if let Ok(chain) = pixel_chain(&self.params, machine.units()) {
                        let centred = chain.centred(Point2::new(reading.x_px, reading.y_px));
                        self.dro.reading(Some(&chain), centred, &reading);
                    }
                }
                self.dro.ok(report.warning());
                Ok(Reply { gcode: ran, report })
            }
            Err(e) => {
                let _ = machine.run_gcode(&[absolute_move(start)]);
                // A failed trigger was shown (and its stale values cleared) as it happened.
                self.publish_failure(None, &e);
                Err(e)
            }
        }
    }

    /// M283's checks before anything moves or triggers.
    fn check_calibration(&mut self, machine: &dyn Machine, mode: Calibrate) -> Result<(), VisionError> {
        self.check_enabled()?;
        self.check_tool(machine)?;
        if let Calibrate::Sheet { n } = mode {
            if cal_sheet(n).is_none() {
                return Err(VisionError::UnknownSheet { sheet: n, known: known_sheets() });
            }
        }
        if machine.active_alignment().is_some_and(|a| !is_identity(&a)) {
            return Err(VisionError::AlignmentActive);
        }
        self.driver_mut()?;
        // A profile that cannot be saved is found before the walk moves the machine.
        if let Some(store) = &self.profile {
            store.check_writable()?;
        }
        Ok(())
    }

    /// Applies a calibration solution: all of it, or nothing (see [`VisionModule::m283`]).
    fn apply_calibration(&mut self, machine: &mut dyn Machine, solution: Solution) -> Result<CalReport, VisionError> {
        let calibration =
            self.params.calibration.solved(solution.k, solution.remap, machine.units(), solution.report.date())?;
        let next = Params { calibration, ..self.params.clone() };
        let restore = match solution.tool_offset {
            Some((tool, offset)) => {
                let before = machine.tool_offset(tool)?;
                machine.set_tool_offset(tool, offset)?;
                Some((tool, before))
            }
            None => None,
        };
        if let Err(save) = self.commit_params(next) {
            let Some((tool, before)) = restore else { return Err(save) };
            if let Err(e) = machine.set_tool_offset(tool, before) {
                return Err(VisionError::Machine(MachineError::new(format!(
                    "{save}; restoring tool {tool}'s offset then failed too ({e}) — set its X/Y offset back to \
                     X{} Y{} by hand",
                    fixed(before.x, 6),
                    fixed(before.y, 6)
                ))));
            }
            return Err(save);
        }
        Ok(solution.report)
    }
}
