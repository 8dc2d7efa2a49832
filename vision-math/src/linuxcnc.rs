//! M282's alignment as LinuxCNC executes it (SPEC §9): LinuxCNC has no G68 and no G51.
//!
//! LinuxCNC rotates the active G5x system (`G10 L2 P0 R`, degrees, counter-clockwise) about its
//! origin, and its canon maps a programmed XY `p` to the machine as
//! `g5x + R(rot)·(p + g92) + tool` (emccanon.cc, `rotate_and_offset_pos`): the G92/G52 offset
//! is added *before* the rotation, in the rotated frame (rs274's own G53 conversion agrees:
//! `hosts/linuxcnc/test`). So the chain's rotation about its centre
//! `c` plus its shift `t`, `R(θ)·(p − c) + c + t = R(θ)·p + t'` with `t' = c − R(θ)·c + t`, is
//! executed exactly by rotating the G5x system by θ (on top of the rotation it had before, the
//! *base* rotation θ₀) and setting `G52 = R(θ)ᵀ·t'`:
//! `R(θ₀ + θ)·(p + R(θ)ᵀ·t') = R(θ₀)·(R(θ)·p + t')`.
//!
//! The fit's frame is the program frame before the alignment, i.e. the G5x system already rotated
//! by θ₀ (so a host must turn the camera's machine-axis offset by −θ₀ before adding it to a
//! program-frame position); the cancel restores θ₀ and clears G52. Who remembers θ₀ (the host)
//! is not this module's concern: it takes it as a number.
//!
//! LinuxCNC cannot scale. A chain whose scale deviates from 1 by more than the scale gate is
//! refused ([`MathError::ScaleNotExpressible`]); within the gate the rigid part is applied — the
//! rotation and a shift that agree with the chain at its centre, so a fit's marks keep their
//! centroid exactly — and the scale that was left out is reported in
//! [`LinuxCncAlignment::ignored_scale`].

use nalgebra::Vector2;
#[cfg(test)]
use nalgebra::{Matrix2, Point2};

use crate::chain::AlignmentChain;
use crate::{bounds, MathError};

/// M282's alignment as LinuxCNC executes it: a G5x rotation and a G52 shift.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinuxCncAlignment {
    /// `G10 L2 P0 R`: the active G5x system's rotation, degrees counter-clockwise: the base
    /// rotation plus the fit's.
    pub rotation_deg: f64,
    /// `G52 X Y`: the shift, program units, in the rotated frame (LinuxCNC adds it before
    /// rotating).
    pub g52: Vector2<f64>,
    /// The G5x rotation before the alignment, degrees counter-clockwise; the cancel restores it.
    pub base_rotation_deg: f64,
    /// The chain's per-axis scale that is not applied (dimensionless; `(1, 1)` when none).
    pub ignored_scale: Vector2<f64>,
}

impl LinuxCncAlignment {
    /// Converts `chain` for a G5x system whose rotation is `base_rotation_deg` (degrees
    /// counter-clockwise) when no alignment is active.
    ///
    /// `max_scale_dev_pct` is the scale gate, percent, with `VisionFitMaxScaleDev`'s meaning:
    /// a chain whose X or Y scale deviates from 1 by more is refused; 0 (or less) disables the
    /// gate, and then any scale is left out and reported.
    ///
    /// # Errors
    /// [`MathError::NonFinite`] when the chain, the base rotation or the gate is not finite;
    /// [`MathError::BeyondBound`] for a base rotation past [`crate::bounds::MAX_ROTATION_DEG`];
    /// [`MathError::ScaleNotExpressible`] when the scale is outside the gate.
    pub fn from_chain(
        chain: &AlignmentChain,
        base_rotation_deg: f64,
        max_scale_dev_pct: f64,
    ) -> Result<LinuxCncAlignment, MathError> {
        if !chain.is_finite() {
            return Err(MathError::NonFinite { what: "the alignment chain" });
        }
        bounds::rotation_deg("the G5x rotation before the alignment", base_rotation_deg)?;
        if !max_scale_dev_pct.is_finite() {
            return Err(MathError::NonFinite { what: "the scale gate" });
        }
        let dev_pct = (chain.scale.x - 1.0).abs().max((chain.scale.y - 1.0).abs()) * 100.0;
        if max_scale_dev_pct > 0.0 && dev_pct > max_scale_dev_pct {
            return Err(MathError::ScaleNotExpressible {
                scale_x: chain.scale.x,
                scale_y: chain.scale.y,
                dev_pct,
                max_dev_pct: max_scale_dev_pct,
            });
        }
        let r = chain.rotation_matrix();
        let c = chain.center.coords;
        let rigid_shift = chain.rigid().shift;
        // R·(p − c) + c + t_r = R·p + t'  →  G52 = Rᵀ·t' = Rᵀ·(c + t_r) − c.
        let g52 = r.transpose() * (c + rigid_shift) - c;
        Ok(LinuxCncAlignment {
            rotation_deg: base_rotation_deg + chain.rotation_deg,
            g52,
            base_rotation_deg,
            ignored_scale: chain.scale,
        })
    }

