//! `M283 Qd`: K from one dot of known diameter.

use vision_math::show::number;
use vision_math::{LengthUnit, Matrix2, Vector2, MM_PER_INCH};

use super::axis::motion_pairs;
use super::fail;
use super::report::{k_change, resolution_warning, CalReport, LensUpdate, QuickReport, Solution};
use super::walk::Walker;
use crate::error::VisionError;
use crate::module::capture::{chain_with, mark_size};
use crate::params::Params;

/// `M283 Qd`.
pub(super) fn quick(walker: &mut Walker<'_>, params: &Params, diameter: f64) -> Result<Solution, VisionError> {
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
    Ok(Solution { k, remap, tool_offset: None, centre: None, lens: LensUpdate::Keep, report: CalReport::Quick(report) })
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
    let moved: f64 = motion.iter().map(vision_math::Vector2::norm).sum();
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
