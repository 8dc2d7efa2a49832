//! The modal alignment chain M282 emits: `G51` scale → `G68` rotation → `G52` shift (SPEC §6),
//! and the fixed decimals its numbers are written with (the text is `vision-mcode`'s).

use nalgebra::{Matrix2, Point2, UnitComplex, Vector2};

use crate::{bounds, MathError};

/// Decimals for X/Y words (machine units): rounding moves a point by at most 5·10⁻⁸.
pub const POSITION_DECIMALS: usize = 7;
/// Decimals for `G68 R` (degrees): rounding moves a point 1000 units away by < 10⁻⁷.
pub const ANGLE_DECIMALS: usize = 9;
/// Decimals for `G51` factors: rounding moves a point 1000 units away by ≤ 5·10⁻⁸.
pub const SCALE_DECIMALS: usize = 10;

/// The three alignment modals, in program units, exactly as they execute.
///
/// A programmed point `p` reaches the work frame as
/// `R(rotation_deg)·(S·p − center) + center + shift` with `S = diag(scale)`: G51 scales about
/// the local origin, G68 rotates about `center` (counter-clockwise seen from +Z), G52 adds
/// `shift`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlignmentChain {
    /// `G51 X Y`: per-axis factors (dimensionless).
    pub scale: Vector2<f64>,
    /// `G68 X Y`: centre of rotation, program units.
    pub center: Point2<f64>,
    /// `G68 R`: rotation, degrees, counter-clockwise.
    pub rotation_deg: f64,
    /// `G52 X Y`: shift, program units.
    pub shift: Vector2<f64>,
}

impl Default for AlignmentChain {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl AlignmentChain {
    /// No scale, no rotation, no shift.
    pub const IDENTITY: AlignmentChain = AlignmentChain {
        scale: Vector2::new(1.0, 1.0),
        center: Point2::new(0.0, 0.0),
        rotation_deg: 0.0,
        shift: Vector2::new(0.0, 0.0),
    };

    /// The chain that maps `commanded_centroid` onto `observed_centroid` with linear part
    /// `R·diag(scale)`, rotating about `center`. Lengths in program units.
    #[must_use]
    pub fn from_parts(
        scale: Vector2<f64>,
        center: Point2<f64>,
        rotation: UnitComplex<f64>,
        commanded_centroid: Point2<f64>,
        observed_centroid: Point2<f64>,
    ) -> AlignmentChain {
        let rotation_deg = rotation.im.atan2(rotation.re).to_degrees();
        let mut chain = AlignmentChain { scale, center, rotation_deg, shift: Vector2::zeros() };
        // Choose the shift so that the centroid lands exactly: t = ō − chain_without_shift(n̄).
        chain.shift = observed_centroid - chain.apply(commanded_centroid);
        chain
    }

    /// The rotation matrix of `rotation_deg`.
    #[must_use]
    pub fn rotation_matrix(&self) -> Matrix2<f64> {
        let (s, c) = self.rotation_deg.to_radians().sin_cos();
        Matrix2::new(c, -s, s, c)
    }

    /// Program point → work point (program units): scale, rotate about the centre, shift.
    #[must_use]
    pub fn apply(&self, p: Point2<f64>) -> Point2<f64> {
        self.apply_with(&self.rotation_matrix(), p)
    }

    /// [`AlignmentChain::apply`] with the rotation matrix given, for a caller that maps many
    /// points through one chain and computes `rotation` once. `rotation` must be
    /// [`AlignmentChain::rotation_matrix`] of this chain; then the result is bit-identical to
    /// `apply` (it is the same arithmetic: `apply` calls this).
    #[inline]
    #[must_use]
    pub fn apply_with(&self, rotation: &Matrix2<f64>, p: Point2<f64>) -> Point2<f64> {
        let scaled = Vector2::new(self.scale.x * p.x, self.scale.y * p.y);
        let rotated = rotation * (scaled - self.center.coords) + self.center.coords;
        Point2::from(rotated + self.shift)
    }

    /// The rigid part of this chain: no scale, the same rotation about the same centre, and the
    /// shift that makes it agree with this chain at the centre
    /// (`c ↦ R·(S·c − c) + c + t`). What a host that cannot scale (LinuxCNC) executes.
    #[must_use]
    pub fn rigid(&self) -> AlignmentChain {
        let c = self.center.coords;
        let scaled_c = Vector2::new(self.scale.x * c.x, self.scale.y * c.y);
        let shift = self.shift + self.rotation_matrix() * (scaled_c - c);
        AlignmentChain { scale: Vector2::new(1.0, 1.0), shift, ..*self }
    }

    /// Work point → program point: the inverse of [`AlignmentChain::apply`]; `None` when a scale
    /// factor is zero.
    #[must_use]
    pub fn inverse(&self, w: Point2<f64>) -> Option<Point2<f64>> {
        if self.scale.x == 0.0 || self.scale.y == 0.0 {
            return None;
        }
        let v = self.rotation_matrix().transpose() * (w.coords - self.shift - self.center.coords) + self.center.coords;
        Some(Point2::new(v.x / self.scale.x, v.y / self.scale.y))
    }

    /// The chain a controller runs after reading the lines written for it: every field
    /// rounded to the decimals it is written with (moves no point by more than 1e-6 units).
    /// `None` if a field is NaN or infinite.
    #[must_use]
    pub fn as_emitted(&self) -> Option<AlignmentChain> {
        let round = |v: f64, decimals: usize| fixed(v, decimals).parse::<f64>().ok().filter(|r| r.is_finite());
        let p = |v: f64| round(v, POSITION_DECIMALS);
        Some(AlignmentChain {
            scale: Vector2::new(round(self.scale.x, SCALE_DECIMALS)?, round(self.scale.y, SCALE_DECIMALS)?),
            center: Point2::new(p(self.center.x)?, p(self.center.y)?),
            rotation_deg: round(self.rotation_deg, ANGLE_DECIMALS)?,
            shift: Vector2::new(p(self.shift.x)?, p(self.shift.y)?),
        })
    }

