//! The CNC side: what the Vision module needs from its host (SPEC §6).
//!
//! The host is a real control or the simulated machine that wraps a G-code interpreter: one
//! trait for both. The module never parses or writes G-code itself: it asks the host for
//! positions and state and hands it typed [`MachineCommand`]s to run.

use std::time::{Duration, SystemTime, UNIX_EPOCH};

use vision_math::{LengthUnit, Point2, Vector2};

use crate::command::MachineCommand;
use crate::controller::Controller;
use crate::kind_error::{Kind, KindError};

/// The common kind of a machine failure, so a host or the module can react without reading
/// text (an e-stop is not a missing tool).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum MachineErrorKind {
    /// The controller refused a G-code line (unsupported word, bad syntax, limit).
    RefusedGcode,
    /// Motion stopped: cycle stop, feed hold, e-stop or an alarm during the line.
    Stopped,
    /// The tool is not in the tool table.
    UnknownTool,
    /// A parameter or pound variable that does not exist, or a value out of its range.
    OutOfRange,
    /// The controller could not be reached or answered something unusable (a scripting call
    /// that failed, a value of the wrong type).
    Communication,
    /// Anything else.
    Other,
}

impl Kind for MachineErrorKind {
    const NAME: &'static str = "MachineError";
    const PREFIX: &'static str = "machine: ";
}

/// A failure reported by the host machine: the common [`MachineErrorKind`] and the host's own
/// cause, kept whole ([`KindError`], like [`crate::DriverError`]).
///
/// `Display` is `machine: ` and the host's own words.
pub type MachineError = KindError<MachineErrorKind>;

/// A point in time from the host's clock, with the local UTC offset so that calibration dates
/// can be written in local time without a time-zone database.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Timestamp {
    /// The instant.
    pub time: SystemTime,
    /// Local time minus UTC, seconds (e.g. `3600` for UTC+01:00).
    pub utc_offset_s: i32,
}

impl Timestamp {
    /// A timestamp `unix_s` seconds after the Unix epoch, local offset `utc_offset_s` seconds.
    #[must_use]
    pub fn from_unix(unix_s: u64, utc_offset_s: i32) -> Timestamp {
        Timestamp { time: UNIX_EPOCH + Duration::from_secs(unix_s), utc_offset_s }
    }

    /// Local civil time `(year, month, day, hour, minute, second, millisecond)`.
    #[must_use]
    pub fn local_fields(&self) -> (i64, u32, u32, u32, u32, u32, u32) {
        let (secs, millis) = match self.time.duration_since(UNIX_EPOCH) {
            Ok(d) => (i64::try_from(d.as_secs()).unwrap_or(i64::MAX / 2), d.subsec_millis()),
            Err(e) => {
                // Before 1970: round towards −∞ to whole seconds.
                let d = e.duration();
                let s = i64::try_from(d.as_secs()).unwrap_or(i64::MAX / 2);
                if d.subsec_nanos() == 0 {
                    (-s, 0)
                } else {
                    (-s - 1, 1000 - d.subsec_millis().min(999))
                }
            }
        };
        let local = secs.saturating_add(i64::from(self.utc_offset_s));
        let days = local.div_euclid(86_400);
        let sod = local.rem_euclid(86_400);
        let (y, m, d) = civil_from_days(days);
        // sod < 86400, so every field fits in u32.
        let sod = u32::try_from(sod).unwrap_or(0);
        (y, m, d, sod / 3600, (sod / 60) % 60, sod % 60, millis)
    }

    /// ISO 8601 local time with its offset, e.g. `2025-03-14T09:26:53+01:00` (the manual's
    /// `VisionCal_Date`).
    #[must_use]
    pub fn iso_local(&self) -> String {
        let (y, mo, d, h, mi, s, _) = self.local_fields();
        let off = self.utc_offset_s;
        let sign = if off < 0 { '-' } else { '+' };
        let a = off.unsigned_abs();
        format!("{y:04}-{mo:02}-{d:02}T{h:02}:{mi:02}:{s:02}{sign}{:02}:{:02}", a / 3600, (a / 60) % 60)
    }

    /// A compact local-time stamp for file names, `YYYYMMDD_HHMMSS_mmm`.
    #[must_use]
    pub fn file_stamp(&self) -> String {
        let (y, mo, d, h, mi, s, ms) = self.local_fields();
        format!("{y:04}{mo:02}{d:02}_{h:02}{mi:02}{s:02}_{ms:03}")
    }
}

/// Days since 1970-01-01 → (year, month 1–12, day 1–31), proleptic Gregorian (H. Hinnant).
fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let y = yoe + era * 400;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = if m <= 2 { y + 1 } else { y };
    (y, u32::try_from(m).unwrap_or(1), u32::try_from(d).unwrap_or(1))
}

