//! [`Host`]: what a controller bridge implements.

use std::time::SystemTime;

use vision_core::{Controller, Timestamp};
use vision_math::{LengthUnit, Point2, Vector2};

use crate::error::HostError;

/// The controller, seen through its scripting API (Mach4's `mc` table, LinuxCNC's remap
/// `self`). Every length is in the controller's **current** units ([`Host::units`]).
///
/// Each call either does what it says or returns [`HostError::Host`] with the controller's
/// reason; the session turns that into the operator's message.
pub trait Host {
    /// Runs one G-code line and returns when its motion is finished (Mach4:
    /// `mcCntlGcodeExecuteWait`; LinuxCNC: `self.execute`).
    ///
    /// # Errors
    /// The controller refused the line or stopped during it.
    fn execute(&mut self, line: &str) -> Result<(), HostError>;

    /// Reads pound variable `#index`.
    ///
    /// # Errors
    /// The controller refused the read.
    fn pound(&self, index: u32) -> Result<f64, HostError>;

    /// Writes pound variable `#index`.
    ///
    /// # Errors
    /// The controller refused the write (read-only or missing variable).
    fn set_pound(&mut self, index: u32, value: f64) -> Result<(), HostError>;

    /// The tool in the spindle (0 = none).
    ///
    /// # Errors
    /// The controller refused the read.
    fn active_tool(&self) -> Result<u32, HostError>;

    /// Tool `tool`'s X/Y tool-table offset, current units, as the controller's table holds it
    /// (on LinuxCNC the session flips its sign: see [`Controller::LinuxCnc`] below).
    ///
    /// # Errors
    /// The tool is not in the table.
    fn tool_offset(&self, tool: u32) -> Result<Vector2<f64>, HostError>;

    /// Writes tool `tool`'s X/Y tool-table offset, current units, as the controller's table
    /// holds it.
    ///
    /// # Errors
    /// The tool is not in the table or the table is locked.
    fn set_tool_offset(&mut self, tool: u32, offset: Vector2<f64>) -> Result<(), HostError>;

    /// The commanded XY in the **program** frame (what the G-code wrote, before the G51/G68/G52
    /// alignment), current units.
    ///
    /// # Errors
    /// The controller refused the read.
    fn position(&self) -> Result<Point2<f64>, HostError>;

    /// The active length unit (G20 inch / G21 millimetre).
    ///
    /// # Errors
    /// The controller refused the read or reported neither unit.
    fn units(&self) -> Result<LengthUnit, HostError>;

    /// Waits `seconds` (≥ 0) for the machine to settle before a trigger.
    ///
    /// # Errors
    /// The controller refused the wait (e.g. stopped).
    fn dwell(&mut self, seconds: f64) -> Result<(), HostError>;

    /// Whether a G51/G68/G52 alignment is active, when the controller can tell (`None`: it
    /// cannot; the session then trusts the alignment its own M282 left, until the next M280).
    /// A controller that answers lets the session forget an alignment the program cancelled
    /// itself (`G69 G50 G52 X0 Y0` before M30).
    ///
    /// # Errors
    /// The controller refused the read.
    fn alignment_active(&self) -> Result<Option<bool>, HostError> {
        Ok(None)
    }

    /// Which controller this is: the dialect of M280/M282's alignment lines and where the
    /// alignment's state lives. Default: Mach4.
    ///
    /// [`Controller::LinuxCnc`] also means: [`Host::tool_offset`] is LinuxCNC's table value,
    /// which LinuxCNC *adds* to a programmed point (`machine = g5x + R·(p + g92) + tool`), while
    /// the Vision module's offset is where the tool's point lies from the spindle (commanding P
    /// puts the spindle at P − offset); the session negates it both ways.
    fn controller(&self) -> Controller {
        Controller::Mach4
    }

    /// The active G5x work system's XY rotation (LinuxCNC's `G10 L2 R`), degrees
    /// counter-clockwise. Default 0 (Mach4 has none).
    ///
    /// # Errors
    /// The controller refused the read.
    fn xy_rotation_deg(&self) -> Result<f64, HostError> {
        Ok(0.0)
    }

    /// The G92/G52 X/Y offset (LinuxCNC keeps G52 in the G92 registers), current units. Default
    /// zero. A LinuxCNC session reads the active alignment from it.
    ///
    /// # Errors
    /// The controller refused the read.
    fn g92_offset(&self) -> Result<Vector2<f64>, HostError> {
        Ok(Vector2::zeros())
    }

    /// Shows `text` to the operator (a status line, not an alarm).
    fn message(&mut self, text: &str);

    /// The time for `VisionCal_Date` and image names; the system clock in UTC unless the
    /// controller knows better.
    fn now(&self) -> Timestamp {
        Timestamp { time: SystemTime::now(), utc_offset_s: 0 }
    }
}
