//! The CNC side: what the Vision module needs from its host (SPEC §6).
//!
//! The host is a real control or the simulated machine that wraps a G-code interpreter. The
//! module never parses G-code itself: it asks the host for positions and state and hands it
//! G-code text to run.

use std::fmt;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use vision_math::{AlignmentChain, LengthUnit, Point2, Vector2};

/// A failure reported by the host machine, in the host's own words.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MachineError {
    /// What the host says went wrong (e.g. `line 1: unsupported word G28.3`).
    pub message: String,
}

impl MachineError {
    /// Builds an error with `message`.
    pub fn new(message: impl Into<String>) -> Self {
        MachineError { message: message.into() }
    }
}

impl fmt::Display for MachineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "machine: {}", self.message)
    }
}

impl std::error::Error for MachineError {}

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

/// The controller a host is, as far as the Vision M-codes' output differs (SPEC §9).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Controller {
    /// Mach4 (and the simulator): M282 aligns with `G51` scale, `G68` rotation about a centre
    /// and a `G52` shift; M280 cancels with `G69 G50 G52 X0 Y0`.
    #[default]
    Mach4,
    /// LinuxCNC: no G68 and no G51. M282 rotates the active G5x system (`G10 L2 P0 R`, about its
    /// origin) and shifts with `G52` (kept in the G92 registers), and cannot scale
    /// ([`vision_math::linuxcnc`]); the alignment state lives in persistent parameters
    /// ([`crate::linuxcnc`]). A capture waits for the machine first and may not move after
    /// that, so M281 does not re-centre, and M283 runs stepwise
    /// ([`crate::VisionModule::m283_begin`]).
    LinuxCnc,
}

/// The host CNC, seen by the Vision module.
///
/// All lengths are in the machine's **current** units ([`Machine::units`], G20 inch or G21
/// millimetre). "Commanded position" is the XY the program last commanded for the active tool:
/// with a tool whose table offset is `(ox, oy)`, commanding `P` puts the tool (for the camera
/// tool: its optical axis) at `P` and the spindle at `P − (ox, oy)`.
///
/// The host executes synchronously: when [`Machine::run_gcode`] returns, the motion is done and
/// [`Machine::program_position`] reports the new position.
pub trait Machine {
    /// Commanded XY in the **program** frame (the coordinates the G-code wrote, before any
    /// active G51/G68/G52 alignment), current units.
    fn program_position(&self) -> Point2<f64>;

    /// The active alignment modals (G51 scale, G68 rotation, G52 shift), or `None` when all
    /// three are cancelled. Lengths in current units.
    fn active_alignment(&self) -> Option<AlignmentChain>;

    /// Commanded XY in the active **work** frame (after G51/G68/G52, before work and tool
    /// offsets), current units. The default maps [`Machine::program_position`] through
    /// [`Machine::active_alignment`].
    fn work_position(&self) -> Point2<f64> {
        let p = self.program_position();
        self.active_alignment().map_or(p, |chain| chain.apply(p))
    }

    /// The controller, for the dialect of M280/M282's alignment lines. Default: Mach4.
    fn controller(&self) -> Controller {
        Controller::Mach4
    }

    /// The active G5x work system's XY rotation (LinuxCNC's `G10 L2 R`), degrees
    /// counter-clockwise; 0 on a controller without one (the default). The program frame is
    /// turned by it against the machine axes, along which the camera's K and its tool offset
    /// are measured.
    fn xy_rotation_deg(&self) -> f64 {
        0.0
    }

    /// Runs G-code lines in order and waits until they are done.
    ///
    /// # Errors
    /// The host's own error (unsupported word, limit, alarm); lines after the failing one are
    /// not run.
    fn run_gcode(&mut self, lines: &[String]) -> Result<(), MachineError>;

    /// The active tool number (the tool last loaded by `Tn M6`; 0 = none).
    fn active_tool(&self) -> u32;

    /// Tool `tool`'s X/Y tool-table offset, current units.
    ///
    /// # Errors
    /// The tool does not exist in the table.
    fn tool_offset(&self, tool: u32) -> Result<Vector2<f64>, MachineError>;

    /// Writes tool `tool`'s X/Y tool-table offset, current units. Takes effect at the next move.
    ///
    /// # Errors
    /// The tool does not exist or the table is locked.
    fn set_tool_offset(&mut self, tool: u32, offset: Vector2<f64>) -> Result<(), MachineError>;

    /// The active length unit (G20 inch / G21 millimetre).
    fn units(&self) -> LengthUnit;

    /// Reads pound variable `#index`.
    ///
    /// # Errors
    /// The variable does not exist.
    fn pound(&self, index: u32) -> Result<f64, MachineError>;

    /// Writes pound variable `#index`.
    ///
    /// # Errors
    /// The variable does not exist or is read-only.
    fn set_pound(&mut self, index: u32, value: f64) -> Result<(), MachineError>;

    /// Waits `seconds` (like `G4`), letting motion settle. A simulated machine may return at once.
    fn dwell(&mut self, seconds: f64);

    /// The host's clock (injected so tests are deterministic).
    fn now(&self) -> Timestamp;
}

#[cfg(test)]
#[allow(clippy::float_cmp)]
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
