//! What M283 measured and wrote: the reports, and the solution the module commits.

use vision_math::{LengthUnit, Matrix2, Point2, Remap, Vector2};

use super::walk::Shot;
use crate::module::capture::{k_in, outside_image_note};
use crate::params::Params;
use crate::ser;

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
    /// `docs/calibration-solve.md`). Also in `VisionLastStatus`.
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
    /// The lens distortion measured with K.
    pub lens: LensReport,
    /// The working-distance change the new K implies against the previous calibration's
    /// (`None`: there was none).
    pub k_change: Option<KChange>,
    /// Number of camera triggers used.
    pub triggers: usize,
    /// The `Cal_Date` written.
    pub date: String,
    /// A non-fatal problem: a reading outside the image (the resolution setting is wrong; see
    /// `docs/calibration-solve.md`), or a lift that could not measure the centre. Also in
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
pub(super) fn k_change(params: &Params, unit: LengthUnit, k: Matrix2<f64>) -> Option<KChange> {
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

/// The lens distortion the sheet walk measured with K (OpenCV's Brown–Conrady coefficients on
/// coordinates normalised by `focal_px`), written to `VisionLensK1`..`P2`, their σ and
/// `VisionLensFocalPx`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LensReport {
    /// Radial `k1` (− barrel, + pincushion).
    pub k1: f64,
    /// Radial `k2`.
    pub k2: f64,
    /// Tangential `p1`.
    pub p1: f64,
    /// Tangential `p2`.
    pub p2: f64,
    /// The 1σ of `[k1, k2, p1, p2]`.
    pub sigma: [f64; 4],
    /// Which of them the walk's readings determined; one that was not is kept near 0 with its
    /// prior's σ (see `note`).
    pub measured: [bool; 4],
    /// The focal length the coefficients are normalised by, pixels.
    pub focal_px: f64,
    /// How far the lens moves the image's farthest corner, pixels.
    pub corner_px: f64,
    /// The farthest reading from the optical centre, pixels.
    pub reach_px: f64,
    /// RMS residual of the joint solve per pixel axis, pixels.
    pub rms_px: f64,
    /// Readings the solve used.
    pub readings: usize,
    /// Lens-grid positions where the camera found the mark, of `grid_asked`.
    pub grid_found: usize,
    /// Lens-grid positions read (`VisionCalibrationGrid`²).
    pub grid_asked: usize,
    /// What was not measured, or why there is no lens model, and what to do.
    pub note: Option<String>,
}

impl LensReport {
    /// No lens model: the chain stays linear, for `note`'s reason.
    pub(super) fn none(focal_px: f64, grid: (usize, usize), readings: usize, note: String) -> LensReport {
        LensReport {
            k1: 0.0,
            k2: 0.0,
            p1: 0.0,
            p2: 0.0,
            sigma: [0.0; 4],
            measured: [false; 4],
            focal_px,
            corner_px: 0.0,
            reach_px: 0.0,
            rms_px: 0.0,
            readings,
            grid_found: grid.0,
            grid_asked: grid.1,
            note: Some(note),
        }
    }
}

/// M283's report (JSON: the inner report with `"mode": "quick"` or `"sheet"`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "mode", rename_all = "lowercase")]
#[expect(clippy::large_enum_variant, reason = "one report per calibration, moved once, never held in bulk")]
pub enum CalReport {
    /// `Qd`.
    Quick(QuickReport),
    /// `Cn`.
    Sheet(SheetReport),
}

/// What a calibration does to the profile's lens.
pub(crate) enum LensUpdate {
    /// Leave it as it is.
    Keep,
    /// Write this one (`None`: no lens model).
    Write(Option<(vision_math::Lens, [f64; 4])>),
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
    /// The lens to write with its coefficients' 1σ (`None`: a linear chain); `Keep`: leave the
    /// profile's (a quick calibration reads one position and cannot measure it).
    pub(crate) lens: LensUpdate,
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

/// The resolution check (`docs/calibration-solve.md`) over the calibration's readings: the
/// first reading outside the image, and how many were.
pub(super) fn resolution_warning(params: &Params, shots: &[Shot]) -> Option<String> {
    let outside: Vec<String> = shots.iter().filter_map(|s| outside_image_note(params, s.native)).collect();
    let first = outside.first()?;
    Some(if outside.len() == 1 {
        first.clone()
    } else {
        format!("{} of {} calibration readings were outside the image; the first: {first}", outside.len(), shots.len())
    })
}
