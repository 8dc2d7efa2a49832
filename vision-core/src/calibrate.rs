//! M283 calibration (SPEC §4): the axis-detect bump, quick calibration (`Qd`) and the sheet
//! walk (`Cn`).
//!
//! # How the sheet walk solves K, the sheet pose and the camera offset
//!
//! For a capture with the camera tool commanded at `C` (current units), native pixel `p`:
//! the optical axis is at `A = C − o₀ + a` (`o₀` = the camera tool's table offset now, `a` = the
//! true camera-vs-spindle vector), and the mark is at `M = A + K·R·c(p)`. Two facts split the
//! problem into two well-conditioned least-squares solves:
//!
//! 1. **K from motion whose pixel effect is known.** Between two captures of the same dot the
//!    mark stays put, so `K·R·(c₂ − c₁) = −(C₂ − C₁)`. The axis-detect bumps and four probe
//!    moves around every dot (±X, ±Y, about a fifth of the field of view) give 22 such pairs;
//!    [`solve_linear`] returns the full 2×2 K. This never depends on the sheet, so a sheet lying
//!    perfectly square, or printed at the wrong scale, cannot corrupt K (SPEC §4 note).
//! 2. **Sheet pose and offset from the dot observations.** With K known, every capture gives
//!    `D = C + K·R·c = M + (o₀ − a)`. The sheet's origin is where the operator zeroed the work
//!    X/Y with the spindle, so `Mᵢ = L·nᵢ` with `L` the sheet's rotation and print scale, and
//!    `Dᵢ = L·nᵢ + b` with `b = o₀ − a`. A rectangle fit (rotation, X and Y scale, shift) of the
//!    nominal dots onto the mean `D` of each dot gives `L` (reported as the sheet rotation and
//!    measured scale, so a mis-printed sheet is visible, not baked into K) and `b`.
//!
//! The camera offset solved is `a = o₀ − b`: once written, commanding `P` puts the spindle at
//! `P − a` and the optical axis at `P`. The routine then re-walks every dot in G90 with the new
//! K and reports each dot's residual against the fitted sheet. The offset is not written yet, so
//! the verify walk compensates: commanding `N + o₀ − a = N + b` puts the optical axis on `N`,
//! and a capture there is seen at `C − b + K·R·c`, where the new offset will see it.
//!
//! # The optical centre, measured by a lift
//!
//! At one working distance the walk cannot see the optical centre: moving the reference pixel
//! (`res/2 + PxCenterOffset`) by `δ` pixels moves the solved offset by `K·R·δ` and leaves every
//! residual unchanged. So the reference pixel calibrates exactly at the sheet's height, while a
//! part at another height is off by the height change times `K·δ` (and re-centring centres marks
//! on the wrong pixel) — a shift no camera move at that height can tell from the part's own.
//! The pixel that matters is the one that sees the same table X/Y at every height: where the
//! machine's Z direction meets the image. After the probe moves (K known) the walk measures it
//! (`lift_centre`): it reads the last dot from a [`LIFT_GRID`]² grid of camera positions (±a
//! fifth of the field, within the probes' reach: `lift_positions`) at the calibration height, rises `VisionCalibrationLift` (machine +Z:
//! away from the part, marks move towards the image centre), reads the same positions again and
//! comes back down. The image shrinks about the centre `c`: `p_lift = r·p₀ + (1 − r)·c`, fitted
//! by [`vision_math::fit_centre`] with its 1σ. `VisionPxCenterOffsetX/Y = c − res/2` and its σ
//! are written with K, and steps 4–5 below solve the sheet pose, the camera offset and the
//! verify at that reference pixel (K does not depend on it). A lift that cannot measure (a
//! refused rise, a lost mark, no scale change) keeps the centre and warns; the calibration
//! stands. On a stepwise walk (LinuxCNC) the lift's targets carry their height
//! ([`WalkTarget`]).
//!
//! A wrong `VisionCameraResX`/`ResY` still calibrates exactly at the sheet's height; the
//! evidence the walk has of it is where the camera reports its marks. Rule: a calibration
//! reading outside `ResX` × `ResY` (threshold 0 px: a right setting never gives one) makes the
//! report's `warning` say the resolution setting is wrong (the check M281 makes on every
//! capture); the calibration itself still stands.
//!
//! Nothing here commits: `sheet_walk` and `quick` return a `Solution` (K, remap, tool
//! offset, report) and M283 applies it in one place, or nothing (see
//! [`crate::VisionModule::m283`]).
//!
//! On a controller whose G5x system is rotated by θ₀ against the machine axes (LinuxCNC's
//! `G10 L2 R`) the walk measures in that rotated program frame; K and the offset it writes are
//! turned by θ₀ back onto the machine axes, along which the camera and the tool table measure.
//!
//! Moves between stations are incremental (`G91 G0 X.. Y..` followed by `G90`), stations are
//! planned so each dot lands near the image centre, and `VisionTriggerSettleSec` is dwelt after
//! every move. Decision: M283 leaves the machine in G90 (the manual's calibration programs run
//! in G90), over the sheet's last dot on success and back at the start position on failure.

use vision_math::chain::fixed;
use vision_math::show::number;
use vision_math::{
    fit_centre, fit_rectangle, solve_linear, LengthUnit, Matrix2, PixelChain, Point2, Remap, Vector2, MM_PER_INCH,
};

use crate::command::MachineCommand;
use crate::controller::{program_to_machine, rotation};
use crate::driver::{CameraDriver, Reading};
use crate::error::VisionError;
use crate::machine::{checked, Machine};
use crate::module::capture::{centred_px, chain_with, k_in, mark_size, outside_image_note};
use crate::module::dro::{Dro, WalkProgress};
use crate::params::Params;
use crate::ser;
use crate::sheets::{cal_sheet, known_sheets};

