//! The frame chain of SPEC §6: program → (G51 → G68 → G52) → work → (+ work offset + G92
//! − tool X/Y) → machine.
//!
//! The X/Y part of program → work is [`vision_math::AlignmentChain::apply_with`] with the cached
//! rotation matrix, the very arithmetic of [`vision_math::AlignmentChain::apply`], so it is
//! bit-identical by construction.

use vision_math::{AlignmentChain, Matrix2, Point2, Vector2};

use crate::geom::Xyz;

/// The alignment modals in machine units, and the G52 Z shift.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Frame {
    /// G51 / G68 / G52 (X/Y), machine units.
    pub(crate) chain: AlignmentChain,
    /// `chain.rotation_matrix()`, cached.
    rotation: Matrix2<f64>,
    /// G52 Z, machine units.
    pub(crate) local_z: f64,
}

impl Default for Frame {
    fn default() -> Self {
        Frame::identity()
    }
}

impl Frame {
    /// No scale, rotation or shift.
    pub(crate) fn identity() -> Frame {
        Frame { chain: AlignmentChain::IDENTITY, rotation: AlignmentChain::IDENTITY.rotation_matrix(), local_z: 0.0 }
    }

    /// G68: rotate by `degrees` about `center` (machine units); G69 is `(origin, 0)`.
    pub(crate) fn set_rotation(&mut self, center: Point2<f64>, degrees: f64) {
        self.chain.center = center;
        self.chain.rotation_deg = degrees;
        self.rotation = self.chain.rotation_matrix();
    }

    /// Program X/Y → work X/Y: [`AlignmentChain::apply`] with the cached rotation matrix.
    #[inline]
    pub(crate) fn apply(&self, p: Point2<f64>) -> Point2<f64> {
        self.chain.apply_with(&self.rotation, p)
    }

    /// Work X/Y → program X/Y: [`AlignmentChain::inverse`]. Its `None` (a zero scale factor)
    /// cannot happen here, G51 refuses zero factors; `w` is returned unchanged if it did.
    pub(crate) fn inverse(&self, w: Point2<f64>) -> Point2<f64> {
        self.chain.inverse(w).unwrap_or(w)
    }

    /// True when the X/Y map keeps circles circles (|sx| = |sy|).
    #[expect(clippy::float_cmp, reason = "exact: a similarity has equal scale magnitudes by construction")]
    pub(crate) fn is_similarity(&self) -> bool {
        self.chain.scale.x.abs() == self.chain.scale.y.abs()
    }

    /// True when the X/Y map is a pure translation (no scale, no rotation).
    pub(crate) fn is_translation(&self) -> bool {
        self.chain.scale == Vector2::new(1.0, 1.0) && self.rotation == Matrix2::identity()
    }

    /// True when the X/Y map mirrors (reverses arc directions).
    pub(crate) fn mirrors(&self) -> bool {
        self.chain.scale.x * self.chain.scale.y < 0.0
    }

    /// The largest factor by which the map stretches a length in 3D (Z is never scaled).
    pub(crate) fn stretch(&self) -> f64 {
        self.chain.scale.x.abs().max(self.chain.scale.y.abs()).max(1.0)
    }
}

/// The whole program → machine map at one moment: the frame, the summed offsets and LinuxCNC's
/// coordinate-system rotation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Placement {
    pub(crate) frame: Frame,
    /// `x = (work.x + g92.x) − tool.x`, `y` likewise, `z = (work.z + g92.z) + tool length`,
    /// machine units. Under a [`SystemRotation`] only `z` is used.
    pub(crate) offset: Xyz,
    /// The active G5x system's XY rotation (`G10 L2 R`), `None` when it has none.
    pub(crate) rotation: Option<SystemRotation>,
}

/// LinuxCNC's rotation of a coordinate system about its origin (emccanon.cc,
/// `rotate_and_offset_pos`): `m.xy = (work.xy − tool.xy) + R·(w.xy + g92.xy)`, the G92 (and
/// G52) offset added before rotating, the tool offset after.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SystemRotation {
    /// `R(θ)`, counter-clockwise.
    matrix: Matrix2<f64>,
    /// The G92 offset's X/Y, machine units: added before rotating.
    inner: Vector2<f64>,
    /// The work origin's X/Y minus the tool's X/Y offset, machine units: added after.
    outer: Vector2<f64>,
}

impl SystemRotation {
    /// The rotation by `degrees` (counter-clockwise) of a system whose origin is `work`, with
    /// the G92 offset `g92` and the tool offset `tool` (machine units); `None` for 0°, so that
    /// an unrotated system keeps the plain offset sum bit for bit.
    pub(crate) fn new(degrees: f64, work: Xyz, g92: Xyz, tool: Xyz) -> Option<SystemRotation> {
        if degrees == 0.0 {
            return None;
        }
        let (sin, cos) = degrees.to_radians().sin_cos();
        Some(SystemRotation {
            matrix: Matrix2::new(cos, -sin, sin, cos),
            inner: Vector2::new(g92.x, g92.y),
            outer: Vector2::new(work.x - tool.x, work.y - tool.y),
        })
    }

