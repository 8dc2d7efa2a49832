//! The modal state: everything a line can change except the parameters and the tool table.

use vision_math::LengthUnit;

use super::cycles::CycleState;
use crate::config::InterpreterConfig;
use crate::error::GCode;
use crate::event::PathMode;
use crate::frame::{Frame, Placement, SystemRotation};
use crate::geom::{ArcDirection, Plane, Xyz};
use crate::params::{work_rotation, ParameterTable, G92_OFFSET};

/// The active motion mode (modal group 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MotionMode {
    /// G0.
    Rapid,
    /// G1.
    Linear,
    /// G2 / G3.
    Arc(ArcDirection),
    /// A canned cycle: G73, G81, G82, G83, G85 or G89.
    Cycle(GCode),
}

/// The modal state. `Copy`, so a line works on a copy and commits it only when it succeeds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Modal {
    pub(crate) motion: Option<MotionMode>,
    pub(crate) plane: Plane,
    /// G90 (true) / G91.
    pub(crate) absolute: bool,
    /// G90.1 (true) / G91.1.
    pub(crate) arc_absolute: bool,
    pub(crate) units: LengthUnit,
    pub(crate) path: PathMode,
    /// 1 (G54) … 6 (G59).
    pub(crate) system: u32,
    /// The active system's origin in force, machine units: loaded from its parameters when the
    /// system is selected, set by G10, or (per dialect) written; see [`Modal::load_system`].
    pub(crate) origin: Xyz,
    /// The active system's XY rotation in force (LinuxCNC's `G10 L2 R`), degrees
    /// counter-clockwise; always 0 in the other dialects.
    pub(crate) rotation: f64,
    /// Machine units per minute (G94) or per revolution (G95).
    pub(crate) feed: Option<f64>,
    /// G95: `feed` is per spindle revolution, and a feed move goes at `feed` × `speed`.
    pub(crate) per_revolution: bool,
    /// The last `T`.
    pub(crate) selected_tool: u32,
    /// The tool loaded by M6.
    pub(crate) tool: u32,
    /// Its offset and length, machine units (cached from the tool table).
    pub(crate) tool_offset: Xyz,
    pub(crate) frame: Frame,
    /// Spindle speed `S` (revolutions per minute), `None` before any `S`.
    pub(crate) speed: Option<f64>,
    /// G99 (true: canned cycles retract to R) / G98 (to the level the series started at).
    pub(crate) retract_to_r: bool,
    /// What a series of canned cycles remembers.
    pub(crate) cycle: CycleState,
    /// Current point in the program frame, machine units.
    pub(crate) program: Xyz,
    /// Current machine position (the spindle), machine units.
    pub(crate) machine: Xyz,
}

impl Modal {
    /// The start-up state at machine position `machine`.
    pub(crate) fn initial(config: &InterpreterConfig) -> Modal {
        Modal {
            motion: None,
            plane: Plane::Xy,
            absolute: true,
            arc_absolute: false,
            units: config.initial_units,
            path: config.initial_path_mode,
            system: 1,
            origin: Xyz::ZERO,
            rotation: 0.0,
            feed: config.default_feed,
            per_revolution: false,
            selected_tool: 0,
            tool: 0,
            tool_offset: Xyz::ZERO,
            frame: Frame::identity(),
            speed: None,
            retract_to_r: true,
            cycle: CycleState::default(),
            program: Xyz::ZERO,
            machine: Xyz::ZERO,
        }
    }

    /// What M2/M30 (and [`crate::Interpreter::reset`]) do: restore G54, G17, G90, G91.1, G94, no
    /// motion mode, the initial path mode, G51/G68/G52 cancelled; zero the G92 offset (logged in
    /// `params`' undo log, so a failing line takes it back); re-derive the program position.
    /// Units, feed, tools and the machine position stay.
    pub(crate) fn end_program(&mut self, config: &InterpreterConfig, params: &mut ParameterTable) {
        self.motion = None;
        self.plane = Plane::Xy;
        self.absolute = true;
        self.arc_absolute = false;
        self.path = config.initial_path_mode;
        self.per_revolution = false;
        self.system = 1;
        self.frame = Frame::identity();
        for axis in 0..3 {
            params.set(G92_OFFSET + axis, 0.0);
        }
        self.load_system(config, params);
        self.rederive_program(params);
    }

    /// The program → machine map now.
    pub(crate) fn placement(&self, params: &ParameterTable) -> Placement {
        let [gx, gy, gz] = params.triple(G92_OFFSET);
        let (work, g92) = (self.origin, Xyz::new(gx, gy, gz));
        Placement {
            frame: self.frame,
            offset: Placement::offset(work, g92, self.tool_offset),
            rotation: SystemRotation::new(self.rotation, work, g92, self.tool_offset),
        }
    }

    /// Takes the active system's origin and rotation from its parameters (the rotation under
    /// LinuxCNC only; the other dialects have none).
    pub(crate) fn load_system(&mut self, config: &InterpreterConfig, params: &ParameterTable) {
        let [x, y, z] = params.triple(work_offset_base(self.system));
        self.origin = Xyz::new(x, y, z);
        self.rotation = system_rotation(config, params, self.system);
    }

    /// After a program line wrote an offset parameter (G92 or a system's origin or rotation;
    /// `g92` whether the G92 offset was among them): the G92 offset always takes effect; a
    /// written origin of the active system does at once in Mach4 and seed 002, and under
    /// LinuxCNC only when the system is selected again from another one, or a G10 sets it
    /// (rs274 2.9: `convert_coordinate_system` reloads the parameters only on a change of
    /// system). Where the frame changed the program point is re-derived: the machine stays.
    /// Under LinuxCNC a written origin leaves the frame, so rs274's current point stays as it
    /// is (it need not read the machine position after a rotation change with a G92/G52
    /// offset in force).
    pub(crate) fn after_offset_write(&mut self, config: &InterpreterConfig, params: &ParameterTable, g92: bool) {
        if !config.rules().origin_reloads_on_system_change {
            self.load_system(config, params);
        } else if !g92 {
            return;
        }
        self.rederive_program(params);
    }

    /// Re-derives the program position from the machine position (after a frame change; the
    /// machine does not move).
    pub(crate) fn rederive_program(&mut self, params: &ParameterTable) {
        self.program = self.placement(params).program_of(self.machine);
    }
}

/// Coordinate system `system`'s XY rotation, degrees: its parameter under LinuxCNC, 0 in the
/// dialects without coordinate-system rotation.
pub(crate) fn system_rotation(config: &InterpreterConfig, params: &ParameterTable, system: u32) -> f64 {
    if config.rules().rotated_systems {
        params.get(work_rotation(system))
    } else {
        0.0
    }
}

pub(crate) use crate::params::{is_work_offset, work_offset_base, SYSTEMS};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn work_offsets_are_the_xyz_of_g54_to_g59() {
        assert_eq!(work_offset_base(1), 5221);
        assert_eq!(work_offset_base(6), 5321);
        assert_eq!(work_offset_base(9), 5321);
        let offsets: Vec<u32> = (5000..5500).filter(|&n| is_work_offset(n)).collect();
        let expected: Vec<u32> = (0..6).flat_map(|s| (0..3).map(move |a| 5221 + 20 * s + a)).collect();
        assert_eq!(offsets, expected);
    }
}