/// The axis-detect bump: 0.1 inch (2.54 mm under G21).
pub const BUMP_IN: f64 = 0.1;
/// Probe moves around each dot, as a fraction of the smaller field-of-view side.
pub const PROBE_FOV_FRACTION: f64 = 0.2;
/// Fewest pixels the mark must move during a bump for the axis detect to trust it.
pub const MIN_BUMP_PX: f64 = 2.0;
/// Largest sheet print-scale error accepted, as a fraction (10 %).
pub const MAX_SHEET_SCALE_DEV: f64 = 0.10;

/// Where a stepwise M283 walk needs its next capture (see
/// [`crate::VisionModule::m283_next`]): the camera tool's X/Y and its height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkTarget {
    /// Program frame, current units.
    pub at: Point2<f64>,
    /// Height above the Z the walk started at, current units (machine +Z, up): 0, or
    /// `VisionCalibrationLift` while the calibration lift reads.
    pub lift: f64,
}

/// Which calibration M283 runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Calibrate {
    /// `Qd`: K = diag(d/width_px, d/height_px) from one trigger over a dot of diameter `d`
    /// (current units).
    Quick {
        /// The printed dot's diameter, current units.
        diameter: f64,
    },
    /// `Cn`: walk calibration sheet `n` of [`crate::sheets::CAL_SHEETS`].
    Sheet {
        /// The sheet number.
        n: u32,
    },
}

/// Result of the axis-detect bump.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct AxisReport {
    /// The remap written to `VisionCameraSwapXY` / `InvertX` / `InvertY`.
    #[serde(serialize_with = "ser::remap")]
    pub remap: Remap,
    /// The bump length, current units.
    pub bump: f64,
    /// Native pixel motion of the mark during the +X bump.
    #[serde(serialize_with = "ser::vector")]
    pub pixels_for_x: Vector2<f64>,
    /// Native pixel motion of the mark during the +Y bump.
    #[serde(serialize_with = "ser::vector")]
    pub pixels_for_y: Vector2<f64>,
}

/// What `M283 Qd` measured and wrote. Lengths in `unit`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct QuickReport {
    /// The unit of every length (also the new `Cal_Units`).
    #[serde(serialize_with = "ser::unit")]
    pub unit: LengthUnit,
    /// The axis detect.
    pub axis: AxisReport,
    /// The K written, units per pixel.
    #[serde(serialize_with = "ser::matrix")]
    pub k: Matrix2<f64>,
    /// The dot diameter given.
    pub diameter: f64,
    /// The mark size the camera reported, pixels (native width, height).
    #[serde(serialize_with = "ser::vector")]
    pub size_px: Vector2<f64>,
    /// The confirming trigger's mark size with the new K (width, height).
    #[serde(serialize_with = "ser::vector")]
    pub confirm_size: Vector2<f64>,
    /// Largest `|confirm size − diameter|`.
    pub size_error: f64,
    /// Largest disagreement between the bump moves and the mark motion K predicts for them
    /// (shows rotation or anisotropy Q cannot represent).
    pub bump_error: f64,
    /// The working-distance change the new K implies against the previous calibration's
    /// (`None`: there was none).
    pub k_change: Option<KChange>,
    /// The `Cal_Date` written.
    pub date: String,
    /// A non-fatal problem: a reading outside the image (the resolution setting is wrong; see
    /// the module doc). Also in `VisionLastStatus`.
    pub warning: Option<String>,
}

/// One dot of the verify walk. Lengths in the report's unit, work frame.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DotVerify {
    /// The dot's number on the sheet (1-based, walk order).
    pub dot: usize,
    /// Nominal position (the G90 target).
    #[serde(serialize_with = "ser::point")]
    pub nominal: Point2<f64>,
    /// Where the walk's sheet fit puts the dot.
    #[serde(serialize_with = "ser::point")]
    pub expected: Point2<f64>,
    /// Where the re-walk saw it with the new K and offset.
    #[serde(serialize_with = "ser::point")]
    pub observed: Point2<f64>,
    /// `observed − expected`.
    #[serde(serialize_with = "ser::vector")]
    pub residual: Vector2<f64>,
}

/// What `M283 Cn` measured and wrote: everything the manual's result popup shows. Lengths in
/// `unit`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SheetReport {
    /// The sheet walked.
    pub sheet: u32,
    /// The unit of every length (also the new `Cal_Units`).
    #[serde(serialize_with = "ser::unit")]
    pub unit: LengthUnit,
    /// The axis detect.
    pub axis: AxisReport,
    /// The K written, units per pixel.
    #[serde(serialize_with = "ser::matrix")]
    pub k: Matrix2<f64>,
    /// Per-axis scale: units per pixel along machine X and Y (K's column norms).
    #[serde(serialize_with = "ser::vector")]
    pub scale: Vector2<f64>,
    /// Camera rotation left in K after the remap, degrees counter-clockwise.
    pub camera_rotation_deg: f64,
    /// RMS disagreement of the probe moves with K, units.
    pub k_rms: f64,
    /// Sheet rotation on the table, degrees counter-clockwise.
    pub sheet_rotation_deg: f64,
    /// Measured print scale of the sheet along its X and Y (1 = true size).
    #[serde(serialize_with = "ser::vector")]
    pub sheet_scale: Vector2<f64>,
    /// RMS residual of the sheet fit over the walk, units.
    pub walk_rms: f64,
    /// The camera tool whose offset was written.
    pub tool: u32,
    /// Its X/Y offset before.
    #[serde(serialize_with = "ser::vector")]
    pub offset_before: Vector2<f64>,
    /// Its X/Y offset written.
    #[serde(serialize_with = "ser::vector")]
    pub offset_written: Vector2<f64>,
    /// The verify walk, one entry per dot.
    pub verify: Vec<DotVerify>,
    /// RMS of the verify residuals.
    pub verify_rms: f64,
    /// Largest verify residual.
    pub verify_max: f64,
    /// The optical centre: measured by the lift, or kept.
    pub centre: CentreReport,
    /// The working-distance change the new K implies against the previous calibration's
    /// (`None`: there was none).
    pub k_change: Option<KChange>,
    /// Number of camera triggers used.
    pub triggers: usize,
    /// The `Cal_Date` written.
    pub date: String,
    /// A non-fatal problem: a reading outside the image (the resolution setting is wrong; see
    /// the module doc), or a lift that could not measure the centre. Also in
    /// `VisionLastStatus`.
    pub warning: Option<String>,
}

