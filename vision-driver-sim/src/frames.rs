//! The image-mode camera: what the simulated camera would *see* — the fixtures' marks rendered
//! through the same optics the reading-mode camera ([`crate::SimCamera`]) uses, with the
//! world's print, focus, light and sensor ([`crate::world::ImageLook`]) — so a driver that
//! finds the mark itself can run on the simulated machine.
//!
//! Geometry: a mark whose centre images at native pixel `p` ([`crate::Optics::image`], origin
//! at the top-left corner of the image, lens distortion included) is drawn centred at
//! `p − (½, ½)` in the renderer's pixel-centre coordinates, so a finder that reports pixel
//! centres and a driver that adds ½ back give exactly the reading-mode camera's native pixels.
//! Its diameter in pixels is [`crate::Optics::size_px`] (the mean of width and height for
//! non-square pixels). Decision: the lens moves a mark's centre but does not reshape it (its
//! few-percent squash near a corner would shift a real blob's centroid by a tenth of a pixel
//! or so), so the finder and the reading-mode camera agree on where the mark is.
//!
//! Defocus: blur σ = `blur_px` + `defocus_px_per_pct` × |working distance − focus distance| /
//! focus distance × 100.

use vision_locate::render::{self, Depth, Lighting, PlacedMark, Scene, Shape};
use vision_locate::MarkKind;
use vision_locate::{OwnedImage, OwnedPixels};
use vision_math::Point2;

use crate::error::SimError;
use crate::sim::{Sim, State};
use crate::world::ImageLook;

/// A rendered frame and the truth in it.
#[derive(Debug, Clone, PartialEq)]
pub struct SimFrame {
    /// The image, 8 bit, the camera's resolution.
    pub image: OwnedImage,
    /// Where every mark drawn in it really is, native pixels (corner origin), nearest the
    /// image centre first.
    pub marks: Vec<Point2<f64>>,
    /// The mark diameter drawn, pixels.
    pub diameter_px: f64,
    /// The blur σ used (lens plus defocus), pixels.
    pub blur_px: f64,
}

impl SimFrame {
    /// The 8-bit pixels, row-major.
    #[must_use]
    pub fn gray8(&self) -> &[u8] {
        match self.image.pixels() {
            OwnedPixels::Gray8(p) => p,
            OwnedPixels::Gray16(_) => &[],
        }
    }
}

impl Sim {
    /// The world's image look ([`ImageLook::default`] when the world has none).
    #[must_use]
    pub fn image_look(&self) -> ImageLook {
        self.lock().world.camera.image.clone().unwrap_or_default()
    }

    /// How many frames [`Sim::render_frame`] has rendered.
    #[must_use]
    pub fn frames_rendered(&self) -> u64 {
        self.lock().frames
    }

    /// The marks' diameter in the image, pixels (the first mark's; the worlds print one size).
    #[must_use]
    pub fn mark_diameter_px(&self) -> Option<f64> {
        let st = self.lock();
        st.marks.first().map(|m| mean_size(&st, m.diameter))
    }

    /// The largest search radius about the image centre, pixels, that leaves every other mark
    /// wholly outside while the camera is centred on one (the closest two marks' distance in
    /// pixels, less a mark radius and three blur σ); `None` with fewer than two marks.
    #[must_use]
    pub fn clear_radius_px(&self) -> Option<f64> {
        let st = self.lock();
        let look = st.world.camera.image.clone().unwrap_or_default();
        let origin = st.optics().pixel(vision_math::Vector2::zeros());
        let mut closest: Option<(f64, f64)> = None;
        for (i, a) in st.marks.iter().enumerate() {
            for b in &st.marks[i + 1..] {
                let d = (st.optics().pixel(a.position - b.position) - origin).norm();
                let r = 0.5 * mean_size(&st, a.diameter.max(b.diameter));
                if closest.is_none_or(|(c, _)| d < c) {
                    closest = Some((d, r));
                }
            }
        }
        closest.map(|(d, r)| d - r - 3.0 * (look.blur_px + look.defocus_px_per_pct * defocus_pct(&st)))
    }

    /// Renders what the camera sees from the head's true position now. Each frame has its own
    /// noise (seeded by the world's seed and the frame number), so frames are reproducible.
    ///
    /// # Errors
    /// [`SimError::Invalid`] when the renderer refuses the scene (an image over 2^28 pixels).
    pub fn render_frame(&self) -> Result<SimFrame, SimError> {
        let scene_and_truth = {
            let mut st = self.lock();
            st.frames += 1;
            scene(&st)
        };
        let (scene, marks, diameter_px) = scene_and_truth;
        let image = render::render(&scene)
            .map_err(|e| SimError::Invalid { field: "camera.image".into(), reason: e.to_string() })?;
        Ok(SimFrame { image, marks, diameter_px, blur_px: scene.blur_sigma })
    }
}

