//! The true camera: where a point on the table lands in native pixels.
//!
//! With `s` = units per pixel × working distance / reference working distance, `a` the pixel
//! aspect, `m` = −1 for a mirrored image (else 1) and `φ` the image rotation, a point `v`
//! away from the optical axis (machine X/Y axes, world unit) images at native pixel
//!
//! `p = res/2 + bias + (K·R)⁻¹·v`, with `K·R = s·Rot(φ)·[[a·m, 0], [0, −1]]`.
//!
//! The scale follows the working distance, which follows the head's Z ([`crate::World`]'s
//! `camera.focus_z`): a point on the optical axis (`v` = 0) images at the optical centre
//! `res/2 + bias` at every height, and the image grows or shrinks about it.
//!
//! (Image +y points down, hence the −1.) This is exactly the core's pixel chain run backwards,
//! so with the right K, remap and centre offset the core recovers `v` exactly.

use vision_math::{Matrix2, Point2, Vector2};

use crate::lens::Lens;
use crate::world::CameraMount;

/// The true optics of a mounted camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Optics {
    kr: Matrix2<f64>,
    kr_inv: Matrix2<f64>,
    resolution: Vector2<f64>,
    bias: Vector2<f64>,
    /// Pixel width and height on the table, world unit.
    pixel: Vector2<f64>,
    lens: Option<Lens>,
}

impl Optics {
    /// The optics of `mount` (validated by [`crate::World::validate`]) with the spindle at the
    /// mount's focus Z (working distance `mount.working_distance`).
    #[must_use]
    pub fn new(mount: &CameraMount) -> Optics {
        Optics::at(mount, mount.working_distance)
    }

    /// The optics of `mount` at lens-to-surface distance `working_distance` (world unit,
    /// positive): the image scales about the optical centre (`center_bias_px`), the one pixel
    /// that sees the same table point at every distance.
    #[must_use]
    pub fn at(mount: &CameraMount, working_distance: f64) -> Optics {
        // A validated mount has a valid lens.
        Optics::with_lens(mount, working_distance, Lens::new(mount).ok().flatten())
    }

    /// [`Optics::at`] with the mount's lens already built.
    pub(crate) fn with_lens(mount: &CameraMount, working_distance: f64, lens: Option<Lens>) -> Optics {
        let reference = mount.reference_working_distance.unwrap_or(mount.working_distance);
        let s = mount.units_per_pixel * working_distance / reference;
        let m = if mount.mirror { -1.0 } else { 1.0 };
        let (sin, cos) = mount.rotation_deg.to_radians().sin_cos();
        let kr = Matrix2::new(cos, -sin, sin, cos) * Matrix2::new(s * mount.pixel_aspect * m, 0.0, 0.0, -s);
        // det = −m·a·s² ≠ 0 for a validated mount.
        let det = kr.determinant();
        let kr_inv = Matrix2::new(kr[(1, 1)], -kr[(0, 1)], -kr[(1, 0)], kr[(0, 0)]) / det;
        Optics {
            kr,
            kr_inv,
            resolution: Vector2::new(f64::from(mount.resolution[0]), f64::from(mount.resolution[1])),
            bias: Vector2::from(mount.center_bias_px),
            pixel: Vector2::new(s * mount.pixel_aspect, s),
            lens,
        }
    }

    /// `K·R`: centred native pixels → offset on the table, world unit per pixel.
    #[must_use]
    pub fn kr(&self) -> Matrix2<f64> {
        self.kr
    }

    /// The native pixel where a point `v` away from the optical axis images (`v` in world unit).
    #[must_use]
    pub fn pixel(&self, v: Vector2<f64>) -> Point2<f64> {
        Point2::from(self.resolution * 0.5 + self.bias + self.kr_inv * v)
    }

    /// Where a point `v` away from the optical axis (world unit) images through the lens,
    /// native pixels: [`Optics::pixel`] distorted by the world's lens, if any; `None` outside
    /// the lens's field.
    #[must_use]
    pub fn image(&self, v: Vector2<f64>) -> Option<Point2<f64>> {
        let p = self.pixel(v);
        match &self.lens {
            None => Some(p),
            Some(lens) => lens.distort(p),
        }
    }

    /// The offset from the optical axis (world unit) of what images at native pixel `p`
    /// through the linear optics (the lens's distortion not undone).
    #[must_use]
    pub fn offset(&self, p: Point2<f64>) -> Vector2<f64> {
        self.kr * (p.coords - self.resolution * 0.5 - self.bias)
    }