/// The working-distance change a new K implies against the previous calibration's (scale ∝
/// working distance: each M283 measures K at the current height, so against the last K it
/// measures how far the camera now looks from).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct KChange {
    /// `√|det K_new| / √|det K_old| − 1`, percent: + the camera now looks from farther.
    pub change_pct: f64,
    /// The same as a length, `VisionWorkingDistance` × `change_pct` / 100, the report's unit
    /// (0 when `VisionWorkingDistance` is 0).
    pub change: f64,
}

/// The change from the calibration in `params` (K converted to `unit`) to `k` (`unit` per
/// pixel); `None` when there was none (K all zero).
fn k_change(params: &Params, unit: LengthUnit, k: Matrix2<f64>) -> Option<KChange> {
    let scale = |m: Matrix2<f64>| m.determinant().abs().sqrt();
    let (old, new) = (scale(k_in(params, unit)), scale(k));
    let ratio = new / old - 1.0;
    (old > 0.0 && ratio.is_finite()).then(|| KChange {
        change_pct: ratio * 100.0,
        change: LengthUnit::Inch.convert(params.working_distance_in(), unit) * ratio,
    })
}

/// The optical centre as the sheet walk left it: measured by the calibration lift, or kept.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CentreReport {
    /// How far the camera rose (machine +Z), the report's unit; 0 when it did not.
    pub lift: f64,
    /// True when the lift measured the centre (written with its σ); false: the offset and
    /// `VisionPxCenterSigmaPx` were kept as they were.
    pub measured: bool,
    /// `VisionPxCenterOffsetX/Y` written (measured) or kept, native pixels.
    #[serde(serialize_with = "ser::vector")]
    pub offset_px: Vector2<f64>,
    /// The centre's 1σ, the larger pixel axis's, pixels: measured now, or kept (0: never
    /// measured).
    pub sigma_px: f64,
    /// Pairs of readings (calibration height, lifted) the fit used.
    pub pairs: usize,
    /// The working distance the scale change implies, the report's unit: `lift·r/(1 − r)`
    /// (0 when not measured).
    pub working_distance: f64,
    /// Why the centre was not measured (also the report's warning when the lift was asked for).
    pub note: Option<String>,
}

/// M283's report (JSON: the inner report with `"mode": "quick"` or `"sheet"`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "mode", rename_all = "lowercase")]
pub enum CalReport {
    /// `Qd`.
    Quick(QuickReport),
    /// `Cn`.
    Sheet(SheetReport),
}

/// What a successful calibration asks the module to write; nothing is written yet.
pub(crate) struct Solution {
    /// K, units (the machine's, at calibration) per pixel.
    pub(crate) k: Matrix2<f64>,
    pub(crate) remap: Remap,
    /// The camera tool and its new X/Y table offset, current units (sheet walk only).
    pub(crate) tool_offset: Option<(u32, Vector2<f64>)>,
    /// The measured `VisionPxCenterOffsetX/Y` (pixels) and its 1σ (pixels), or `None`: keep
    /// both as they are.
    pub(crate) centre: Option<(Vector2<f64>, f64)>,
    pub(crate) report: CalReport,
}

impl CalReport {
    /// The `Cal_Date` the calibration writes.
    #[must_use]
    pub fn date(&self) -> &str {
        match self {
            CalReport::Quick(r) => &r.date,
            CalReport::Sheet(r) => &r.date,
        }
    }

    /// The calibration's non-fatal problem, if any.
    #[must_use]
    pub fn warning(&self) -> Option<&str> {
        match self {
            CalReport::Quick(r) => r.warning.as_deref(),
            CalReport::Sheet(r) => r.warning.as_deref(),
        }
    }
}

/// The resolution check of the module doc over the calibration's readings: the first reading
/// outside the image, and how many were.
fn resolution_warning(params: &Params, shots: &[Shot]) -> Option<String> {
    let outside: Vec<String> = shots.iter().filter_map(|s| outside_image_note(params, s.native)).collect();
    let first = outside.first()?;
    Some(if outside.len() == 1 {
        first.clone()
    } else {
        format!("{} of {} calibration readings were outside the image; the first: {first}", outside.len(), shots.len())
    })
}

fn fail(reason: impl Into<String>) -> VisionError {
    VisionError::Calibration { reason: reason.into() }
}

/// A capture during calibration.
#[derive(Debug, Clone, Copy)]
struct Shot {
    pos: Point2<f64>,
    native: Point2<f64>,
    reading: Reading,
    dot: usize,
    /// Taken by the sheet walk proper (at the calibration height), not by the lift.
    in_fit: bool,
}

/// An incremental rapid by `d` (program frame), absolute again after it (the Vision M-codes
/// expect absolute programs, as the manual's do).
pub(crate) fn relative_move(d: vision_math::Vector2<f64>) -> MachineCommand {
    MachineCommand::MoveBy(d)
}

/// An absolute rapid to `target` (program frame).
pub(crate) fn absolute_move(target: Point2<f64>) -> MachineCommand {
    MachineCommand::MoveTo(target)
}

/// Where a walker's readings come from.
enum Source<'a> {
    /// The camera, triggered where the walker's moves (run on the machine) left it.
    Live(&'a mut dyn CameraDriver),
    /// Readings taken before, each with the program position it was taken at. Moves are not
    /// run: the walker only tracks where they would have gone (`at`). A trigger past the last
    /// reading stops the walk and records where that capture is `needed`.
    /// `lift`: how far above the walk's start Z the moves so far left the head (current units).
    Replay { taken: &'a [(Point2<f64>, Reading)], next: usize, at: Point2<f64>, lift: f64, needed: Option<WalkTarget> },
}

/// Moves, dwells and triggers; writes every trigger to the DRO as it happens.
pub(crate) struct Walker<'a> {
    machine: &'a mut dyn Machine,
    source: Source<'a>,
    params: &'a Params,
    dro: &'a mut Dro,
    unit: LengthUnit,
    shots: Vec<Shot>,
    triggers: usize,
    /// Every line run on the machine (on a replay: that would have run), in order (M283's
    /// reply lists them).
    ran: Vec<String>,
    /// The last trigger's reading (a failed one too), for the `Last*` telemetry.
    last: Option<Reading>,
    /// The best K (current units per pixel) and remap known so far, for the DRO: the module's
    /// calibration at the start, then each one the routine solves.
    known: Option<(Matrix2<f64>, Remap)>,
    /// True while the calibration lift reads: its shots stay out of the sheet fit.
    lifting: bool,
}