/// The host CNC, seen by the Vision module: a real controller through its bridge (Mach4's Lua
/// module, LinuxCNC's Python module) or the simulated machine. A bridge implements this and
/// nothing else; the session keeps the Vision module between M-code calls.
///
/// All lengths are in the machine's **current** units ([`Machine::units`], G20 inch or G21
/// millimetre). "Program position" is the XY the program last commanded for the active tool.
/// Every read can fail: a controller's scripting call can, and the failure reaches the operator
/// with its [`MachineErrorKind`] instead of a made-up value.
///
/// The host executes synchronously: when [`Machine::command`] returns, the motion is done and
/// [`Machine::program_position`] reports the new position.
pub trait Machine {
    /// Which controller this is: every rule that differs between controllers (how an alignment
    /// is applied, the tool table's sign, re-centring, …) comes from it.
    fn controller(&self) -> &'static dyn Controller;

    /// The G-code lines this controller runs for `command`, in order: the bridge answers with
    /// `vision-mcode`'s text for its controller (`vision_mcode::gcode`). The module lists them in
    /// [`crate::Reply::gcode`], also for a stepwise walk's moves that the host runs itself.
    ///
    /// # Errors
    /// The controller has no text for the command, or a number in it is not finite.
    fn gcode(&self, command: &MachineCommand) -> Result<Vec<String>, MachineError>;

    /// Runs one line of [`Machine::gcode`]'s text and returns when its motion is finished
    /// (Mach4: `mcCntlGcodeExecuteWait`; LinuxCNC: `self.execute`). The module never writes a
    /// line itself: it calls [`Machine::command`].
    ///
    /// # Errors
    /// The controller refused the line or stopped during it.
    fn execute(&mut self, line: &str) -> Result<(), MachineError>;

    /// Runs `command`: its [`Machine::gcode`] lines, each with [`Machine::execute`]; returns the
    /// lines run. Lines after a failing one are not run.
    ///
    /// # Errors
    /// The text's failure, or the first line's.
    fn command(&mut self, command: &MachineCommand) -> Result<Vec<String>, MachineError> {
        let lines = self.gcode(command)?;
        lines.iter().try_for_each(|line| self.execute(line))?;
        Ok(lines)
    }

    /// Runs `commands` in order, each with [`Machine::command`]; returns every line run.
    /// Commands after a failing one are not run.
    ///
    /// # Errors
    /// The first command's failure.
    fn run(&mut self, commands: &[MachineCommand]) -> Result<Vec<String>, MachineError> {
        let mut ran = Vec::new();
        for command in commands {
            ran.extend(self.command(command)?);
        }
        Ok(ran)
    }

    /// Saves the program's modal state — motion mode, distance mode, feed and feed mode, plane,
    /// units, offsets — before the module's own moves (M281's re-centring, M283's walk), so
    /// that [`Machine::restore_modal_state`] puts back exactly what the program had: a feed move
    /// after M281 stays a feed move (Mach4: `mcCntlMachineStatePush`; LinuxCNC: `M70`).
    ///
    /// # Errors
    /// The controller refused; the module then does not move.
    fn save_modal_state(&mut self) -> Result<(), MachineError>;

    /// Restores the modal state [`Machine::save_modal_state`] saved last (Mach4:
    /// `mcCntlMachineStatePop`; LinuxCNC: `M72`). The module calls it after its own moves, on
    /// success and on failure alike.
    ///
    /// # Errors
    /// The controller refused.
    fn restore_modal_state(&mut self) -> Result<(), MachineError>;

    /// Commanded XY in the **program** frame (the coordinates the G-code wrote, before any
    /// G51/G68/G52 alignment), current units.
    ///
    /// # Errors
    /// The controller refused the read.
    fn program_position(&self) -> Result<Point2<f64>, MachineError>;

    /// The tool in the spindle (the tool last loaded by `Tn M6`; 0 = none).
    ///
    /// # Errors
    /// The controller refused the read.
    fn active_tool(&self) -> Result<u32, MachineError>;

    /// Tool `tool`'s X/Y tool-table offset as the controller's table holds it, current units
    /// (its sign is the controller's: [`Controller::tool_table_sign`]).
    ///
    /// # Errors
    /// The tool is not in the table ([`MachineErrorKind::UnknownTool`]).
    fn tool_offset(&self, tool: u32) -> Result<Vector2<f64>, MachineError>;

    /// Writes tool `tool`'s X/Y tool-table offset as the controller's table holds it, current
    /// units. Takes effect at the next move.
    ///
    /// # Errors
    /// The tool is not in the table or the table is locked.
    fn set_tool_offset(&mut self, tool: u32, offset: Vector2<f64>) -> Result<(), MachineError>;

    /// The active length unit (G20 inch / G21 millimetre).
    ///
    /// # Errors
    /// The controller refused the read or reported neither unit.
    fn units(&self) -> Result<LengthUnit, MachineError>;

    /// Reads pound variable `#index`.
    ///
    /// # Errors
    /// The variable does not exist ([`MachineErrorKind::OutOfRange`]) or the read failed.
    fn pound(&self, index: u32) -> Result<f64, MachineError>;

