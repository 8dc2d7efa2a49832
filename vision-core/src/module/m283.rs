//! M283: calibrate K (and, for `Cn`, the camera tool offset).

use vision_math::{AlignmentChain, Point2, Vector2};

use super::{Reply, VisionModule};
use crate::calibrate::{quick, sheet_walk, CalReport, Calibrate, Walker};
use crate::error::VisionError;
use crate::machine::Machine;
use crate::params::Params;
use crate::sheets::{cal_sheet, known_sheets};

/// True when `chain` moves no point (within 1e-12).
fn is_identity(chain: &AlignmentChain) -> bool {
    let eps = 1e-12;
    (chain.scale - Vector2::new(1.0, 1.0)).norm() < eps && chain.rotation_deg.abs() < eps && chain.shift.norm() < eps
}

impl VisionModule {
    /// **M283**: calibrates. Both modes start with the axis-detect bump (+0.1″ X, trigger,
    /// +0.1″ Y, trigger, back; 2.54 mm under G21) and write `VisionCameraSwapXY` /
    /// `InvertX` / `InvertY`.
    ///
    /// * [`Calibrate::Quick`]: K = diag(d/width_px, d/height_px) (width and height along the
    ///   remapped axes), then re-triggers to confirm; no tool offset is written.
    /// * [`Calibrate::Sheet`]: walks the sheet, solves the full K, the sheet pose and the camera
    ///   tool's X/Y offset by least squares, writes them, re-walks every dot in G90 and reports
    ///   (see [`crate::calibrate`]). The offset goes to `VisionCameraToolNumber`, or to the
    ///   active tool when that is 0.
    ///
    /// On success K11..K22, the remap flags, `Cal_Date` (ISO local time from the machine clock)
    /// and `Cal_Units` (the machine's unit) are written together and the profile is saved
    /// atomically; `LastStatus` is `OK`. G-code runs inside the call (the reply's `gcode` is
    /// empty).
    ///
    /// # Errors
    /// [`VisionError::NotEnabled`], [`VisionError::WrongTool`], [`VisionError::UnknownSheet`],
    /// [`VisionError::AlignmentActive`] (calibration moves must not be scaled or rotated),
    /// [`VisionError::NoDriver`] — nothing changes; then [`VisionError::Calibration`],
    /// [`VisionError::Driver`], [`VisionError::Machine`] or [`VisionError::Profile`] during the
    /// routine: K, the remap flags, `Cal_*` and the tool offset are restored, the machine is sent
    /// back to its start position (best effort) and `LastStatus` holds the error.
    pub fn m283(&mut self, machine: &mut dyn Machine, mode: Calibrate) -> Result<Reply<CalReport>, VisionError> {
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
        let tool = self.params.camera_tool().unwrap_or_else(|| machine.active_tool());
        let offset_before = match mode {
            Calibrate::Sheet { .. } => Some(machine.tool_offset(tool)?),
            Calibrate::Quick { .. } => None,
        };
        let start: Point2<f64> = machine.program_position();

        let outcome = {
            let Some(driver) = self.driver.as_deref_mut() else {
                return Err(VisionError::NoDriver { name: self.params.driver().to_string() });
            };
            let mut walker = Walker::new(machine, driver, self.params.trigger_settle_s());
            match mode {
                Calibrate::Quick { diameter } => quick(&mut walker, &self.params, diameter),
                Calibrate::Sheet { n } => sheet_walk(&mut walker, &self.params, n, tool),
            }
        };
        let result = outcome.and_then(|solution| {
            let date = match &solution.report {
                CalReport::Quick(r) => r.date.clone(),
                CalReport::Sheet(r) => r.date.clone(),
            };
            let calibration = self.params.calibration.solved(solution.k, solution.remap, machine.units(), &date)?;
            self.commit_params(Params { calibration, ..self.params.clone() })?;
            Ok(solution.report)
        });
        match result {
            Ok(report) => {
                self.telemetry.last_status = "OK".to_string();
                Ok(Reply { gcode: Vec::new(), report })
            }
            Err(e) => {
                if let Some(offset) = offset_before {
                    let _ = machine.set_tool_offset(tool, offset);
                }
                if let Some(driver) = self.driver.as_deref_mut() {
                    let _ = Walker::new(machine, driver, 0.0).move_abs(start);
                }
                self.publish_failure(None, &e);
                Err(e)
            }
        }
    }
}