fn mean_size(st: &State, diameter: f64) -> f64 {
    let (w, h) = st.optics().size_px(diameter);
    0.5 * (w + h)
}

/// The working-distance change from the focus distance, percent.
fn defocus_pct(st: &State) -> f64 {
    let camera = &st.world.camera;
    let look = camera.image.clone().unwrap_or_default();
    let focus = look.focus_distance.or(camera.reference_working_distance).unwrap_or(camera.working_distance);
    (st.working_distance() - focus).abs() / focus * 100.0
}

/// The scene the camera sees now, the true mark centres (native pixels) and the diameter.
fn scene(st: &State) -> (Scene, Vec<Point2<f64>>, f64) {
    let look = st.world.camera.image.clone().unwrap_or_default();
    let camera = &st.world.camera;
    let res = st.optics().resolution();
    let axis = st.camera_axis();
    let centre = Point2::from(res * 0.5);
    let blur = look.blur_px + look.defocus_px_per_pct * defocus_pct(st);
    let mut seen: Vec<(Point2<f64>, f64, f64)> = st
        .marks
        .iter()
        .filter_map(|m| {
            let seen_deg =
                if camera.mirror { -(m.angle_deg - camera.rotation_deg) } else { m.angle_deg - camera.rotation_deg };
            Some((st.optics().image(m.position - axis)?, mean_size(st, m.diameter), seen_deg))
        })
        // Anything that reaches into the frame (with its blur) is drawn, clipped or not.
        .filter(|(p, d, _)| {
            let reach = d / 2.0 + 3.0 * blur;
            p.x > -reach && p.y > -reach && p.x < res.x + reach && p.y < res.y + reach
        })
        .collect();
    seen.sort_by(|a, b| (a.0 - centre).norm().total_cmp(&(b.0 - centre).norm()));
    let diameter = seen.first().map_or_else(|| st.marks.first().map_or(0.0, |m| mean_size(st, m.diameter)), |s| s.1);
    let line = look.line_width_pct / 100.0;
    let marks = seen
        .iter()
        .map(|&(p, d, deg)| PlacedMark {
            shape: match look.mark {
                MarkKind::Dot => Shape::Dot { diameter: d },
                MarkKind::Ring => Shape::Ring { diameter: d, line_width: d * line },
                // Counter-clockwise on the table is towards −y in the image.
                MarkKind::Cross => Shape::Cross { length: d, bar_width: d * line, angle: -deg.to_radians() },
            },
            x: p.x - 0.5,
            y: p.y - 0.5,
            reflectance: look.ink,
        })
        .collect();
    let (w, h) = (camera.resolution[0] as usize, camera.resolution[1] as usize);
    let seed = st.world.seed ^ st.frames.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let clutter = match (look.clutter, seen.first()) {
        (0, _) => Vec::new(),
        (n, nearest) => {
            let (x, y) = nearest.map_or((res.x / 2.0, res.y / 2.0), |s| (s.0.x - 0.5, s.0.y - 0.5));
            // Clear of the mark by a quarter diameter, so clutter never touches the truth.
            render::random_clutter(seed, n as usize, w, h, (x, y, diameter), diameter * 0.75 + 3.0 * blur)
        }
    };
    let scene = Scene {
        width: w,
        height: h,
        depth: Depth::Eight,
        background: look.ground,
        texture: None,
        clutter,
        marks,
        blur_sigma: blur,
        lighting: Lighting {
            level: look.light,
            gradient: look.light_gradient_pct / 100.0,
            angle: look.light_angle_deg.to_radians(),
        },
        noise_sigma: look.noise_grey,
        seed,
    };
    let truth = seen.iter().map(|s| s.0).collect();
    (scene, truth, diameter)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::World;
    use nalgebra::Point3;
    use vision_math::Vector2;

    #[test]
    fn the_frame_shows_the_mark_where_the_reading_camera_reports_it() {
        let mut world = World::default_world();
        world.camera.noise_px = 0.0;
        world.camera.jobs.clear();
        world.camera.image =
            Some(ImageLook { noise_grey: 0.0, light_gradient_pct: 0.0, blur_px: 0.0, ..ImageLook::default() });
        let sim = Sim::new(world).expect("sim");
        // Camera axis 0.05 in off dot 5 (machine (10, 8)).
        sim.place_head(Point3::new(10.0 + 3.25 + 0.05, 8.0 - 1.75 - 0.02, 0.0));
        let frame = sim.render_frame().expect("frame");
        let reading = vision_core::CameraDriver::trigger(&mut sim.camera()).expect("reading");
        assert_eq!(frame.marks.len(), 1, "{:?}", frame.marks);
        let truth = frame.marks[0];
        assert!((truth - Point2::new(reading.x_px, reading.y_px)).norm() < 1e-9, "{truth} vs {reading:?}");
        assert!((frame.diameter_px - reading.width_px).abs() < 1e-9);
        // The drawn disc's dark-pixel centroid sits at the truth (native pixels).
        let centroid = centroid(&frame);
        assert!((centroid - truth).norm() < 0.05, "{centroid} vs {truth}");
        assert!((frame.blur_px - 0.0).abs() < 1e-12);
    }

    #[test]
    fn through_a_barrel_lens_the_frame_and_the_reading_agree_up_to_a_corner() {
        let mut world = World::default_world();
        world.camera.noise_px = 0.0;
        world.camera.jobs.clear();
        world.camera.distortion = Some([-0.10, 0.0, 0.0, 0.0, 0.0]);
        world.camera.image =
            Some(ImageLook { noise_grey: 0.0, light_gradient_pct: 0.0, blur_px: 0.0, ..ImageLook::default() });
        world.fixtures.truncate(1);
        world.fixtures[0].sheet = None;
        world.fixtures[0].marks = vec![[0.0, 0.0]];
        let sim = Sim::new(world).expect("sim");
        let mark = sim.marks()[0].position;
        let offset = Vector2::from(sim.world().camera.offset);
        // Image offsets of the mark in inches: centre, sides, and 1.5 in (740 px) off both axes.
        for v in [[0.0, 0.0], [1.2, 0.0], [0.0, -1.3], [-1.5, 1.5], [1.5, -1.45]] {
            let axis = mark - Vector2::from(v);
            sim.place_head(Point3::new(axis.x - offset.x, axis.y - offset.y, 0.0));
            let frame = sim.render_frame().expect("frame");
            let r = vision_core::CameraDriver::trigger(&mut sim.camera()).expect("reading");
            let linear = sim.optics().pixel(Vector2::from(v));
            assert!(r.found(), "{v:?}");
            let reading = Point2::new(r.x_px, r.y_px);
            assert!((frame.marks[0] - reading).norm() < 1e-9, "{v:?}");
            let c = centroid(&frame);
            assert!((c - reading).norm() < 0.05, "{v:?}: drawn at {c}, read at {reading}");
            // The lens really moved it: barrel pulls a point 700 px off by about 5 px.
            if v[0] != 0.0 && v[1] != 0.0 {
                assert!((linear - reading).norm() > 5.0, "{v:?}: {linear} vs {reading}");
            }
        }
    }

    /// The dark-pixel centroid of a noiseless, evenly lit frame, native pixels.
    fn centroid(frame: &SimFrame) -> Point2<f64> {
        let (w, px) = (frame.image.width(), frame.gray8());
        let (mut sx, mut sy, mut n) = (0.0, 0.0, 0.0);
        for (i, &v) in px.iter().enumerate() {
            let dark = (255.0 - f64::from(v)).max(0.0) - (255.0 - 0.85 * 0.9 * 255.0);
            if dark > 1.0 {
                let (x, y) = ((i % w) as f64, (i / w) as f64);
                sx += dark * x;
                sy += dark * y;
                n += dark;
            }
        }
        Point2::new(sx / n + 0.5, sy / n + 0.5)
    }

    #[test]
    fn defocus_grows_with_the_working_distance_change() {
        let mut world = World::default_world();
        world.camera.working_distance = 6.6; // 10 % farther than the 6.0 focus
        let sim = Sim::new(world).expect("sim");
        let frame = sim.render_frame().expect("frame");
        assert!((frame.blur_px - (0.8 + 0.5 * 10.0)).abs() < 1e-9, "{}", frame.blur_px);
        // Nothing in view: a blank frame, no truth.
        sim.place_head(Point3::new(40.0, 40.0, 0.0));
        assert!(sim.render_frame().expect("frame").marks.is_empty());
    }

    #[test]
    fn a_bad_look_is_refused_by_name() {
        let mut world = World::default_world();
        world.camera.image = Some(ImageLook { ink: 0.84, ..ImageLook::default() });
        let e = Sim::new(world).expect_err("invisible mark");
        assert!(e.to_string().contains("camera.image.ink"), "{e}");
        let text = World::default_world().to_toml().expect("toml");
        assert!(!text.contains("[camera.image]"), "an absent look stays absent");
    }
}
