//! [`SimCamera`]: a [`CameraDriver`] that sees the simulated table from the head's true position.

use vision_core::{CameraDriver, Capabilities, DriverError, DriverErrorKind, DriverRegistry, Judgment, Reading};
use vision_math::Point2;

use crate::sim::Sim;

/// Highest camera job number (as on a Keyence VS).
const MAX_JOB: u32 = 999;

/// The simulated camera. Drivers are dumb (SPEC §7): it returns native pixels only.
///
/// Per trigger: every present mark whose centre images at least the job's margin inside the
/// image is *in view*; the one nearest the image centre is reported (count = how many are in
/// view), with Gaussian noise of the job's σ on x and y. Nothing in view → NG, count 0.
/// Width and height are the mark's true diameter in pixels; the angle is the mark's rotation
/// seen in the image; the score is 0.99. Two normal samples are drawn per trigger whether or not
/// a mark is found, so the noise stream depends only on the number of triggers.
#[derive(Debug, Clone)]
pub struct SimCamera {
    sim: Sim,
}

impl Sim {
    /// A camera driver on this world.
    #[must_use]
    pub fn camera(&self) -> SimCamera {
        SimCamera { sim: self.clone() }
    }

    /// Registers the driver name `Sim` in `registry`, building cameras on this world.
    pub fn register(&self, registry: &mut DriverRegistry) {
        let sim = self.clone();
        registry.register("Sim", move |_params| Ok(Box::new(sim.camera()) as Box<dyn CameraDriver>));
    }
}

impl CameraDriver for SimCamera {
    fn name(&self) -> &str {
        "Sim"
    }

    fn capabilities(&self) -> Capabilities {
        Capabilities { select_job: true, grab_image: false }
    }

    fn trigger(&mut self) -> Result<Reading, DriverError> {
        let mut st = self.sim.lock();
        st.triggers += 1;
        let (sigma, margin) = st.job_settings();
        let noise = (st.rng.gaussian() * sigma, st.rng.gaussian() * sigma);
        let axis = st.camera_axis();
        let optics = st.optics();
        let centre = Point2::from(optics.resolution() * 0.5);
        let seen: Vec<_> = st
            .marks
            .iter()
            .filter_map(|m| Some((m, optics.image(m.position - axis)?)))
            .filter(|(_, p)| optics.in_view(*p, margin))
            .collect();
        let Some((mark, p)) = seen.iter().min_by(|a, b| (a.1 - centre).norm().total_cmp(&(b.1 - centre).norm())) else {
            return Ok(Reading { judgment: Judgment::Ng, count: Some(0), ..Reading::position(0.0, 0.0) });
        };
        let (width_px, height_px) = optics.size_px(mark.diameter);
        let camera = &st.world.camera;
        let seen_angle =
            if camera.mirror { -(mark.angle_deg - camera.rotation_deg) } else { mark.angle_deg - camera.rotation_deg };
        Ok(Reading {
            judgment: Judgment::Ok,
            count: Some(u32::try_from(seen.len()).unwrap_or(u32::MAX)),
            x_px: p.x + noise.0,
            y_px: p.y + noise.1,
            width_px,
            height_px,
            angle_deg: normalize_deg(seen_angle),
            score: 0.99,
        })
    }

    /// The world camera's resolution (the image every reading is counted in).
    fn frame_size(&mut self) -> Option<(u32, u32)> {
        let [w, h] = self.sim.lock().world.camera.resolution;
        Some((w, h))
    }

    fn select_job(&mut self, job: u32) -> Result<(), DriverError> {
        if job > MAX_JOB {
            return Err(DriverError::new(
                DriverErrorKind::InvalidArgument,
                format!("camera job {job} is out of range 0..{MAX_JOB}"),
            ));
        }
        let mut st = self.sim.lock();
        let jobs = &st.world.camera.jobs;
        if job != 0 && !jobs.is_empty() && !jobs.iter().any(|j| j.id == job) {
            let known = jobs.iter().map(|j| j.id.to_string()).collect::<Vec<_>>().join(", ");
            return Err(DriverError::new(
                DriverErrorKind::Rejected,
                format!("the simulated camera has no job {job} (the world defines jobs {known})"),
            ));
        }
        st.job = job;
        Ok(())
    }

    fn test_connection(&mut self) -> Result<String, DriverError> {
        Ok(format!("FVR,mach-vision-sim {}", env!("CARGO_PKG_VERSION")))
    }
}

