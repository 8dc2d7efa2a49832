//! What a calibration was made with, and the check that it still holds.
//!
//! K, the optical centre and the camera offset are right only for the camera and tool table
//! M283 measured them with. M283 records the image size, the driver and the camera tool's X/Y
//! offset beside K (`VisionCal_ResX/ResY`, `VisionCal_Driver`, `VisionCal_ToolNumber`,
//! `VisionCal_ToolOffsetX/Y`); M280–M282 compare them with what they see and refuse a change
//! that moves every capture: another resolution reads each mark from another image centre at
//! another pixel scale, another driver is another camera, and another tool offset shifts every
//! observed point by the difference (the fit takes it as the part's shift). A calibration
//! loaded without a record (made before it existed) is taken as made at the resolution it is
//! used with; its driver and tool offset are not checked.

use vision_math::chain::fixed;
use vision_math::Vector2;

use super::VisionModule;
use crate::controller;
use crate::driver::CameraDriver;
use crate::error::VisionError;
use crate::machine::Machine;
use crate::params::Calibration;

/// The largest difference between the camera tool's offset now and the one M283 recorded that
/// passes, inches: a tool table's rounding (4 decimals in inches, 3 in mm), far below any fit's
/// predicted error.
pub(crate) const TOOL_OFFSET_TOLERANCE_IN: f64 = 1e-4;

impl VisionModule {
    /// Takes the size of the frames the camera delivers as `VisionCameraResX/Y` (in memory;
    /// saved with the next calibration). A camera that reports its frame size is the authority
    /// on it: the default resolution is the camera's own. A calibration without a record takes
    /// the resolution it was used with as its record first, so the change is still seen.
    ///
    /// # Errors
    /// [`VisionError::InvalidParam`] for a frame size outside 2..100000 pixels.
    pub(crate) fn adopt_frame_size(&mut self) -> Result<(), VisionError> {
        let Some(driver) = self.driver.as_deref_mut() else { return Ok(()) };
        let Some((w, h)) = driver.frame_size() else { return Ok(()) };
        let setting = (self.params.camera_res_x(), self.params.camera_res_y());
        let frames = (i64::from(w), i64::from(h));
        if frames == setting {
            return Ok(());
        }
        let calibrated = self.params.cal_k() != vision_math::Matrix2::zeros();
        if calibrated && self.params.calibration.recorded_resolution().is_none() {
            let mut next = self.params.clone();
            next.set("VisionCal_ResX", setting.0)?;
            next.set("VisionCal_ResY", setting.1)?;
            self.params = next;
        }
        let mut next = self.params.clone();
        next.set("VisionCameraResX", frames.0)?;
        next.set("VisionCameraResY", frames.1)?;
        self.params = next;
        Ok(())
    }

    /// Refuses when the camera's frames (adopted first, [`VisionModule::adopt_frame_size`]) or
    /// `VisionCameraResX/Y` differ from the image size the calibration was made at; `sheet` is
    /// the controller's sheet-calibration word, for the advice. Run after every trigger too:
    /// a camera can change its mode between frames.
    ///
    /// # Errors
    /// [`VisionError::CalibrationChanged`]; as [`VisionModule::adopt_frame_size`].
    pub(crate) fn check_resolution(&mut self, sheet: &str) -> Result<(), VisionError> {
        self.adopt_frame_size()?;
        let Some((rx, ry)) = self.params.calibration.recorded_resolution() else { return Ok(()) };
        let now = (self.params.camera_res_x(), self.params.camera_res_y());
        if now == (rx, ry) {
            return Ok(());
        }
        Err(VisionError::CalibrationChanged {
            what: "the camera's resolution",
            detail: format!(
                "the camera is now {} x {} px (VisionCameraResX/ResY), K was calibrated at {rx} x {ry} px",
                now.0, now.1
            ),
            fix: format!("set the camera back to {rx} x {ry} px, or run {sheet} to calibrate at {} x {}", now.0, now.1),
        })
    }