impl<'a> Walker<'a> {
    /// A walker that moves `machine` (whose units are `unit`) and triggers `driver`, dwelling
    /// `VisionTriggerSettleSec` after every move.
    pub(crate) fn new(
        machine: &'a mut dyn Machine,
        driver: &'a mut dyn CameraDriver,
        params: &'a Params,
        dro: &'a mut Dro,
        unit: LengthUnit,
    ) -> Self {
        Walker::with_source(machine, Source::Live(driver), params, dro, unit)
    }

    /// A walker that replays `taken` (readings with the program positions they were taken at)
    /// from `start`: it runs nothing on `machine` and only reads it (units, tool offsets, clock).
    /// Only the newest reading reaches the DRO: the older ones were shown when they were new.
    pub(crate) fn replay(
        machine: &'a mut dyn Machine,
        taken: &'a [(Point2<f64>, Reading)],
        start: Point2<f64>,
        params: &'a Params,
        dro: &'a mut Dro,
        unit: LengthUnit,
    ) -> Self {
        Walker::with_source(
            machine,
            Source::Replay { taken, next: 0, at: start, lift: 0.0, needed: None },
            params,
            dro,
            unit,
        )
    }

    fn with_source(
        machine: &'a mut dyn Machine,
        source: Source<'a>,
        params: &'a Params,
        dro: &'a mut Dro,
        unit: LengthUnit,
    ) -> Self {
        let known = Some((k_in(params, unit), params.remap()));
        Walker {
            machine,
            source,
            params,
            dro,
            unit,
            shots: Vec::new(),
            triggers: 0,
            ran: Vec::new(),
            last: None,
            known,
            lifting: false,
        }
    }

    /// Moves the head by `dz` along machine Z (current units, relative, then absolute again)
    /// and settles. `Err(true)`: the move ran but the settle failed (the head moved);
    /// `Err(false)`: the controller refused the move (it did not).
    fn move_z(&mut self, dz: f64) -> Result<(), (bool, VisionError)> {
        let command = MachineCommand::MoveZBy(dz);
        if let Source::Replay { lift, .. } = &mut self.source {
            *lift += dz;
            self.ran.extend(self.machine.gcode(&command).map_err(|e| (false, e.into()))?);
            return Ok(());
        }
        let lines = self.machine.command(&command).map_err(|e| (false, e.into()))?;
        self.ran.extend(lines);
        self.machine.dwell(self.params.trigger_settle_s()).map_err(|e| (true, e.into()))
    }

    /// The lines run so far, in order, and the last trigger's reading.
    pub(crate) fn into_ran(self) -> (Vec<String>, Option<Reading>) {
        (self.ran, self.last)
    }

    /// On a replay that ran out of readings: where the next capture must be taken (program
    /// frame).
    pub(crate) fn needed(&self) -> Option<WalkTarget> {
        match self.source {
            Source::Replay { needed, .. } => needed,
            Source::Live(_) => None,
        }
    }

    /// Runs `command` (a move to `target`, program frame) on the machine, records its lines,
    /// settles.
    fn run(&mut self, command: MachineCommand, target: Point2<f64>) -> Result<(), VisionError> {
        let lines = if let Source::Replay { at, .. } = &mut self.source {
            *at = target;
            self.machine.gcode(&command)?
        } else {
            let lines = self.machine.command(&command)?;
            self.machine.dwell(self.params.trigger_settle_s())?;
            lines
        };
        self.ran.extend(lines);
        Ok(())
    }

    fn position(&self) -> Result<Point2<f64>, VisionError> {
        match self.source {
            Source::Replay { at, .. } => Ok(at),
            Source::Live(_) => Ok(checked::program_position(self.machine)?),
        }
    }

    /// Incremental move to `target` (program frame), then back to G90, then settle.
    fn move_to(&mut self, target: Point2<f64>) -> Result<(), VisionError> {
        self.run(relative_move(target - self.position()?), target)
    }

    /// Absolute G90 move to `target`, then settle.
    fn move_abs(&mut self, target: Point2<f64>) -> Result<(), VisionError> {
        self.run(absolute_move(target), target)
    }

    /// Triggers and records a shot of walk dot `dot`; returns its index. The DRO shows the
    /// reading at once (through the best K known so far), or the failure.
    fn shoot(&mut self, dot: usize) -> Result<usize, VisionError> {
        self.triggers += 1;
        let (reading, pos, newest) = match &mut self.source {
            Source::Live(driver) => match driver.trigger() {
                Ok(r) => (r, checked::program_position(self.machine)?, true),
                Err(e) => {
                    let e = VisionError::from(e);
                    self.dro.failure(Some(-1), &e);
                    return Err(e);
                }
            },
            Source::Replay { taken, next, at, lift, needed } => {
                let Some(&(pos, reading)) = taken.get(*next) else {
                    *needed = Some(WalkTarget { at: *at, lift: *lift });
                    return Err(fail("a capture is needed to go on (the stepwise M283 walk)"));
                };
                *next += 1;
                (reading, pos, *next == taken.len())
            }
        };
        self.last = Some(reading);
        if !reading.found() {
            let why = match &self.source {
                Source::Live(driver) => driver.miss_reason().map(|r| format!(" ({r})")).unwrap_or_default(),
                Source::Replay { .. } => String::new(),
            };
            let e = fail(format!(
                "the camera lost the mark (NG / no mark{why}) at X{} Y{} — keep the dot in view, check lighting \
                 and the camera job",
                fixed(pos.x, 4),
                fixed(pos.y, 4)
            ));
            if newest {
                self.dro.failure(Some(i64::from(reading.judgment.code())), &e);
            }
            return Err(e);
        }
        let native = Point2::new(reading.x_px, reading.y_px);
        if newest {
            let chain = self.known.and_then(|(k, remap)| chain_with(self.params, k, remap).ok());
            self.dro.reading(chain.as_ref(), centred_px(self.params, native), &reading);
        }
        self.shots.push(Shot { pos, native, reading, dot, in_fit: !self.lifting });
        Ok(self.shots.len() - 1)
    }