/// `deg` folded into (−180, 180].
fn normalize_deg(deg: f64) -> f64 {
    let r = deg.rem_euclid(360.0);
    if r > 180.0 {
        r - 360.0
    } else {
        r
    }
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;
    use crate::World;
    use vision_gcode::{Interpreter, InterpreterConfig, Xyz};
    use vision_math::Vector2;

    /// Puts the optical axis over machine point `at`: a bare interpreter in the world's unit
    /// drives the head there.
    fn look_at(sim: &Sim, at: Point2<f64>) {
        let o = Vector2::from(sim.world().camera.offset);
        let p = at - o;
        let mut interp = Interpreter::new(InterpreterConfig::new(sim.unit()));
        sim.follow(interp.watch_position());
        interp.set_machine_position(Xyz::new(p.x, p.y, 0.0)).expect("finite");
    }

    fn quiet_world() -> World {
        let mut w = World::default_world();
        w.camera.noise_px = 0.0;
        w.camera.jobs.clear();
        w
    }

    #[test]
    fn sees_the_nearest_mark_through_the_true_optics() {
        let sim = Sim::new(quiet_world()).expect("sim");
        let mut cam = sim.camera();
        let dot5 = sim.marks()[4];
        look_at(&sim, dot5.position + Vector2::new(0.1, -0.05));
        let r = cam.trigger().expect("reading");
        assert_eq!((r.judgment, r.count), (Judgment::Ok, Some(1)));
        let want = sim.optics().pixel(Vector2::new(-0.1, 0.05));
        assert!((Point2::new(r.x_px, r.y_px) - want).norm() < 1e-9, "{r:?} vs {want}");
        assert!((r.width_px - 0.5 * (1.0008f64 * 1.0012).sqrt() / 0.00203).abs() < 1e-6);
        assert!((r.angle_deg - (0.3 - 0.6)).abs() < 1e-12);
        assert_eq!(sim.triggers(), 1);
    }

    #[test]
    fn nothing_in_view_is_ng_with_count_zero() {
        let sim = Sim::new(quiet_world()).expect("sim");
        look_at(&sim, Point2::new(-100.0, -100.0));
        let r = sim.camera().trigger().expect("reading");
        assert_eq!((r.judgment, r.count), (Judgment::Ng, Some(0)));
        assert!(!r.found());
    }

    #[test]
    fn the_margin_decides_what_is_in_view() {
        let sim = Sim::new(quiet_world()).expect("sim");
        let dot5 = sim.marks()[4].position;
        // 888 px − 40 px margin = 848 px from the centre; 860 px is outside, 840 px inside.
        for (px, found) in [(840.0, true), (860.0, false)] {
            look_at(&sim, dot5 - Vector2::new(px * 0.00203, 0.0));
            // The camera is rotated 0.6°, the bias shifts the centre by 3 px: stay clear of
            // the boundary by more than that.
            assert_eq!(sim.camera().trigger().expect("reading").found(), found, "{px}");
        }
    }

    #[test]
    fn jobs_change_the_noise_and_unknown_jobs_are_refused() {
        let mut w = World::default_world();
        w.camera.noise_px = 0.0;
        let sim = Sim::new(w).expect("sim");
        let mut cam = sim.camera();
        look_at(&sim, sim.marks()[4].position);
        let exact = cam.trigger().expect("r");
        cam.select_job(1).expect("job 1");
        let noisy = cam.trigger().expect("r");
        assert!((noisy.x_px - exact.x_px).abs() > 1e-6);
        let e = cam.select_job(7).expect_err("no job 7");
        assert_eq!(e.kind(), DriverErrorKind::Rejected);
        assert!(e.to_string().contains("jobs 1, 2"), "{e}");
        assert_eq!(cam.select_job(1000).expect_err("range").kind(), DriverErrorKind::InvalidArgument);
        assert_eq!(sim.job(), 1, "a refused switch keeps the job");
    }

    #[test]
    fn same_seed_same_readings() {
        let run = || {
            let sim = Sim::new(World::default_world()).expect("sim");
            look_at(&sim, sim.marks()[0].position);
            let mut cam = sim.camera();
            (0..5).map(|_| cam.trigger().expect("r").x_px).collect::<Vec<_>>()
        };
        assert_eq!(run(), run());
    }

    #[test]
    fn angles_fold_into_a_half_open_range() {
        assert_eq!(normalize_deg(190.0), -170.0);
        assert_eq!(normalize_deg(-180.0), 180.0);
        assert_eq!(normalize_deg(45.0), 45.0);
    }
}
