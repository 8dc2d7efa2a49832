//! The shared simulated world: the truth, where the head is, the noise source and the camera
//! job, behind one cheap-to-clone handle that the camera and the machine both hold.

use std::sync::{Arc, Mutex, MutexGuard};

use nalgebra::Point3;
use vision_gcode::PositionWatch;
use vision_math::{LengthUnit, Point2, Vector2};

use crate::error::SimError;
use crate::fixture::TrueMark;
use crate::lens::Lens;
use crate::optics::Optics;
use crate::rng::Rng;
use crate::world::{Fixture, Job, World};

/// Everything the handle shares. Lengths in the world unit.
#[derive(Debug)]
pub(crate) struct State {
    pub(crate) world: World,
    /// Marks of every present fixture, machine coordinates.
    pub(crate) marks: Vec<TrueMark>,
    /// Where the spindle is.
    pub(crate) head: Head,
    pub(crate) rng: Rng,
    /// The selected camera job (0 = the base settings).
    pub(crate) job: u32,
    pub(crate) triggers: u64,
    /// Frames rendered by the image-mode camera (each seeds its own noise).
    pub(crate) frames: u64,
    /// The camera's lens distortion, built once (the camera never changes).
    pub(crate) lens: Option<Lens>,
}

/// Where the spindle is: at the world's start until a machine drives it, then wherever that
/// machine's interpreter says (its published position, machine coordinates in the world unit:
/// the interpreter runs in the world's unit). The interpreter is the one source; nothing here
/// keeps a copy of its position.
#[derive(Debug)]
pub(crate) enum Head {
    /// No machine: the spindle stays at this point (machine coordinates, world unit).
    Parked(Point3<f64>),
    /// The machine whose interpreter publishes to this watch.
    Driven(PositionWatch),
}

impl State {
    /// Spindle position, machine coordinates, world unit.
    pub(crate) fn spindle(&self) -> Point3<f64> {
        match &self.head {
            Head::Parked(p) => *p,
            Head::Driven(watch) => {
                let p = watch.get();
                Point3::new(p.x, p.y, p.z)
            }
        }
    }

    /// The settings of the selected job (noise σ, margin), pixels.
    pub(crate) fn job_settings(&self) -> (f64, f64) {
        let c = &self.world.camera;
        let job: Option<&Job> = c.jobs.iter().find(|j| j.id == self.job);
        (job.and_then(|j| j.noise_px).unwrap_or(c.noise_px), job.and_then(|j| j.margin_px).unwrap_or(c.margin_px))
    }

    /// Lens-to-surface distance now, world unit: the world's at its focus Z, plus how far the
    /// head rose since. Held at 1 % of the world's when the head went lower than the surface
    /// (the simulator does not model a crash).
    pub(crate) fn working_distance(&self) -> f64 {
        let camera = &self.world.camera;
        let focus_z = camera.focus_z.unwrap_or(self.world.machine.start[2]);
        let wd = camera.working_distance + (self.spindle().z - focus_z);
        wd.max(0.01 * camera.working_distance)
    }

    /// The true optics with the head where it is now.
    pub(crate) fn optics(&self) -> Optics {
        Optics::with_lens(&self.world.camera, self.working_distance(), self.lens)
    }

    /// The optical axis, machine coordinates.
    pub(crate) fn camera_axis(&self) -> Point2<f64> {
        let spindle = self.spindle();
        Point2::new(spindle.x, spindle.y) + Vector2::from(self.world.camera.offset)
    }
}

/// Machine coordinates of every mark of the present fixtures.
fn place(world: &World) -> Vec<TrueMark> {
    let unit = world.length_unit();
    world
        .fixtures
        .iter()
        .filter(|f| f.present)
        .flat_map(|f| f.true_marks(unit))
        .map(|m| TrueMark { position: world.work_to_machine(m.position), ..m })
        .collect()
}

/// A handle on one simulated world; clones share it.
#[derive(Debug, Clone)]
pub struct Sim {
    shared: Arc<Mutex<State>>,
}

impl Sim {
    /// A simulation of `world`, with the head at the world's start position.
    ///
    /// # Errors
    /// [`SimError::Invalid`] when the world does not validate.
    pub fn new(world: World) -> Result<Sim, SimError> {
        world.validate()?;
        let state = State {
            marks: place(&world),
            head: Head::Parked(Point3::from(world.machine.start)),
            rng: Rng::new(world.seed),
            job: 0,
            triggers: 0,
            frames: 0,
            lens: Lens::new(&world.camera)?,
            world,
        };
        Ok(Sim { shared: Arc::new(Mutex::new(state)) })
    }

    pub(crate) fn lock(&self) -> MutexGuard<'_, State> {
        // A panic while holding the lock cannot leave State inconsistent (every write is a
        // single assignment), so a poisoned lock is still usable.
        self.shared.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// A copy of the world as it is now (fixtures included).
    #[must_use]
    pub fn world(&self) -> World {
        self.lock().world.clone()
    }