    /// True when `p` lies at least `margin_px` inside the image.
    #[must_use]
    pub fn in_view(&self, p: Point2<f64>, margin_px: f64) -> bool {
        p.x >= margin_px
            && p.y >= margin_px
            && p.x <= self.resolution.x - margin_px
            && p.y <= self.resolution.y - margin_px
    }

    /// Image resolution `(ResX, ResY)`, pixels.
    #[must_use]
    pub fn resolution(&self) -> Vector2<f64> {
        self.resolution
    }

    /// Optical centre minus image centre, pixels.
    #[must_use]
    pub fn bias(&self) -> Vector2<f64> {
        self.bias
    }

    /// A round mark of `diameter` (world unit) as `(width, height)` in pixels.
    #[must_use]
    pub fn size_px(&self, diameter: f64) -> (f64, f64) {
        (diameter / self.pixel.x, diameter / self.pixel.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::World;
    use approx::assert_relative_eq;

    #[test]
    fn pixel_and_offset_are_inverse_and_follow_the_image_axes() {
        let mut mount = World::default_world().camera;
        mount.rotation_deg = 0.0;
        mount.center_bias_px = [0.0, 0.0];
        let o = Optics::new(&mount);
        // +X on the table is +x in the image; +Y is −y (up).
        let p = o.pixel(Vector2::new(0.203, 0.0));
        assert_relative_eq!(p.x, 888.0 + 100.0, epsilon = 1e-9);
        assert_relative_eq!(p.y, 888.0, epsilon = 1e-9);
        let p = o.pixel(Vector2::new(0.0, 0.203));
        assert_relative_eq!(p.y, 888.0 - 100.0, epsilon = 1e-9);
        mount.mirror = true;
        mount.rotation_deg = 37.0;
        mount.pixel_aspect = 1.01;
        mount.center_bias_px = [4.0, -3.0];
        let o = Optics::new(&mount);
        let v = Vector2::new(0.31, -0.77);
        assert_relative_eq!(o.offset(o.pixel(v)), v, epsilon = 1e-12);
        assert!(o.kr().determinant() > 0.0, "a mirrored image flips handedness");
    }

    #[test]
    fn raising_the_head_shrinks_the_image_about_the_optical_centre() {
        use crate::{Sim, SimMachine};
        let mut world = World::default_world();
        world.camera.noise_px = 0.0;
        world.camera.center_bias_px = [4.5, -3.0];
        let sim = Sim::new(world.clone()).expect("sim");
        let mut machine = SimMachine::new(&sim).expect("machine");
        let before = sim.optics();
        let wd = world.camera.working_distance;
        let mut ignore = |_: &vision_gcode::Event| {};
        machine.run_program("G91 G0 Z0.25\nG90\n", None, &mut ignore).expect("lift");
        let after = sim.optics();
        // K grows with the working distance, one for one with Z.
        assert_relative_eq!(after.kr(), before.kr() * ((wd + 0.25) / wd), epsilon = 1e-15);
        // The optical centre sees the same table point at both heights; every other pixel
        // moves towards it by the ratio of the distances.
        let centre = Point2::from(before.resolution() * 0.5 + before.bias());
        assert_relative_eq!(after.pixel(Vector2::zeros()), centre, epsilon = 1e-9);
        let v = Vector2::new(0.5, -0.3);
        let moved = centre + (before.pixel(v) - centre) * (wd / (wd + 0.25));
        assert_relative_eq!(after.pixel(v), moved, epsilon = 1e-9);
        // Back down: as before.
        machine.run_program("G91 G0 Z-0.25\nG90\n", None, &mut ignore).expect("down");
        assert_relative_eq!(sim.optics().kr(), before.kr(), epsilon = 1e-15);
    }

    #[test]
    fn scale_follows_the_working_distance() {
        let mut mount = World::default_world().camera;
        mount.reference_working_distance = Some(6.0);
        mount.working_distance = 6.6;
        let o = Optics::new(&mount);
        assert_relative_eq!(o.kr().column(1).norm(), 0.00203 * 1.1, epsilon = 1e-15);
        let (w, h) = o.size_px(0.5);
        assert_relative_eq!(w, 0.5 / (0.00203 * 1.1), epsilon = 1e-9);
        assert_relative_eq!(h, w, epsilon = 1e-9);
    }
}