    /// The axis-detect bump from the current position; returns the remap and the two pairs.
    /// Tells the host's progress sink where the walk is; a replay (the stepwise walk) tells
    /// nothing, its stages were told when they ran.
    fn progress(&mut self, progress: WalkProgress) {
        if matches!(self.source, Source::Live(_)) {
            self.dro.progress(progress);
        }
    }

    fn axis_detect(&mut self) -> Result<(AxisReport, [(usize, usize); 2]), VisionError> {
        let bump = LengthUnit::Inch.convert(BUMP_IN, self.unit);
        let start = self.position()?;
        let s0 = self.shoot(0)?;
        self.move_to(start + Vector2::new(bump, 0.0))?;
        let s1 = self.shoot(0)?;
        self.move_to(start + Vector2::new(bump, bump))?;
        let s2 = self.shoot(0)?;
        self.move_to(start)?;
        let px = self.shots[s1].native - self.shots[s0].native;
        let py = self.shots[s2].native - self.shots[s1].native;
        let remap = detect_remap(px, py)?;
        Ok((AxisReport { remap, bump, pixels_for_x: px, pixels_for_y: py }, [(s0, s1), (s1, s2)]))
    }
}

/// The remap under which a +X camera move moves the mark towards −x and a +Y move towards −y
/// (the mark stays put, so relative to the camera it moves against the motion).
///
/// # Errors
/// The mark hardly moved, or both bumps moved it the same way.
pub fn detect_remap(pixels_for_x: Vector2<f64>, pixels_for_y: Vector2<f64>) -> Result<Remap, VisionError> {
    let (nx, ny) = (pixels_for_x.norm(), pixels_for_y.norm());
    if !(nx.is_finite() && ny.is_finite()) || nx < MIN_BUMP_PX || ny < MIN_BUMP_PX {
        return Err(fail(format!(
            "axis detect: the mark moved only {nx:.1} px for the X bump and {ny:.1} px for the Y bump — keep a \
             mark in view, and make sure the camera moves with the head"
        )));
    }
    let (ux, uy) = (pixels_for_x / nx, pixels_for_y / ny);
    if (ux.x * uy.y - ux.y * uy.x).abs() < 0.5 {
        return Err(fail(
            "axis detect: the X and Y bumps moved the mark in nearly the same direction — the mark may have \
             moved or another mark was found; re-jog and retry",
        ));
    }
    let score = |r: &Remap| -r.apply(ux).x - r.apply(uy).y;
    let best = Remap::all().into_iter().max_by(|a, b| score(a).total_cmp(&score(b))).unwrap_or_default();
    Ok(best)
}

/// `(K·R·(pᵢ − p_b), −(Cᵢ − C_b))` for every pair, ready for [`solve_linear`].
fn motion_pairs(shots: &[Shot], pairs: &[(usize, usize)], remap: Remap) -> (Vec<Vector2<f64>>, Vec<Vector2<f64>>) {
    pairs.iter().map(|(b, p)| (remap.apply(shots[*p].native - shots[*b].native), shots[*b].pos - shots[*p].pos)).unzip()
}

fn solve_k(shots: &[Shot], pairs: &[(usize, usize)], remap: Remap) -> Result<(Matrix2<f64>, f64), VisionError> {
    let (p, q) = motion_pairs(shots, pairs, remap);
    let fit = solve_linear(&p, &q).map_err(|e| fail(format!("K from the probe moves: {e}")))?;
    Ok((fit.m, fit.rms))
}

/// `M283 Qd`.
pub(crate) fn quick(walker: &mut Walker<'_>, params: &Params, diameter: f64) -> Result<Solution, VisionError> {
    let (axis, pairs) = walker.axis_detect()?;
    let remap = axis.remap;
    let s = walker.shoot(0)?;
    let r = walker.shots[s].reading;
    let (w, h) = if remap.swap_xy { (r.height_px, r.width_px) } else { (r.width_px, r.height_px) };
    if !(w.is_finite() && h.is_finite() && w > 0.0 && h > 0.0) {
        return Err(fail(format!(
            "the camera job does not report the mark's width and height — M283 Q needs a camera \
             output that includes them (judgment,count,x,y,width,height,angle,score); or use {}",
            walker.machine.controller().sheet_calibration()
        )));
    }
    let k = Matrix2::new(diameter / w, 0.0, 0.0, diameter / h);
    let (p, q) = motion_pairs(&walker.shots, &pairs, remap);
    check_quick_scale(diameter, k, &p, &q, walker.unit)?;
    walker.known = Some((k, remap));
    let chain = chain_with(params, k, remap)?;
    let c = walker.shoot(0)?;
    let (cw, ch) = mark_size(&chain, &walker.shots[c].reading);
    let size_error = (cw - diameter).abs().max((ch - diameter).abs());
    let bump_error = p.iter().zip(&q).map(|(p, q)| (k * p - q).norm()).fold(0.0, f64::max);
    let report = QuickReport {
        unit: walker.unit,
        axis,
        k,
        diameter,
        size_px: Vector2::new(r.width_px, r.height_px),
        confirm_size: Vector2::new(cw, ch),
        size_error,
        bump_error,
        k_change: k_change(params, walker.unit, k),
        date: walker.machine.now().iso_local(),
        warning: resolution_warning(params, &walker.shots),
    };
    Ok(Solution { k, remap, tool_offset: None, centre: None, report: CalReport::Quick(report) })
}

