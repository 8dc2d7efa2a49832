//! The axis-detect bump and K from motion whose pixel effect is known.

use vision_math::{solve_linear, LengthUnit, Matrix2, Remap, Vector2};

use super::fail;
use super::report::AxisReport;
use super::walk::{Shot, Walker};
use crate::error::VisionError;

/// The axis-detect bump: 0.1 inch (2.54 mm under G21).
pub const BUMP_IN: f64 = 0.1;
/// Fewest pixels the mark must move during a bump for the axis detect to trust it.
pub const MIN_BUMP_PX: f64 = 2.0;

impl Walker<'_> {
    /// The axis-detect bump from the current position; returns the remap and the two pairs.
    pub(super) fn axis_detect(&mut self) -> Result<(AxisReport, [(usize, usize); 2]), VisionError> {
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
pub(super) fn motion_pairs(
    shots: &[Shot],
    pairs: &[(usize, usize)],
    remap: Remap,
) -> (Vec<Vector2<f64>>, Vec<Vector2<f64>>) {
    pairs.iter().map(|(b, p)| (remap.apply(shots[*p].native - shots[*b].native), shots[*b].pos - shots[*p].pos)).unzip()
}

pub(super) fn solve_k(
    shots: &[Shot],
    pairs: &[(usize, usize)],
    remap: Remap,
) -> Result<(Matrix2<f64>, f64), VisionError> {
    let (p, q) = motion_pairs(shots, pairs, remap);
    let fit = solve_linear(&p, &q).map_err(|e| fail(format!("K from the probe moves: {e}")))?;
    Ok((fit.m, fit.rms))
}

#[cfg(test)]
mod tests {
    use super::*;

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