    /// Refuses an alignment no controller can be handed: a field NaN or infinite, or past
    /// [`crate::bounds`] (fixed decimals would write hundreds of digits).
    ///
    /// # Errors
    /// [`MathError::NonFinite`] if a field is NaN or infinite, [`MathError::BeyondBound`] past
    /// [`crate::bounds`].
    pub fn check(&self) -> Result<(), MathError> {
        if !(self.rotation_deg.is_finite() && self.g52.x.is_finite() && self.g52.y.is_finite()) {
            return Err(MathError::NonFinite { what: "the LinuxCNC alignment" });
        }
        bounds::rotation_deg("the LinuxCNC alignment's G5x rotation", self.rotation_deg)?;
        bounds::coordinate("the LinuxCNC alignment's G52 shift", self.g52.x)?;
        bounds::coordinate("the LinuxCNC alignment's G52 shift", self.g52.y)?;
        Ok(())
    }

    /// Largest deviation of the ignored scale from 1, percent (0 when the chain had no scale).
    #[must_use]
    pub fn ignored_scale_dev_pct(&self) -> f64 {
        (self.ignored_scale.x - 1.0).abs().max((self.ignored_scale.y - 1.0).abs()) * 100.0
    }
}

/// LinuxCNC's canon for XY with no tool offset and the G5x origin at zero, written out
/// independently of [`LinuxCncAlignment`]: `R(rot)·(p + g92)`, rotating counter-clockwise.
#[cfg(test)]
fn canon(rotation_deg: f64, g92: Vector2<f64>, p: Point2<f64>) -> Point2<f64> {
    let (s, c) = rotation_deg.to_radians().sin_cos();
    let q = p.coords + g92;
    Point2::new(c * q.x - s * q.y, s * q.x + c * q.y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use proptest::prelude::*;

    fn rot(deg: f64) -> Matrix2<f64> {
        let (s, c) = deg.to_radians().sin_cos();
        Matrix2::new(c, -s, s, c)
    }

    /// The numbers as the lines write them (9 decimals of angle, 7 of position), read back.
    fn written(a: &LinuxCncAlignment) -> (f64, Vector2<f64>) {
        use crate::chain::{fixed, ANGLE_DECIMALS, POSITION_DECIMALS};
        let read = |v: f64, decimals: usize| fixed(v, decimals).parse::<f64>().expect("a number");
        let p = |v: f64| read(v, POSITION_DECIMALS);
        (read(a.rotation_deg, ANGLE_DECIMALS), Vector2::new(p(a.g52.x), p(a.g52.y)))
    }

    #[test]
    fn quarter_turn_about_a_centre_becomes_rotation_about_the_origin_plus_g52() {
        // Rotating 90° about (1, 0) then shifting (0, 2): (1, 0) stays put, then moves to (1, 2);
        // (2, 0) → (1, 1) → (1, 3).
        let chain = AlignmentChain {
            scale: Vector2::new(1.0, 1.0),
            center: Point2::new(1.0, 0.0),
            rotation_deg: 90.0,
            shift: Vector2::new(0.0, 2.0),
        };
        let a = LinuxCncAlignment::from_chain(&chain, 0.0, 2.0).expect("rigid");
        // t' = c − R·c + t = (1, 0) − (0, 1) + (0, 2) = (1, 1); G52 = Rᵀ·t' = (1, −1).
        assert_relative_eq!(a.g52.x, 1.0, epsilon = 1e-12);
        assert_relative_eq!(a.g52.y, -1.0, epsilon = 1e-12);
        assert_relative_eq!(a.rotation_deg, 90.0);
        let w = canon(a.rotation_deg, a.g52, Point2::new(2.0, 0.0));
        assert_relative_eq!(w.x, 1.0, epsilon = 1e-12);
        assert_relative_eq!(w.y, 3.0, epsilon = 1e-12);
    }

    #[test]
    fn the_rotation_adds_to_the_base_and_a_far_one_is_refused() {
        let chain = AlignmentChain { rotation_deg: 1.5, ..AlignmentChain::IDENTITY };
        let a = LinuxCncAlignment::from_chain(&chain, -12.25, 2.0).expect("rigid");
        assert_eq!((a.rotation_deg, a.base_rotation_deg), (-10.75, -12.25));
        assert_eq!(a.check(), Ok(()));
        assert!(matches!(
            LinuxCncAlignment { g52: Vector2::new(f64::NAN, 0.0), ..a }.check(),
            Err(MathError::NonFinite { .. })
        ));
        // A base rotation of 1e308 (#3991 or the G5x rotation) is refused, never written as
        // a 309-digit `G10 L2 P0 R…`.
        for far in [1e308, -2e6] {
            let e = LinuxCncAlignment::from_chain(&chain, far, 2.0).expect_err("far");
            assert!(matches!(e, MathError::BeyondBound { .. }), "{e:?}");
            assert!(e.to_string().len() < 200, "{e}");
            let a = LinuxCncAlignment { rotation_deg: far, ..a };
            assert!(matches!(a.check(), Err(MathError::BeyondBound { .. })));
        }
    }

    #[test]
    fn scale_outside_the_gate_is_refused_and_says_linuxcnc_cannot_scale() {
        let chain = AlignmentChain { scale: Vector2::new(1.0, 1.001), ..AlignmentChain::IDENTITY };
        let e = LinuxCncAlignment::from_chain(&chain, 0.0, 0.05).expect_err("0.1 % > 0.05 %");
        assert!(matches!(e, MathError::ScaleNotExpressible { .. }), "{e:?}");
        assert!(e.to_string().starts_with("LinuxCNC cannot scale"), "{e}");
        let a = LinuxCncAlignment::from_chain(&chain, 0.0, 0.2).expect("0.1 % < 0.2 %");
        assert_relative_eq!(a.ignored_scale_dev_pct(), 0.1, epsilon = 1e-9);
        let off = LinuxCncAlignment::from_chain(&chain, 0.0, 0.0).expect("gate disabled");
        assert_eq!(off.ignored_scale, chain.scale);
    }

    #[test]
    fn non_finite_input_is_an_error() {
        let bad = AlignmentChain { shift: Vector2::new(f64::INFINITY, 0.0), ..AlignmentChain::IDENTITY };
        assert!(LinuxCncAlignment::from_chain(&bad, 0.0, 2.0).is_err());
        assert!(LinuxCncAlignment::from_chain(&AlignmentChain::IDENTITY, f64::NAN, 2.0).is_err());
        assert!(LinuxCncAlignment::from_chain(&AlignmentChain::IDENTITY, 0.0, f64::NAN).is_err());
    }

    fn rigid_chain() -> impl Strategy<Value = (AlignmentChain, f64)> {
        (-500.0..500.0f64, -500.0..500.0f64, -180.0..180.0f64, -50.0..50.0f64, -50.0..50.0f64, -180.0..180.0f64)
            .prop_map(|(cx, cy, deg, tx, ty, base)| {
                let chain = AlignmentChain {
                    scale: Vector2::new(1.0, 1.0),
                    center: Point2::new(cx, cy),
                    rotation_deg: deg,
                    shift: Vector2::new(tx, ty),
                };
                (chain, base)
            })
    }

    proptest! {
        /// Every commanded mark lands, through LinuxCNC's canon order, where the chain puts it in
        /// the frame rotated by the base rotation.
        #[test]
        fn rigid_chain_is_executed_exactly(
            (chain, base) in rigid_chain(),
            px in -1000.0..1000.0f64,
            py in -1000.0..1000.0f64,
        ) {
            let a = LinuxCncAlignment::from_chain(&chain, base, 2.0).expect("rigid");
            let p = Point2::new(px, py);
            let want = rot(base) * chain.apply(p).coords;
            let got = canon(a.rotation_deg, a.g52, p);
            prop_assert!((got.coords - want).norm() <= 1e-9, "{got} vs {want}");
            // The text: 7 decimals on G52 (≤ 7.1e-8) and 9 on R (≤ 1.5e-11 rad · 1.5e3).
            let (r, g52) = written(&a);
            let text = canon(r, g52, p);
            prop_assert!((text.coords - want).norm() <= 1e-7, "{text} vs {want}");
        }

        /// Within the gate the rigid part is applied: the centre lands exactly where the full chain
        /// puts it, and every other point is off by no more than the ignored scale allows.
        #[test]
        fn scaled_chain_keeps_its_centre(
            (chain, base) in rigid_chain(),
            sx in 0.999..1.001f64,
            sy in 0.999..1.001f64,
            px in -1000.0..1000.0f64,
            py in -1000.0..1000.0f64,
        ) {
            let chain = AlignmentChain { scale: Vector2::new(sx, sy), ..chain };
            let a = LinuxCncAlignment::from_chain(&chain, base, 0.1).expect("within 0.1 %");
            let c = chain.center;
            let at_centre = canon(a.rotation_deg, a.g52, c);
            prop_assert!((at_centre.coords - rot(base) * chain.apply(c).coords).norm() <= 1e-9);
            let p = Point2::new(px, py);
            let off = (canon(a.rotation_deg, a.g52, p).coords - rot(base) * chain.apply(p).coords).norm();
            let bound = ((sx - 1.0) * (p.x - c.x)).hypot((sy - 1.0) * (p.y - c.y)) + 1e-9;
            prop_assert!(off <= bound, "{off} > {bound}");
        }
    }
}