/// How far (as a factor either way) the scale `Qd` implies may be from the scale the axis-detect
/// bump measured. Mark-size noise is a few percent; a unit mix-up is 25.4×.
pub const QUICK_SCALE_TOLERANCE: f64 = 1.5;

/// Refuses a `Qd` whose K (`k`) disagrees with the bump moves `(K·pixels, −motion)` by more
/// than [`QUICK_SCALE_TOLERANCE`], naming the likely unit mix-up (lengths in `unit`).
fn check_quick_scale(
    diameter: f64,
    k: Matrix2<f64>,
    pixels: &[Vector2<f64>],
    motion: &[Vector2<f64>],
    unit: LengthUnit,
) -> Result<(), VisionError> {
    let implied: f64 = pixels.iter().map(|p| (k * p).norm()).sum();
    let moved: f64 = motion.iter().map(|m| m.norm()).sum();
    let ratio = implied / moved;
    if ratio.is_finite() && (1.0 / QUICK_SCALE_TOLERANCE..=QUICK_SCALE_TOLERANCE).contains(&ratio) {
        return Ok(());
    }
    let near = |factor: f64| (ratio / factor - 1.0).abs() < 0.2;
    let hint = match unit {
        LengthUnit::Inch if near(MM_PER_INCH) => {
            format!("; is it a millimetre value in an inch program (Q{} in inches)?", number(diameter / MM_PER_INCH))
        }
        LengthUnit::Millimetre if near(1.0 / MM_PER_INCH) => {
            format!(
                "; is it an inch value in a millimetre program (Q{} in millimetres)?",
                number(diameter * MM_PER_INCH)
            )
        }
        _ => String::new(),
    };
    Err(fail(format!(
        "the dot diameter Q{} {} makes the marks move {}× the distance the axis-detect \
         bump moved{hint} — give the printed dot's diameter in the program's units",
        number(diameter),
        unit.short_name(),
        number(ratio)
    )))
}

/// Positions per axis of the calibration lift's grid (25 pairs of readings: the centre to
/// ~0.7 px at 0.1 px noise and a 4 % lift; 16 left the ±4 % heights at 1.19× the floor).
pub const LIFT_GRID: usize = 5;

/// The lift's camera positions about `around` (program frame): a [`LIFT_GRID`]² grid `±step`
/// wide, serpentine so each move is one grid step, every position farther than `step` from
/// `around` brought in radially onto that circle.
///
/// Decision (issue 33): the walk has read the mark `step` away from the image centre along each
/// axis (its probe moves), and no farther; a square grid's corners lie √2 × `step` out, where a
/// camera that searches only a disc about its centre does not find a mark (the image path on
/// the built-in world: a `VisionCameraSearchRadius` of 572 px for a 247 px dot, so a mark is
/// whole inside it up to 448 px out; the probes reach 355 px, the corners 502 px). Within the
/// circle every reading lies where a probe proved the camera reads, whatever shape its field
/// has; the spread of positions, which sets the centre's σ, shrinks by only √(0.5 / 0.38) =
/// 1.15× against the square.
fn lift_positions(around: Point2<f64>, step: f64) -> Vec<Point2<f64>> {
    let g = LIFT_GRID;
    #[allow(clippy::cast_precision_loss)]
    let t = |i: usize| -1.0 + 2.0 * i as f64 / (g - 1) as f64;
    (0..g)
        .flat_map(|i| (0..g).map(move |j| (i, if i % 2 == 0 { j } else { g - 1 - j })))
        .map(|(i, j)| {
            let v = Vector2::new(t(i), t(j));
            around + v / v.norm().max(1.0) * step
        })
        .collect()
}

/// What the calibration lift came to.
struct Lifted {
    /// The measured `VisionPxCenterOffsetX/Y` (pixels) and 1σ (pixels), or `None` (keep both).
    centre: Option<(Vector2<f64>, f64)>,
    report: CentreReport,
    /// Why a lift that was asked for did not measure the centre.
    warning: Option<String>,
}

