//! **Tests only** (feature `sim`): a session whose camera sees vision-driver-sim's built-in
//! world, as `mach-vision run` sets it up ([`vision_host::testkit::Rig`]), with the head put
//! where the LinuxCNC interpreter's machine is before each call.
//!
//! The simulation has no machine of its own here: LinuxCNC's interpreter (rs274 in the tests)
//! is the machine. The test's `Host.machine_position()` applies LinuxCNC's canon to the
//! interpreter's state (`g5x + R(rotation)·(p + g92) + tool`) and the head is parked there
//! ([`vision_driver_sim::Sim::place_head`]) before the camera can trigger.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::Point3;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use vision_host::testkit::{self, Camera, Rig};
use vision_host::{HostError, Machine, Session};
use vision_math::{LengthUnit, Point2, Vector2};

use crate::host::PyHost;

/// The part's pose on the table, replacing the built-in world's where given.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Pose {
    /// Rotation about the part's centre, degrees counter-clockwise.
    pub(crate) rotation_deg: Option<f64>,
    /// Shift, X and Y, world unit (inches).
    pub(crate) shift: Option<(f64, f64)>,
    /// Print scale, X and Y.
    pub(crate) scale: Option<(f64, f64)>,
}

/// The simulated rig behind a session's camera.
pub(crate) struct Simulated {
    rig: Rig,
}

/// The built-in world's part, the one [`Pose`] places.
const PART: &str = "demo target";

impl Simulated {
    /// The rig for `camera` (`"sim"` or `"keyence"`) with the part at `pose` and the camera's
    /// lens `distortion` (`[k1, k2, p1, p2, k3]`, none when `None`), and a session on it:
    /// without `profile`, no profile file, perfectly calibrated (the lens included), or with K
    /// never calibrated when not `calibrated`; with `profile`, the session of that file as
    /// `Session(profile)` opens it (M283 and M284 save to it; `calibrated` has no effect), its
    /// `VisionDriver` naming the simulated camera (`Sim`) or a real driver. Then the numeric
    /// parameters `params` are set.
    ///
    /// # Errors
    /// An unknown camera name, a pose the world refuses or a parameter the module refuses, as a
    /// message.
    pub(crate) fn new(
        camera: &str,
        pose: Pose,
        distortion: Option<[f64; 5]>,
        calibrated: bool,
        params: &BTreeMap<String, f64>,
        profile: Option<&Path>,
    ) -> Result<(Simulated, Session), String> {
        let camera = match camera {
            "sim" => Camera::Sim,
            "keyence" => Camera::Keyence,
            other => return Err(format!("camera {other:?} is not simulated: use \"sim\" or \"keyence\"")),
        };
        let mut world = vision_driver_sim::World::default_world();
        world.camera.distortion = distortion;
        let sim = vision_driver_sim::Sim::new(world).map_err(|e| e.to_string())?;
        let base = (!calibrated).then(|| testkit::uncalibrated_params(&sim));
        let (rig, module) = Rig::with_sim(sim, base, camera);
        let mut session = match profile {
            None => Session::new(module),
            Some(path) => Session::open(path, &vision_host::cameras(Some(&rig.sim))).map_err(|e| e.to_string())?,
        };
        for (name, value) in params {
            session.module_mut().set_param(name, *value).map_err(|e| e.to_string())?;
        }
        let mut fixtures = rig.sim.world().fixtures;
        let part = fixtures.iter_mut().find(|f| f.name == PART).ok_or_else(|| format!("no {PART:?} in the world"))?;
        if let Some(r) = pose.rotation_deg {
            part.rotation_deg = r;
        }
        if let Some((x, y)) = pose.shift {
            part.shift = [x, y];
        }
        if let Some((x, y)) = pose.scale {
            part.scale = [x, y];
        }
        rig.sim.set_fixtures(fixtures).map_err(|e| e.to_string())?;
        Ok((Simulated { rig }, session))
    }

    /// Parks the simulated head where `host.machine_position()` says the machine is (machine
    /// X, Y and, when it gives one, Z, in the program's units, converted to the world's; without
    /// a Z the head keeps its height). The camera's working distance follows that Z.
    pub(crate) fn place_head(&self, host: &PyHost<'_>) -> Result<(), HostError> {
        let (x, y, z): (f64, f64, Option<f64>) = match host.value::<(f64, f64, f64)>("machine_position", (), "") {
            Ok((x, y, z)) => (x, y, Some(z)),
            Err(_) => {
                let (x, y) = host.value("machine_position", (), "an (x, y) or (x, y, z) tuple of numbers")?;
                (x, y, None)
            }
        };
        let (from, to) = (host.units()?, self.rig.sim.unit());
        let z = z.map_or(self.rig.sim.spindle().z, |z| from.convert(z, to));
        self.rig.sim.place_head(Point3::new(from.convert(x, to), from.convert(y, to), z));
        Ok(())
    }

    /// Where nominal part point (`x`, `y`) (work coordinates, world unit) really is, machine
    /// coordinates, world unit.
    pub(crate) fn true_point(&self, x: f64, y: f64) -> Result<(f64, f64), String> {
        let world = self.rig.sim.world();
        let part = world.fixtures.iter().find(|f| f.name == PART).ok_or_else(|| format!("no {PART:?} in the world"))?;
        let p = world.work_to_machine(part.true_point(Point2::new(x, y), world.length_unit()));
        Ok((p.x, p.y))
    }

    /// What the controller must hold for this world (see `Session.setup`).
    pub(crate) fn setup<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let world = self.rig.sim.world();
        let unit = world.length_unit();
        // The module's offset is where the camera's reference point lies from the spindle;
        // LinuxCNC adds its table offset to a programmed point, so its table holds the negation.
        let offset =
            world.machine.camera_table_offset.map_or_else(|| self.rig.sim.calibrated_table_offset(unit), Vector2::from);
        let dict = PyDict::new(py);
        dict.set_item("work_offset", (world.machine.work_offset[0], world.machine.work_offset[1]))?;
        dict.set_item("camera_tool", world.machine.camera_tool)?;
        dict.set_item("camera_table_offset", (-offset.x, -offset.y))?;
        dict.set_item("unit", if unit == LengthUnit::Inch { "in" } else { "mm" })?;
        Ok(dict)
    }
}
