//! Lens distortion: the world's `camera.distortion = [k1, k2, p1, p2, k3]`, OpenCV's
//! Brown–Conrady model, applied to the linear optics' pixel ([`crate::Optics::pixel`]).
//!
//! With the optical centre `c = res/2 + center_bias_px`, the focal length `f` = reference
//! working distance / units per pixel (pixels of height) and the pixel aspect `a`, a linear
//! pixel `p` has normalised coordinates `x = (p.x − c.x)·a/f`, `y = (p.y − c.y)/f`, and
//! images at `x' = x·L + 2·p1·x·y + p2·(r² + 2x²)`, `y' = y·L + p1·(r² + 2y²) + 2·p2·x·y`,
//! `L = 1 + k1·r² + k2·r⁴ + k3·r⁶`, back in pixels by the same scale. The lens belongs to the
//! image: the map does not change when the head moves, only the linear scale does.
//!
//! Decision: a distortion is refused when the map folds (its Jacobian stops being positive, or
//! a ray from the centre turns back) before the image reaches 1.1 × the frame's farthest
//! corner; points beyond that field are not imaged at all, so a fold outside it never shows.

use vision_math::{Matrix2, Point2, Vector2};

use crate::error::SimError;
use crate::world::CameraMount;

/// The world key, as errors name it.
const KEY: &str = "camera.distortion";
/// Rays scanned from the optical centre for a fold.
const RAYS: u32 = 72;
/// Scan step along a ray, normalised units (about 6 px at the built-in 2956 px focal length).
const STEP: f64 = 0.002;
/// The widest field the model is trusted over, normalised (76° off axis).
const MAX_FIELD: f64 = 4.0;
/// Largest |k1|, |k2|, |k3| and |p1|, |p2| accepted before the fold scan.
const MAX_RADIAL: f64 = 1000.0;
/// Largest tangential coefficient.
const MAX_TANGENTIAL: f64 = 1.0;

/// A validated lens distortion on one camera's image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lens {
    k: [f64; 3],
    p: [f64; 2],
    /// Optical centre, native pixels.
    centre: Vector2<f64>,
    /// Focal length along image x and y, pixels.
    focal: Vector2<f64>,
    /// Squared normalised radius beyond which nothing images.
    field_r2: f64,
}

impl Lens {
    /// The lens of `mount` (its other fields already validated), `None` without distortion.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming `camera.distortion` for non-finite or absurd
    /// coefficients, or a distortion that folds the image within the frame.
    pub fn new(mount: &CameraMount) -> Result<Option<Lens>, SimError> {
        let Some([k1, k2, p1, p2, k3]) = mount.distortion else {
            return Ok(None);
        };
        if ![k1, k2, k3].iter().all(|k| k.is_finite() && k.abs() <= MAX_RADIAL) {
            return invalid(format!("k1, k2 and k3 must be finite, within ±{MAX_RADIAL}"));
        }
        if ![p1, p2].iter().all(|p| p.is_finite() && p.abs() <= MAX_TANGENTIAL) {
            return invalid(format!("p1 and p2 must be finite, within ±{MAX_TANGENTIAL}"));
        }
        let reference = mount.reference_working_distance.unwrap_or(mount.working_distance);
        let f = reference / mount.units_per_pixel;
        let res = Vector2::new(f64::from(mount.resolution[0]), f64::from(mount.resolution[1]));
        let mut lens = Lens {
            k: [k1, k2, k3],
            p: [p1, p2],
            centre: res * 0.5 + Vector2::from(mount.center_bias_px),
            focal: Vector2::new(f / mount.pixel_aspect, f),
            field_r2: f64::INFINITY,
        };
        // The farthest corner from the optical centre, normalised, with a margin.
        let reach = [(0.0, 0.0), (res.x, 0.0), (0.0, res.y), (res.x, res.y)]
            .iter()
            .map(|&(x, y)| lens.normalise(Point2::new(x, y)).norm())
            .fold(0.0, f64::max)
            * 1.1;
        // Every ray must reach `reach` without folding; then every ray must stay unfolded out
        // to the widest radius any ray needed, which becomes the field.
        let mut field = 0.0f64;
        for i in 0..RAYS {
            let u = ray(i);
            let mut r = 0.0;
            while lens.apply(u * r).norm() < reach {
                r += STEP;
                if r > MAX_FIELD {
                    return invalid("does not reach the frame's corners within 4 focal lengths (76°)");
                }
                if !lens.unfolded(u, r) {
                    return invalid("folds the image within the frame (the distortion turns back)");
                }
            }
            field = field.max(r);
        }
        for i in 0..RAYS {
            let u = ray(i);
            let mut r = 0.0;
            while r < field {
                r += STEP;
                if !lens.unfolded(u, r) {
                    return invalid("folds the image within the frame (the distortion turns back)");
                }
            }
        }
        lens.field_r2 = field * field;
        Ok(Some(lens))
    }

    /// Where linear native pixel `p` images through the lens, native pixels; `None` when `p`
    /// lies outside the lens's field.
    #[must_use]
    pub fn distort(&self, p: Point2<f64>) -> Option<Point2<f64>> {
        let n = self.normalise(p);
        if n.norm_squared() > self.field_r2 {
            return None;
        }
        let d = self.apply(n);
        Some(Point2::from(self.centre + d.component_mul(&self.focal)))
    }