    /// Every number of the chain (scale, centre, rotation, shift) is finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        [self.scale.x, self.scale.y, self.center.x, self.center.y, self.rotation_deg, self.shift.x, self.shift.y]
            .iter()
            .all(|v| v.is_finite())
    }

    /// Refuses a chain no controller can be handed: a field NaN or infinite, or past
    /// [`crate::bounds`] (fixed decimals would write hundreds of digits).
    ///
    /// # Errors
    /// [`MathError::NonFinite`] if any field is NaN or infinite, [`MathError::BeyondBound`] past
    /// [`crate::bounds`].
    pub fn check(&self) -> Result<(), MathError> {
        if !self.is_finite() {
            return Err(MathError::NonFinite { what: "the alignment chain" });
        }
        for v in [self.center.x, self.center.y, self.shift.x, self.shift.y] {
            bounds::coordinate("the alignment's centre or shift", v)?;
        }
        bounds::rotation_deg("the alignment's rotation", self.rotation_deg)?;
        Ok(())
    }
}

/// Formats a finite `v` with `decimals` fixed decimals, writing a rounded negative zero as zero.
#[must_use]
pub fn fixed(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.starts_with('-') && s[1..].bytes().all(|b| b == b'0' || b == b'.') {
        s[1..].to_string()
    } else {
        s
    }
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn the_emitted_chain_is_the_one_its_lines_write() {
        let chain = AlignmentChain {
            scale: Vector2::new(1.000_775_023_012_3, 1.001_148_365_6),
            center: Point2::new(3.0, 2.000_000_04),
            rotation_deg: 0.300_602_523_47,
            shift: Vector2::new(-0.010_478_12, 0.015_755_24),
        };
        let emitted = chain.as_emitted().expect("finite");
        assert_eq!(emitted.as_emitted(), Some(emitted), "written again, it stays");
        assert_eq!(emitted.shift.x, -0.010_478_1);
        assert_eq!(emitted.rotation_deg, 0.300_602_523);
        for p in [Point2::new(0.0, 0.0), Point2::new(6.0, 4.0)] {
            assert!((emitted.apply(p) - chain.apply(p)).norm() < 1e-6);
        }
        assert_eq!(AlignmentChain { rotation_deg: f64::NAN, ..chain }.as_emitted(), None);
    }

    #[test]
    fn rigid_part_keeps_the_centre_and_drops_the_scale() {
        let chain = AlignmentChain {
            scale: Vector2::new(1.002, 0.999),
            center: Point2::new(3.0, 2.0),
            rotation_deg: 0.4,
            shift: Vector2::new(0.05, -0.02),
        };
        let rigid = chain.rigid();
        assert_eq!(rigid.scale, Vector2::new(1.0, 1.0));
        assert_eq!(rigid.rotation_deg, chain.rotation_deg);
        let (got, want) = (rigid.apply(chain.center), chain.apply(chain.center));
        assert_relative_eq!(got.x, want.x, epsilon = 1e-12);
        assert_relative_eq!(got.y, want.y, epsilon = 1e-12);
        // Away from the centre the two differ by the dropped scale: 0.002 · 3 in X.
        let p = Point2::new(6.0, 2.0);
        assert!((rigid.apply(p) - chain.apply(p)).norm() > 0.005);
    }

    #[test]
    fn order_is_scale_then_rotate_about_centre_then_shift() {
        let chain = AlignmentChain {
            scale: Vector2::new(2.0, 3.0),
            center: Point2::new(1.0, 1.0),
            rotation_deg: 90.0,
            shift: Vector2::new(10.0, 20.0),
        };
        // (1, 1) -> scaled (2, 3) -> minus centre (1, 2) -> rotated 90° (-2, 1) -> plus centre
        // (-1, 2) -> shifted (9, 22).
        let w = chain.apply(Point2::new(1.0, 1.0));
        assert_relative_eq!(w.x, 9.0, epsilon = 1e-12);
        assert_relative_eq!(w.y, 22.0, epsilon = 1e-12);
        let back = chain.inverse(w).expect("invertible");
        assert_relative_eq!(back.x, 1.0, epsilon = 1e-12);
        assert_relative_eq!(back.y, 1.0, epsilon = 1e-12);
    }

    #[test]
    fn a_chain_past_the_bounds_or_not_finite_is_refused() {
        let chain = AlignmentChain { center: Point2::new(3.0, -2.0), ..AlignmentChain::IDENTITY };
        assert_eq!(chain.check(), Ok(()));
        assert!(matches!(AlignmentChain { rotation_deg: f64::NAN, ..chain }.check(), Err(MathError::NonFinite { .. })));
        let far = AlignmentChain { shift: Vector2::new(1e308, 0.0), ..chain };
        assert!(matches!(far.check(), Err(MathError::BeyondBound { .. })));
        assert!(matches!(AlignmentChain { rotation_deg: 1e308, ..chain }.check(), Err(MathError::BeyondBound { .. })));
    }

    #[test]
    fn fixed_keeps_real_negatives() {
        assert_eq!(fixed(-0.5, 2), "-0.50");
        assert_eq!(fixed(-0.004, 2), "0.00");
        assert_eq!(fixed(0.0, 0), "0");
        assert_eq!(fixed(-0.0, 3), "0.000");
    }
}