    /// `p` rotated by `degrees` counter-clockwise about the origin (0° returns it unchanged).
    pub(crate) fn turn(degrees: f64, p: Point2<f64>) -> Point2<f64> {
        match SystemRotation::new(degrees, Xyz::ZERO, Xyz::ZERO, Xyz::ZERO) {
            None => p,
            Some(r) => r.apply(p),
        }
    }

    /// Work X/Y → machine X/Y.
    #[inline]
    pub(crate) fn apply(&self, w: Point2<f64>) -> Point2<f64> {
        Point2::from(self.matrix * (w.coords + self.inner) + self.outer)
    }

    /// Machine X/Y → work X/Y.
    fn inverse(&self, m: Point2<f64>) -> Point2<f64> {
        Point2::from(self.matrix.transpose() * (m.coords - self.outer) - self.inner)
    }
}

impl Placement {
    /// The summed offset of a work offset, a G92 offset and a tool (offset and length).
    pub(crate) fn offset(work: Xyz, g92: Xyz, tool: Xyz) -> Xyz {
        Xyz { x: (work.x + g92.x) - tool.x, y: (work.y + g92.y) - tool.y, z: (work.z + g92.z) + tool.z }
    }

    /// The inverse of [`Placement::offset`] for one summand: the work offset (or G92 offset)
    /// that, with `other` (the G92 offset, or the work offset) and `tool`, sums to `total`.
    pub(crate) fn offset_summand(total: Xyz, other: Xyz, tool: Xyz) -> Xyz {
        Xyz { x: (total.x - other.x) + tool.x, y: (total.y - other.y) + tool.y, z: (total.z - other.z) - tool.z }
    }

    /// Program point → work point.
    pub(crate) fn work_of(&self, p: Xyz) -> Xyz {
        let w = self.frame.apply(p.xy());
        Xyz { x: w.x, y: w.y, z: p.z + self.frame.local_z }
    }

    /// Program point → machine point.
    #[inline]
    pub(crate) fn machine_of(&self, p: Xyz) -> Xyz {
        let w = self.work_of(p);
        match &self.rotation {
            None => Xyz { x: w.x + self.offset.x, y: w.y + self.offset.y, z: w.z + self.offset.z },
            Some(r) => {
                let m = r.apply(w.xy());
                Xyz { x: m.x, y: m.y, z: w.z + self.offset.z }
            }
        }
    }

    /// Machine point → program point.
    pub(crate) fn program_of(&self, m: Xyz) -> Xyz {
        let w = match &self.rotation {
            None => Point2::new(m.x - self.offset.x, m.y - self.offset.y),
            Some(r) => r.inverse(m.xy()),
        };
        let p = self.frame.inverse(w);
        Xyz { x: p.x, y: p.y, z: (m.z - self.offset.z) - self.frame.local_z }
    }

    /// True when the whole X/Y map is a pure translation (no scale, no rotation of any kind).
    pub(crate) fn is_translation(&self) -> bool {
        self.rotation.is_none() && self.frame.is_translation()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn apply_is_bit_identical_to_the_alignment_chain() {
        let mut frame = Frame::identity();
        frame.chain.scale = Vector2::new(1.0003, 0.9991);
        frame.set_rotation(Point2::new(3.1, 2.2), 0.731);
        frame.chain.shift = Vector2::new(0.07, -0.11);
        for p in [Point2::new(0.0, 0.0), Point2::new(6.0, 4.0), Point2::new(-123.456, 78.9)] {
            assert_eq!(frame.apply(p), frame.chain.apply(p));
            let back = frame.inverse(frame.apply(p));
            assert!((back - p).norm() < 1e-12);
        }
        let placement = Placement {
            frame,
            offset: Placement::offset(Xyz::new(1.0, 2.0, 3.0), Xyz::ZERO, Xyz::ZERO),
            rotation: None,
        };
        let p = Xyz::new(1.0, 1.0, 1.0);
        let m = placement.machine_of(p);
        assert!((placement.program_of(m) - p).norm() < 1e-12);
        let (work, g92, tool) = (Xyz::new(1.0, 2.0, 3.0), Xyz::new(0.5, -0.25, 0.125), Xyz::new(0.1, 0.2, 4.0));
        let total = Placement::offset(work, g92, tool);
        assert!((Placement::offset_summand(total, g92, tool) - work).norm() < 1e-12);
        assert!((Placement::offset_summand(total, work, tool) - g92).norm() < 1e-12);
        assert!(!frame.is_similarity() && !frame.is_translation() && !frame.mirrors());
    }
}
