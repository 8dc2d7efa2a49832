//! One trigger turned into an observed point (SPEC §2), shared by M281 and calibration.

use std::path::PathBuf;

use vision_math::{AlignmentChain, LengthUnit, Matrix2, PixelChain, Point2, Remap, Vector2};

use crate::controller::machine_to_program;
use crate::driver::{CameraDriver, Judgment, Reading};
use crate::error::VisionError;
use crate::machine::{checked, Machine};
use crate::params::Params;
use crate::ser;

/// A capture as M281 reports it. Lengths in the machine's current units (`unit`), program frame.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Capture {
    /// The machine unit every length below is in.
    #[serde(serialize_with = "ser::unit")]
    pub unit: LengthUnit,
    /// Commanded camera position `C`, program frame.
    #[serde(serialize_with = "ser::point")]
    pub commanded: Point2<f64>,
    /// Observed mark centre `O`, program frame (mapped through the active alignment, SPEC §2).
    #[serde(serialize_with = "ser::point")]
    pub observed: Point2<f64>,
    /// Offset `d = K·R·c` from the camera to the mark, work-frame axes.
    #[serde(serialize_with = "ser::vector")]
    pub offset: Vector2<f64>,
    /// Centred pixel offset `c` (after the centre shift, before remap and K), pixels.
    #[serde(serialize_with = "ser::vector")]
    pub centred_px: Vector2<f64>,
    /// Mark width along the camera's native x axis.
    pub width: f64,
    /// Mark height along the camera's native y axis.
    pub height: f64,
    /// Mark angle, degrees (0 when not reported).
    pub angle_deg: f64,
    /// Match score (0 when not reported).
    pub score: f64,
    /// The camera's judgment (never NG here: NG is an error).
    #[serde(serialize_with = "ser::judgment")]
    pub judgment: Judgment,
    /// 1-based index in the run's dot list, `None` outside a run.
    pub dot_index: Option<usize>,
    /// Pound-variable slot written besides slot 0 (1–4), `None` outside a run or past the 4th.
    pub slot: Option<u32>,
    /// Where M281 D1 saved the image.
    pub image: Option<PathBuf>,
    /// A non-fatal problem (e.g. no image appeared); also in `VisionLastStatus`.
    pub warning: Option<String>,
    /// How M281 re-centred over the mark before this reading, `None` when it read in one shot.
    pub recentred: Option<Recentred>,
}

/// M281's re-centring of one capture (`VisionRecenterPasses`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Recentred {
    /// Moves over the mark and triggers after the first.
    pub passes: i64,
    /// The centred pixel offset of the first reading, pixels.
    #[serde(serialize_with = "ser::vector")]
    pub first_px: Vector2<f64>,
    /// Whether one move was a probe (`VisionHeightProbePx`): the mark read on the far side of
    /// the centre to measure the image scale, the capture being the reading nearer the centre.
    pub probe: bool,
}

/// K converted from `Cal_Units` to `unit` (units per pixel).
pub(crate) fn k_in(params: &Params, unit: LengthUnit) -> Matrix2<f64> {
    params.cal_k() * params.cal_units().factor_to(unit)
}

/// The image resolution, pixels.
pub(crate) fn resolution(params: &Params) -> Vector2<f64> {
    Vector2::new(params.camera_res_x() as f64, params.camera_res_y() as f64)
}

/// A reading at native pixel `native` outside the image `VisionCameraResX` × `VisionCameraResY`
/// says the resolution setting does not match the camera: every offset is then measured from a
/// pixel that is not the optical centre (exact at the calibration height, wrong by the height
/// change times that distance elsewhere, and re-centring centres on it). `None` inside.
pub(crate) fn outside_image_note(params: &Params, native: Point2<f64>) -> Option<String> {
    let res = resolution(params);
    let inside = (0.0..=res.x).contains(&native.x) && (0.0..=res.y).contains(&native.y);
    (!inside).then(|| {
        format!(
            "the mark was reported at pixel ({:.1}, {:.1}), outside the {} x {} image of VisionCameraResX/ResY: \
             set them to the camera's resolution",
            native.x, native.y, res.x, res.y
        )
    })
}

/// The pixel centre offset, pixels.
pub(crate) fn center_offset(params: &Params) -> Vector2<f64> {
    Vector2::new(params.px_center_offset_x(), params.px_center_offset_y())
}

/// Native pixel `native` less the image centre and `PxCenterOffset` (what [`PixelChain::centred`]
/// gives, without needing a K), pixels.
pub(crate) fn centred_px(params: &Params, native: Point2<f64>) -> Vector2<f64> {
    native.coords - resolution(params) * 0.5 - center_offset(params)
}

/// The pixel chain for the configured K (converted to `unit`), remap and resolution.
pub(crate) fn pixel_chain(params: &Params, unit: LengthUnit) -> Result<PixelChain, VisionError> {
    chain_with(params, k_in(params, unit), params.remap())
}

/// A pixel chain with an explicit K (units per pixel) and remap, and the profile's lens.
pub(crate) fn chain_with(params: &Params, k: Matrix2<f64>, remap: Remap) -> Result<PixelChain, VisionError> {
    let chain = PixelChain::new(k, remap, resolution(params), center_offset(params))?;
    Ok(match params.calibration.lens() {
        Some(lens) => chain.with_lens(lens)?,
        None => chain,
    })
}

/// Mark size along the camera's native axes: `width_px · ‖(K·R) column 1‖`,
/// `height_px · ‖(K·R) column 2‖`.
///
/// Decision: with `SwapXY` the native x axis is the remapped y axis, so the width uses K's
/// second column; without a swap this is exactly the manual's `width_px × ‖K column 1‖`.
pub(crate) fn mark_size(chain: &PixelChain, reading: &Reading) -> (f64, f64) {
    if chain.remap().swap_xy {
        let (h, w) = chain.mark_size(reading.height_px, reading.width_px);
        (w, h)
    } else {
        chain.mark_size(reading.width_px, reading.height_px)
    }
}

/// Checks that a reading carries a usable mark; `driver` says why not, when it can.
pub(crate) fn require_mark(reading: &Reading, driver: &dyn CameraDriver) -> Result<(), VisionError> {
    if reading.found() {
        Ok(())
    } else {
        Err(VisionError::NoMark { reason: driver.miss_reason() })
    }
}

/// The commanded point `C` and the observed point in the program frame: `C` through the active
/// `alignment` to the work frame, plus `d`, and back through the inverse (SPEC §2, last
/// paragraph). `d` is measured along the machine axes, so the G5x rotation under the alignment
/// (θ₀, LinuxCNC) turns it into the program frame first.
pub(crate) fn observe(
    machine: &dyn Machine,
    alignment: Option<AlignmentChain>,
    offset: Vector2<f64>,
) -> Result<(Point2<f64>, Point2<f64>), VisionError> {
    let offset = machine_to_program(offset, machine.controller().base_rotation(machine)?);
    let c = checked::program_position(machine)?;
    let observed = match alignment {
        None => c + offset,
        Some(chain) => chain.inverse(chain.apply(c) + offset).ok_or_else(|| VisionError::BadCalibration {
            reason: "the active alignment's scale has a zero factor, so the program frame cannot be recovered".into(),
        })?,
    };
    if !(observed.x.is_finite() && observed.y.is_finite()) {
        return Err(VisionError::Math(vision_math::MathError::NonFinite { what: "the observed point" }));
    }
    Ok((c, observed))
}