    /// Writes pound variable `#index`.
    ///
    /// # Errors
    /// The variable does not exist or is read-only.
    fn set_pound(&mut self, index: u32, value: f64) -> Result<(), MachineError>;

    /// Waits `seconds` (finite, ≥ 0) for the machine to settle before a trigger (like `G4`). A
    /// simulated machine may return at once.
    ///
    /// # Errors
    /// The controller refused the wait (e.g. stopped).
    fn dwell(&mut self, seconds: f64) -> Result<(), MachineError>;

    /// Whether a G51/G68/G52 alignment is active, when the controller can tell (`None`, the
    /// default: it cannot, and the module trusts the alignment its own M282 left, until the
    /// next M280). A controller that answers lets the module forget an alignment the program
    /// cancelled itself (`G69 G50 G52 X0 Y0` before M30).
    ///
    /// # Errors
    /// The controller refused the read.
    fn alignment_active(&self) -> Result<Option<bool>, MachineError> {
        Ok(None)
    }

    /// The active G5x work system's XY rotation (LinuxCNC's `G10 L2 R`), degrees
    /// counter-clockwise; 0 on a controller without one (the default).
    ///
    /// # Errors
    /// The controller refused the read.
    fn xy_rotation_deg(&self) -> Result<f64, MachineError> {
        Ok(0.0)
    }

    /// The G92/G52 X/Y offset, current units (LinuxCNC keeps G52 in the G92 registers); zero by
    /// default.
    ///
    /// # Errors
    /// The controller refused the read.
    fn g92_offset(&self) -> Result<Vector2<f64>, MachineError> {
        Ok(Vector2::zeros())
    }

    /// The X/Y tool offset the controller applies to moves now, in its tool table's form
    /// (the table entry of the tool whose offset is active: LinuxCNC's `G43 Hn`; zero under
    /// `G49`), current units; `None` (the default) when the controller cannot tell. The module
    /// compares it with the camera tool's table entry before a capture: a camera whose offset is
    /// not applied is not over the commanded point.
    ///
    /// # Errors
    /// The controller refused the read.
    fn applied_tool_offset(&self) -> Result<Option<Vector2<f64>>, MachineError> {
        Ok(None)
    }

    /// Shows `text` to the operator (a status line, not an alarm). Default: nowhere.
    fn message(&mut self, text: &str) {
        let _ = text;
    }

    /// The host's clock, for `VisionCal_Date` and image names; the system clock in UTC unless
    /// the controller knows better.
    fn now(&self) -> Timestamp {
        Timestamp { time: SystemTime::now(), utc_offset_s: 0 }
    }
}

/// The controller's numbers as the module reads them: checked against
/// [`vision_math::bounds`], so a position of 1e308 or a rotation of 1e308° (a units or DRO
/// error) is refused before it reaches a capture or a G-code line.
pub(crate) mod checked {
    use vision_math::{bounds, MathError, Point2, Vector2};

    use super::{Machine, MachineError, MachineErrorKind};

    fn refused(e: MathError) -> MachineError {
        MachineError::new(MachineErrorKind::OutOfRange, e)
    }

    /// [`Machine::program_position`], each axis within ±[`bounds::MAX_COORDINATE`].
    pub(crate) fn program_position(machine: &dyn Machine) -> Result<Point2<f64>, MachineError> {
        let p = machine.program_position()?;
        Ok(Point2::new(
            bounds::coordinate("the controller's X position", p.x).map_err(refused)?,
            bounds::coordinate("the controller's Y position", p.y).map_err(refused)?,
        ))
    }

    /// `v` (an offset `what` the controller reported), each axis within
    /// ±[`bounds::MAX_COORDINATE`].
    pub(crate) fn offset(what: &'static str, v: Vector2<f64>) -> Result<Vector2<f64>, MachineError> {
        Ok(Vector2::new(
            bounds::coordinate(what, v.x).map_err(refused)?,
            bounds::coordinate(what, v.y).map_err(refused)?,
        ))
    }

    /// `deg` (a rotation `what` the controller reported), within ±[`bounds::MAX_ROTATION_DEG`].
    pub(crate) fn rotation_deg(what: &'static str, deg: f64) -> Result<f64, MachineError> {
        bounds::rotation_deg(what, deg).map_err(refused)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iso_local_time() {
        // 2024-02-29T12:34:56Z
        let t = Timestamp::from_unix(1_709_210_096, 3600);
        assert_eq!(t.iso_local(), "2024-02-29T13:34:56+01:00");
        let t = Timestamp::from_unix(0, -5 * 3600 - 1800);
        assert_eq!(t.iso_local(), "1969-12-31T18:30:00-05:30");
        assert_eq!(Timestamp::from_unix(1_709_210_096, 0).file_stamp(), "20240229_123456_000");
        let before = Timestamp { time: UNIX_EPOCH - Duration::from_millis(1500), utc_offset_s: 0 };
        assert_eq!(before.local_fields(), (1969, 12, 31, 23, 59, 58, 500));
    }
}