/// The calibration lift (see the module doc): reads the mark of dot `dot` (its centre at
/// `around`, program frame) from the camera positions [`lift_positions`] gives at the
/// calibration height, rises `VisionCalibrationLift`, reads the same positions again, comes
/// back down and fits the pixel the image shrank about.
///
/// Decision: a lift that cannot measure (the rise refused, a mark lost, a fit without a scale
/// change) does not cost the calibration: the walk commits with the centre kept and a warning.
/// Only a head that cannot come back down fails the walk (the verify walk and the commit
/// would run at the wrong height).
///
/// # Errors
/// The move back down failed.
fn lift_centre(
    walker: &mut Walker<'_>,
    params: &Params,
    around: Point2<f64>,
    step: f64,
    dot: usize,
) -> Result<Lifted, VisionError> {
    let lift_in = params.calibration_lift_in();
    let lift = LengthUnit::Inch.convert(lift_in, walker.unit);
    // `rose`: the head went up (and came back) before the lift gave up.
    let kept = |rose: bool, note: String, warn: bool| Lifted {
        centre: None,
        report: CentreReport {
            lift: if rose { lift } else { 0.0 },
            measured: false,
            offset_px: params.calibration.center_offset(),
            sigma_px: params.px_center_sigma_px(),
            pairs: 0,
            working_distance: 0.0,
            note: Some(note.clone()),
        },
        warning: warn.then_some(note),
    };
    if lift_in == 0.0 {
        return Ok(kept(false, "VisionCalibrationLift is 0: calibrated at one height".into(), false));
    }
    let positions = lift_positions(around, step);
    walker.lifting = true;
    let read = |walker: &mut Walker<'_>, at: &[Point2<f64>]| -> Result<Vec<Point2<f64>>, VisionError> {
        let mut out = Vec::with_capacity(at.len());
        for p in at {
            walker.move_abs(*p)?;
            let s = walker.shoot(dot)?;
            out.push(walker.shots[s].native);
        }
        Ok(out)
    };
    let cannot = |what: &str, e: &VisionError| {
        // The failure's own reason: the calibration stands, so nothing but the centre "failed"
        // or was "left unchanged".
        let why = match e {
            VisionError::Calibration { reason } => reason.clone(),
            other => other.to_string(),
        };
        format!(
            "the optical centre was not measured ({what}: {why}); VisionPxCenterOffset kept — the calibration \
             stands at this height"
        )
    };
    let before = match read(walker, &positions) {
        Ok(v) => v,
        // A stepwise walk that ran out of readings: the host captures, the replay goes on.
        Err(e) if walker.needed().is_some() => {
            walker.lifting = false;
            return Err(e);
        }
        Err(e) => {
            walker.lifting = false;
            return Ok(kept(false, cannot("a reading at the calibration height failed", &e), true));
        }
    };
    let risen;
    let after = match walker.move_z(lift) {
        Err((moved, e)) => {
            risen = moved;
            Err(cannot(if moved { "the lift did not settle" } else { "the lift move was refused" }, &e))
        }
        Ok(()) => {
            risen = true;
            let back: Vec<Point2<f64>> = positions.iter().rev().copied().collect();
            read(walker, &back)
                .map(|mut v| {
                    v.reverse();
                    v
                })
                .map_err(|e| cannot("a reading at the lifted height failed", &e))
        }
    };
    walker.lifting = false;
    if walker.needed().is_some() {
        return Err(fail("a capture is needed to go on (the stepwise M283 walk)"));
    }
    if risen {
        if let Err((moved, e)) = walker.move_z(-lift) {
            return Err(if moved {
                e
            } else {
                fail(format!(
                    "the camera could not come back down from the calibration lift ({e}): it is {} {} above the \
                     calibration height — lower Z by that much before cutting, then re-run M283",
                    number(lift),
                    walker.unit.short_name()
                ))
            });
        }
    }
    let after = match after {
        Ok(v) => v,
        Err(note) => return Ok(kept(risen, note, true)),
    };
    let res = crate::module::capture::resolution(params);
    let fit = match fit_centre(&before, &after, params.camera_noise_px()) {
        Ok(fit) if fit.ratio < 1.0 => fit,
        Ok(fit) => {
            return Ok(kept(
                true,
                format!(
                    "the optical centre was not measured: the image grew ×{} as the camera rose — check that +Z \
                     moves the head up; VisionPxCenterOffset kept",
                    number(1.0 / fit.ratio)
                ),
                true,
            ))
        }
        Err(e) => return Ok(kept(true, cannot("the fit", &e.into()), true)),
    };
    let inside = (0.0..=res.x).contains(&fit.centre.x) && (0.0..=res.y).contains(&fit.centre.y);
    if !inside {
        return Ok(kept(
            true,
            format!(
                "the optical centre was not measured: the lift put it at pixel ({:.1}, {:.1}), outside the \
                 {}×{} image — check VisionCameraResX/ResY; VisionPxCenterOffset kept",
                fit.centre.x, fit.centre.y, res.x, res.y
            ),
            true,
        ));
    }
    let offset = fit.centre.coords - res * 0.5;
    let sigma = fit.sigma.x.max(fit.sigma.y);
    Ok(Lifted {
        centre: Some((offset, sigma)),
        report: CentreReport {
            lift,
            measured: true,
            offset_px: offset,
            sigma_px: sigma,
            pairs: fit.pairs,
            working_distance: lift * fit.ratio / (1.0 - fit.ratio),
            note: None,
        },
        warning: None,
    })
}