    /// The world's length unit.
    #[must_use]
    pub fn unit(&self) -> LengthUnit {
        self.lock().world.length_unit()
    }

    /// The true optics with the head where it is now (the scale follows its Z).
    #[must_use]
    pub fn optics(&self) -> Optics {
        self.lock().optics()
    }

    /// Lens-to-surface distance with the head where it is now, world unit.
    #[must_use]
    pub fn working_distance(&self) -> f64 {
        self.lock().working_distance()
    }

    /// Spindle position, machine coordinates, world unit: the world's start, or where the
    /// [`crate::SimMachine`] on this world is.
    #[must_use]
    pub fn spindle(&self) -> Point3<f64> {
        self.lock().spindle()
    }

    /// From now on the head is where the interpreter behind `watch` is (its machine unit must be
    /// the world's).
    pub(crate) fn follow(&self, watch: PositionWatch) {
        self.lock().head = Head::Driven(watch);
    }

    /// Parks the spindle at `spindle` (machine coordinates, world unit) until the next call or
    /// the next [`crate::SimMachine`] on this world: for a host whose machine runs outside the
    /// simulation (LinuxCNC's interpreter in the bridge's tests), which places the head where
    /// its machine is before each trigger. Stops following any interpreter.
    pub fn place_head(&self, spindle: Point3<f64>) {
        self.lock().head = Head::Parked(spindle);
    }

    /// The camera's optical axis, machine coordinates, world unit.
    #[must_use]
    pub fn camera_axis(&self) -> Point2<f64> {
        self.lock().camera_axis()
    }

    /// Every mark on the table, machine coordinates, world unit.
    #[must_use]
    pub fn marks(&self) -> Vec<TrueMark> {
        self.lock().marks.clone()
    }

    /// Number of camera triggers so far.
    #[must_use]
    pub fn triggers(&self) -> u64 {
        self.lock().triggers
    }

    /// The selected camera job (0 = base settings).
    #[must_use]
    pub fn job(&self) -> u32 {
        self.lock().job
    }

    /// Puts fixture `name` on the table or takes it off (the operator swapping a calibration
    /// sheet for a part).
    ///
    /// # Errors
    /// [`SimError::UnknownFixture`].
    pub fn set_present(&self, name: &str, present: bool) -> Result<(), SimError> {
        let mut st = self.lock();
        let known = st.world.fixtures.iter().map(|f| f.name.clone()).collect::<Vec<_>>().join(", ");
        let f = st
            .world
            .fixtures
            .iter_mut()
            .find(|f| f.name == name)
            .ok_or_else(|| SimError::UnknownFixture { name: name.to_string(), known })?;
        f.present = present;
        st.marks = place(&st.world);
        Ok(())
    }

    /// Replaces everything on the table.
    ///
    /// # Errors
    /// [`SimError::Invalid`] when a fixture does not validate; the table is left unchanged.
    pub fn set_fixtures(&self, fixtures: Vec<Fixture>) -> Result<(), SimError> {
        let mut st = self.lock();
        let mut world = st.world.clone();
        world.fixtures = fixtures;
        world.validate()?;
        st.marks = place(&world);
        st.world = world;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixtures_come_and_go() {
        let sim = Sim::new(World::default_world()).expect("sim");
        assert_eq!(sim.marks().len(), 15);
        // Work zero is G54 = (10, 8): dot 5 lies there in machine coordinates.
        assert!((sim.marks()[4].position - Point2::new(10.0, 8.0)).norm() < 1e-12);
        sim.set_present("demo target", false).expect("known");
        assert!(sim.marks().is_empty());
        assert!(matches!(sim.set_present("nope", true), Err(SimError::UnknownFixture { .. })));
        let mut bad = sim.world().fixtures;
        bad[0].scale = [-1.0, 1.0];
        assert!(sim.set_fixtures(bad).is_err());
        assert!(sim.marks().is_empty(), "a refused table leaves the old one");
    }

    #[test]
    fn a_placed_head_is_where_the_camera_looks_from() {
        use vision_core::CameraDriver;
        let sim = Sim::new(World::default_world()).expect("sim");
        let mut camera = sim.camera();
        // Camera axis over dot 5, at machine (10, 8): the spindle is the camera offset away.
        let spindle = Point3::new(10.0 + 3.25, 8.0 - 1.75, 0.0);
        sim.place_head(spindle);
        assert_eq!(sim.spindle(), spindle);
        let centre = camera.trigger().expect("reading");
        assert!(centre.found());
        let half = sim.optics().resolution() * 0.5;
        assert!((centre.x_px - half.x).hypot(centre.y_px - half.y) < 40.0, "{centre:?}");
        // Far off the table: nothing in view.
        sim.place_head(Point3::new(40.0, 40.0, 0.0));
        assert!(!camera.trigger().expect("reading").found());
    }
}