    /// Refuses when what the calibration was made with has changed: the camera's frames or
    /// `VisionCameraResX/Y` against the recorded image size, the loaded driver against the
    /// recorded one, the camera tool's offset in `machine`'s table against the recorded one.
    /// Nothing recorded, nothing checked.
    ///
    /// # Errors
    /// [`VisionError::CalibrationChanged`] naming the setting, both values and the fix;
    /// [`VisionError::Machine`] when the tool table cannot be read.
    pub(crate) fn check_calibration_record(&mut self, machine: &dyn Machine) -> Result<(), VisionError> {
        let sheet = machine.controller().sheet_calibration();
        self.check_resolution(sheet)?;
        let calibration = &self.params.calibration;
        if let (Some(recorded), Some(driver)) = (calibration.recorded_driver(), self.driver.as_deref()) {
            if !recorded.eq_ignore_ascii_case(driver.name()) {
                return Err(VisionError::CalibrationChanged {
                    what: "the camera driver",
                    detail: format!("the loaded driver is {}, K was calibrated with {recorded}", driver.name()),
                    fix: format!("switch back to the {recorded} camera, or run {sheet} to calibrate this one"),
                });
            }
        }
        if let Some((tool, recorded)) = calibration.recorded_tool() {
            let unit = machine.units()?;
            let recorded = recorded * calibration.cal_units().factor_to(unit);
            let now = controller::tool_offset(machine, tool)?;
            let off = now - recorded;
            let tolerance = vision_math::LengthUnit::Inch.convert(TOOL_OFFSET_TOLERANCE_IN, unit);
            if off.norm() > tolerance {
                let u = unit.short_name();
                let xy = |v: Vector2<f64>| format!("X{} Y{}", fixed(v.x, 5), fixed(v.y, 5));
                return Err(VisionError::CalibrationChanged {
                    what: "the camera tool's offset",
                    detail: format!(
                        "the tool table holds {} {u} for T{tool}, M283 wrote {} {u}: every mark would be read {} {u} off",
                        xy(now),
                        xy(recorded),
                        fixed(off.norm(), 5)
                    ),
                    fix: format!("set T{tool}'s X/Y offset back to {}, or run {sheet} to measure it again", xy(recorded)),
                });
            }
        }
        Ok(())
    }

    /// A warning when the camera searches for another mark than the one M283 calibrated with
    /// (its shape or contrast changed): the centre it reports may be another point of the
    /// print. `None` when the same, or either is unknown.
    pub(crate) fn mark_note(&self) -> Option<String> {
        let recorded = self.params.calibration.recorded_mark()?;
        let now = self.driver.as_deref()?.mark_spec()?;
        (now != recorded).then(|| {
            format!(
                "the camera searches for a {now} mark, M283 calibrated with a {recorded} one: check \
                 VisionCameraMark and VisionCameraPolarity, or recalibrate"
            )
        })
    }

    /// `calibration` with the record of it made now: the image size, the loaded driver's name,
    /// and `tool`'s offset in `machine`'s table (in the machine's units, which `calibration`'s
    /// `Cal_Units` must be).
    ///
    /// # Errors
    /// [`VisionError::Machine`] when the tool table cannot be read; as [`Calibration::recorded`].
    pub(crate) fn with_record(
        &self,
        machine: &dyn Machine,
        tool: Option<u32>,
        calibration: &Calibration,
    ) -> Result<Calibration, VisionError> {
        let resolution = (self.params.camera_res_x(), self.params.camera_res_y());
        // A name the record cannot hold (a test fake's) is not recorded, and so not checked.
        let driver = self
            .driver
            .as_deref()
            .map(|d| d.name().to_string())
            .filter(|n| n.len() <= 64 && n.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-'))
            .unwrap_or_default();
        let mark = self.driver.as_deref().and_then(CameraDriver::mark_spec).unwrap_or_default();
        let tool = match tool {
            Some(t) => Some((t, controller::tool_offset(machine, t)?)),
            None => None,
        };
        calibration.recorded(resolution, &driver, &mark, tool)
    }
}