/// `M283 Cn`: walk, solve, verify (compensating for the offset not yet written); writes nothing.
pub(crate) fn sheet_walk(walker: &mut Walker<'_>, params: &Params, n: u32, tool: u32) -> Result<Solution, VisionError> {
    let sheet = cal_sheet(n).ok_or_else(|| VisionError::UnknownSheet { sheet: n, known: known_sheets() })?;
    let unit = walker.unit;
    let nominal = sheet.dots(unit);
    let offset_before = crate::controller::tool_offset(&*walker.machine, tool)?;

    // 1. Axis detect: the remap and a first K from the two bumps.
    let (axis, bumps) = walker.axis_detect()?;
    let remap = axis.remap;
    let mut pairs: Vec<(usize, usize)> = bumps.to_vec();
    let (mut k, _) = solve_k(&walker.shots, &pairs, remap)?;
    walker.known = Some((k, remap));
    let res = crate::module::capture::resolution(params);
    let pixel = k.determinant().abs().sqrt();
    let probe = (PROBE_FOV_FRACTION * res.x.min(res.y) * pixel).max(axis.bump);
    let probes =
        [Vector2::new(probe, 0.0), Vector2::new(0.0, probe), Vector2::new(-probe, 0.0), Vector2::new(0.0, -probe)];

    // 2. Walk: centre each dot, probe around it, refine K as pairs accumulate.
    let d_of = |shot: &Shot, k: Matrix2<f64>| -> Result<Point2<f64>, VisionError> {
        Ok(shot.pos + chain_with(params, k, remap)?.delta(shot.native))
    };
    let mut station = d_of(&walker.shots[0], k)?;
    for (i, n_i) in nominal.iter().enumerate() {
        walker.progress(WalkProgress::SheetDot { dot: i + 1, dots: nominal.len() });
        if i > 0 {
            station += n_i - nominal[i - 1];
        }
        walker.move_to(station)?;
        let base = walker.shoot(i)?;
        for m in probes {
            walker.move_to(station + m)?;
            let s = walker.shoot(i)?;
            pairs.push((base, s));
        }
        k = solve_k(&walker.shots, &pairs, remap)?.0;
        walker.known = Some((k, remap));
        // Next station from where this dot really is.
        station = d_of(&walker.shots[base], k)?;
    }

    // 3. The final K over every pair.
    let (k, k_rms) = solve_k(&walker.shots, &pairs, remap)?;
    walker.known = Some((k, remap));

    // 3b. The optical centre from the lift over the last dot; the offset below is solved at it.
    walker.progress(WalkProgress::Lift);
    let lifted = lift_centre(walker, params, station, probe, nominal.len() - 1)?;
    let mut solved = params.clone();
    if let Some((offset, sigma)) = lifted.centre {
        solved.calibration = solved.calibration.with_centre(offset, sigma)?;
    }
    let params = &solved;
    let chain: PixelChain = chain_with(params, k, remap)
        .map_err(|e| fail(format!("the solved K is unusable ({e}); check that the camera is rigidly mounted")))?;
    if k.determinant() <= 0.0 {
        return Err(fail("the solved K is mirrored against the axis detect — the mark moved during the walk; retry"));
    }

    // 4. Sheet pose and camera offset from the dots.
    let mut sums = vec![(Vector2::zeros(), 0.0f64); nominal.len()];
    for s in walker.shots.iter().filter(|s| s.in_fit) {
        sums[s.dot].0 += (s.pos + chain.delta(s.native)).coords;
        sums[s.dot].1 += 1.0;
    }
    let seen: Vec<Point2<f64>> = sums.iter().map(|(sum, count)| Point2::from(sum / *count)).collect();
    let fit = fit_rectangle(&nominal, &seen).map_err(|e| fail(format!("sheet fit: {e}")))?;
    let dev = (fit.transform.scale.x - 1.0).abs().max((fit.transform.scale.y - 1.0).abs());
    if dev > MAX_SHEET_SCALE_DEV {
        return Err(fail(format!(
            "the sheet measures {:.4} x {:.4} of its nominal size — wrong sheet number, a sheet printed with \
             'Fit to Page', or the camera found other marks",
            fit.transform.scale.x, fit.transform.scale.y
        )));
    }
    let b = fit.transform.offset();
    // K and the tool offset are kept along the machine axes; the walk measured in the program
    // frame, which a G5x rotation θ₀ (LinuxCNC) turns against them.
    let theta0 = walker.machine.controller().base_rotation(&*walker.machine)?;
    let offset_written = offset_before - program_to_machine(b, theta0);

    // 5. Verify: the optical axis on every dot's nominal position in G90 with the new K, seen
    //    as the new offset will see it (the module doc explains the `+ b`).
    let mut verify = Vec::with_capacity(nominal.len());
    for (i, n_i) in nominal.iter().enumerate() {
        walker.progress(WalkProgress::Verify { dot: i + 1, dots: nominal.len() });
        walker.move_abs(n_i + b)?;
        let s = walker.shoot(i)?;
        let shot = walker.shots[s];
        let observed = shot.pos - b + chain.delta(shot.native);
        let expected = fit.transform.apply(*n_i) - b;
        verify.push(DotVerify { dot: i + 1, nominal: *n_i, expected, observed, residual: observed - expected });
    }
    #[allow(clippy::cast_precision_loss)]
    let verify_rms = (verify.iter().map(|v| v.residual.norm_squared()).sum::<f64>() / verify.len() as f64).sqrt();
    let verify_max = verify.iter().map(|v| v.residual.norm()).fold(0.0, f64::max);
    let k = if theta0 == 0.0 { k } else { rotation(theta0) * k };
    let report = SheetReport {
        sheet: n,
        unit,
        axis,
        k,
        scale: Vector2::new(k.column(0).norm(), k.column(1).norm()),
        camera_rotation_deg: (k[(1, 0)] - k[(0, 1)]).atan2(k[(0, 0)] + k[(1, 1)]).to_degrees(),
        k_rms,
        sheet_rotation_deg: fit.transform.theta_deg(),
        sheet_scale: fit.transform.scale,
        walk_rms: fit.rms,
        tool,
        offset_before,
        offset_written,
        verify,
        verify_rms,
        verify_max,
        centre: lifted.report,
        k_change: k_change(params, unit, k),
        triggers: walker.triggers,
        date: walker.machine.now().iso_local(),
        warning: resolution_warning(params, &walker.shots).or(lifted.warning),
    };
    let centre = lifted.centre;
    Ok(Solution { k, remap, tool_offset: Some((tool, offset_written)), centre, report: CalReport::Sheet(report) })
}

#[cfg(test)]
#[allow(clippy::float_cmp)]
mod tests {
    use super::*;

    #[test]
    fn the_lift_positions_stay_within_the_probes_reach() {
        let around = Point2::new(1.0, -2.0);
        let at = lift_positions(around, 0.5);
        assert_eq!(at.len(), LIFT_GRID * LIFT_GRID);
        assert!(at.iter().all(|p| (p - around).norm() <= 0.5 + 1e-12));
        // The axes' ends, the centre and the inner ring as the square grid has them; the
        // corners on the circle.
        let corner = Vector2::new(1.0, 1.0).normalize() * 0.5;
        for want in
            [Vector2::new(0.5, 0.0), Vector2::new(0.0, -0.5), Vector2::zeros(), Vector2::new(0.25, 0.25), corner]
        {
            assert!(at.iter().any(|p| (p - around - want).norm() < 1e-12), "{want}");
        }
        // Serpentine: no move longer than one grid step (0.25) along an axis.
        assert!(at.windows(2).all(|w| (w[1] - w[0]).amax() <= 0.25 + 1e-12));
    }

    #[test]
    fn remap_detection_for_all_eight_mountings() {
        for r in Remap::all() {
            // Mark motion in machine-aligned pixels is −x for +X and −y for +Y; the camera
            // reports it through R⁻¹, slightly rotated.
            let px = r.unapply(Vector2::new(-50.0, 2.0));
            let py = r.unapply(Vector2::new(-1.5, -49.0));
            assert_eq!(detect_remap(px, py), Ok(r));
        }
        assert!(detect_remap(Vector2::new(0.5, 0.0), Vector2::new(0.0, 50.0)).is_err());
        assert!(detect_remap(Vector2::new(50.0, 0.0), Vector2::new(49.0, 3.0)).is_err());
        assert!(detect_remap(Vector2::new(f64::NAN, 0.0), Vector2::new(0.0, 50.0)).is_err());
    }
}