    fn normalise(&self, p: Point2<f64>) -> Vector2<f64> {
        (p.coords - self.centre).component_div(&self.focal)
    }

    /// The distortion on normalised coordinates.
    fn apply(&self, n: Vector2<f64>) -> Vector2<f64> {
        let ([k1, k2, k3], [p1, p2]) = (self.k, self.p);
        let (x, y) = (n.x, n.y);
        let r2 = x * x + y * y;
        let l = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        Vector2::new(
            x * l + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
            y * l + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y,
        )
    }

    /// The Jacobian of [`Lens::apply`] at `n`.
    fn jacobian(&self, n: Vector2<f64>) -> Matrix2<f64> {
        let ([k1, k2, k3], [p1, p2]) = (self.k, self.p);
        let (x, y) = (n.x, n.y);
        let r2 = x * x + y * y;
        let l = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        let dl = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
        let cross = 2.0 * x * y * dl + 2.0 * p1 * x + 2.0 * p2 * y;
        Matrix2::new(
            l + 2.0 * x * x * dl + 2.0 * p1 * y + 6.0 * p2 * x,
            cross,
            cross,
            l + 2.0 * y * y * dl + 6.0 * p1 * y + 2.0 * p2 * x,
        )
    }

    /// True when the map at `r·u` keeps orientation and still moves outwards along `u`.
    fn unfolded(&self, u: Vector2<f64>, r: f64) -> bool {
        let j = self.jacobian(u * r);
        j.determinant() > 0.0 && u.dot(&(j * u)) > 0.0
    }
}

fn ray(i: u32) -> Vector2<f64> {
    let (s, c) = (f64::from(i) * std::f64::consts::TAU / f64::from(RAYS)).sin_cos();
    Vector2::new(c, s)
}

fn invalid<T>(reason: impl Into<String>) -> Result<T, SimError> {
    Err(SimError::Invalid { field: KEY.into(), reason: reason.into() })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::World;
    use proptest::prelude::*;

    fn mount(d: [f64; 5]) -> CameraMount {
        CameraMount { distortion: Some(d), ..World::default_world().camera }
    }

    #[test]
    fn barrel_pulls_a_corner_in_by_the_model() {
        let m = mount([-0.1, 0.0, 0.0, 0.0, 0.0]);
        let lens = Lens::new(&m).expect("valid").expect("some");
        let f = 6.0 / 0.00203;
        let c = Point2::new(891.0, 886.0);
        let x = 800.0 / f;
        let want = c.x + 800.0 * (1.0 - 0.1 * x * x);
        let got = lens.distort(c + Vector2::new(800.0, 0.0)).expect("in field");
        assert!((got.x - want).abs() < 1e-9 && (got.y - c.y).abs() < 1e-9, "{got} vs {want}");
        assert_eq!(lens.distort(c), Some(c), "the optical centre stays put");
        assert_eq!(Lens::new(&World::default_world().camera), Ok(None));
    }

    #[test]
    fn folding_and_non_finite_lenses_are_refused_by_key() {
        for d in [
            [-2.0, 0.0, 0.0, 0.0, 0.0],
            [f64::NAN, 0.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.9, 0.0, 0.0],
            [0.0, -30.0, 0.0, 0.0, 0.0],
        ] {
            match Lens::new(&mount(d)) {
                Err(SimError::Invalid { field, .. }) => assert_eq!(field, KEY, "{d:?}"),
                other => panic!("{d:?}: expected a refusal, got {other:?}"),
            }
        }
        // Strong barrel that turns back only far outside the frame is a lens, not a fold.
        assert!(Lens::new(&mount([-0.5, 0.0, 0.0, 0.0, 0.0])).expect("valid").is_some());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn accepted_lenses_round_trip_and_never_fold_in_the_frame(
            k1 in -3.0f64..3.0, k2 in -3.0f64..3.0, p1 in -0.05f64..0.05, p2 in -0.05f64..0.05, k3 in -3.0f64..3.0,
            angle in 0.0f64..std::f64::consts::TAU,
        ) {
            let mut world = World::default_world();
            world.camera.distortion = Some([k1, k2, p1, p2, k3]);
            match Lens::new(&world.camera) {
                Err(SimError::Invalid { field, .. }) => prop_assert_eq!(field, KEY),
                Err(e) => prop_assert!(false, "{e}"),
                Ok(None) => prop_assert!(false, "a distortion was given"),
                Ok(Some(lens)) => {
                    let again = World::from_toml(&world.to_toml().expect("toml")).expect("valid");
                    prop_assert_eq!(&again, &world);
                    // Along any ray to the frame's edge the image moves steadily outwards.
                    let (c, u) = (Point2::new(891.0, 886.0), Vector2::new(angle.cos(), angle.sin()));
                    let mut last = 0.0;
                    for i in 1..=125 {
                        // Beyond the field lies outside the frame.
                        let Some(p) = lens.distort(c + u * (f64::from(i) * 10.0)) else { break };
                        prop_assert!(p.x.is_finite() && p.y.is_finite());
                        if (0.0..=1776.0).contains(&p.x) && (0.0..=1776.0).contains(&p.y) {
                            let out = (p - c).dot(&u);
                            prop_assert!(out > last, "{i}: {out} after {last}");
                            last = out;
                        }
                    }
                }
            }
        }
    }
}
