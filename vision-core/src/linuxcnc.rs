//! The alignment state of a LinuxCNC host (SPEC §9; the dialect itself is
//! [`vision_math::linuxcnc`]).
//!
//! LinuxCNC keeps the G5x rotation and the G92/G52 offset in its var file, across M2 and
//! restarts, so an alignment outlives the program and the session that made it. M280 must then
//! put back the rotation the operator had before M282 (θ₀), which the controller no longer
//! shows. The module keeps θ₀ and an "alignment active" flag in two numbered parameters.
//! LinuxCNC keeps a numbered parameter (#31–#5000) across restarts only when the var file
//! already lists it, so the install guide and the tests' var file list
//! [`PERSISTENT_PARAMS`].

use vision_math::linuxcnc::{cancel_gcode, LinuxCncAlignment};
use vision_math::{AlignmentChain, Matrix2, Point2, Vector2};

use crate::error::VisionError;
use crate::machine::{Controller, Machine};

/// `#3990`: 1 while an M282 alignment is active, 0 after M280 (a persistent parameter).
pub const ALIGNMENT_ACTIVE_PARAM: u32 = 3990;
/// `#3991`: θ₀, the active G5x system's rotation before the alignment, degrees
/// counter-clockwise (a persistent parameter); meaningful while [`ALIGNMENT_ACTIVE_PARAM`] is 1.
pub const BASE_ROTATION_PARAM: u32 = 3991;
/// Every parameter the var file must list for the alignment to survive a restart.
pub const PERSISTENT_PARAMS: [u32; 2] = [ALIGNMENT_ACTIVE_PARAM, BASE_ROTATION_PARAM];

/// True when the flag's value `flag` (from [`ALIGNMENT_ACTIVE_PARAM`]) says an alignment is
/// active (1; anything from 0.5 on, so a var file's `1.000000` counts).
#[must_use]
pub fn flag_set(flag: f64) -> bool {
    flag >= 0.5
}

/// The alignment a LinuxCNC host has active, from what it reports: the flag's value `flag`,
/// the stored θ₀ `base_rotation_deg`, the G5x rotation now `rotation_deg` (degrees
/// counter-clockwise) and the G92/G52 offset `g92` (program units). `None` when the flag is not
/// set. The chain maps the program frame into the frame turned by θ₀, as M282's chain does:
/// `R(θ)·(p + g92)` with `θ = rotation − θ₀`, i.e. a rotation about the origin and a shift of
/// `R(θ)·g92`.
#[must_use]
pub fn active_chain(flag: f64, base_rotation_deg: f64, rotation_deg: f64, g92: Vector2<f64>) -> Option<AlignmentChain> {
    if !flag_set(flag) {
        return None;
    }
    let mut chain = AlignmentChain {
        scale: Vector2::new(1.0, 1.0),
        center: Point2::origin(),
        rotation_deg: rotation_deg - base_rotation_deg,
        shift: Vector2::zeros(),
    };
    chain.shift = chain.rotation_matrix() * g92;
    Some(chain)
}

/// θ₀, the G5x rotation the program frame has without the alignment (degrees
/// counter-clockwise): on LinuxCNC the stored one while an alignment is active (also after a
/// restart); else the machine's rotation now (0 on Mach4).
pub(crate) fn base_rotation(machine: &dyn Machine) -> Result<f64, VisionError> {
    if machine.controller() == Controller::LinuxCnc && flag_set(machine.pound(ALIGNMENT_ACTIVE_PARAM)?) {
        Ok(machine.pound(BASE_ROTATION_PARAM)?)
    } else {
        Ok(machine.xy_rotation_deg())
    }
}

/// M280 on LinuxCNC: runs `G52 X0 Y0` and `G10 L2 P0 R{θ₀}`, then clears the flag; returns the
/// lines. When a line is refused the flag stays set, so the next M280 restores θ₀ again.
pub(crate) fn cancel(machine: &mut dyn Machine) -> Result<Vec<String>, VisionError> {
    let lines = cancel_gcode(base_rotation(machine)?)?.to_vec();
    machine.run_gcode(&lines)?;
    machine.set_pound(ALIGNMENT_ACTIVE_PARAM, 0.0)?;
    Ok(lines)
}

/// Refuses a fit whose chain `fit` scales by more than the scale gate `max_scale_dev_pct`
/// (percent; 0 disables): "LinuxCNC cannot scale: …".
pub(crate) fn check_scale(fit: &AlignmentChain, max_scale_dev_pct: f64) -> Result<(), VisionError> {
    LinuxCncAlignment::from_chain(fit, 0.0, max_scale_dev_pct)?;
    Ok(())
}

/// M282's `chain` as LinuxCNC executes it (its scale left out and reported), over the machine's
/// θ₀. Changes nothing.
pub(crate) fn plan(machine: &dyn Machine, chain: &AlignmentChain) -> Result<LinuxCncAlignment, VisionError> {
    Ok(LinuxCncAlignment::from_chain(chain, base_rotation(machine)?, 0.0)?)
}

/// Applies `alignment`: stores θ₀ and sets the flag first (so that an M280 after a refused line
/// still restores θ₀), then runs `G10 L2 P0 R…` and `G52 X… Y…`; returns the lines.
pub(crate) fn apply(machine: &mut dyn Machine, alignment: &LinuxCncAlignment) -> Result<Vec<String>, VisionError> {
    let lines = alignment.gcode()?.to_vec();
    machine.set_pound(BASE_ROTATION_PARAM, alignment.base_rotation_deg)?;
    machine.set_pound(ALIGNMENT_ACTIVE_PARAM, 1.0)?;
    machine.run_gcode(&lines)?;
    Ok(lines)
}

/// Turns `v`, measured along the machine axes (the camera's K output, its tool offset), into
/// the program frame of a G5x system rotated by `rotation_deg` (degrees counter-clockwise):
/// `R(−rotation)·v`. Exactly `v` when the rotation is 0 (every Mach4 host).
#[must_use]
pub fn machine_to_program(v: Vector2<f64>, rotation_deg: f64) -> Vector2<f64> {
    if rotation_deg == 0.0 {
        return v;
    }
    turn(v, -rotation_deg)
}

/// The inverse of [`machine_to_program`]: `R(rotation)·v`.
#[must_use]
pub fn program_to_machine(v: Vector2<f64>, rotation_deg: f64) -> Vector2<f64> {
    if rotation_deg == 0.0 {
        return v;
    }
    turn(v, rotation_deg)
}

fn turn(v: Vector2<f64>, deg: f64) -> Vector2<f64> {
    rotation(deg) * v
}

/// The matrix of a counter-clockwise rotation by `deg` degrees.
pub(crate) fn rotation(deg: f64) -> Matrix2<f64> {
    AlignmentChain { rotation_deg: deg, ..AlignmentChain::IDENTITY }.rotation_matrix()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn active_chain_reads_the_flag_and_rotates_the_g92_shift() {
        assert!(active_chain(0.0, 10.0, 12.0, Vector2::new(1.0, 0.0)).is_none());
        let chain = active_chain(1.0, 10.0, 100.0, Vector2::new(1.0, 0.0)).expect("flag set");
        // θ = 90°: (1, 0) + g92 = (2, 0) → (0, 2).
        let p = chain.apply(Point2::new(1.0, 0.0));
        assert!((p - Point2::new(0.0, 2.0)).norm() < 1e-12, "{p}");
    }

    #[test]
    fn machine_axes_turn_into_the_program_frame_and_back() {
        let v = Vector2::new(1.0, 0.0);
        assert_eq!(machine_to_program(v, 0.0), v);
        let p = machine_to_program(v, 90.0);
        assert!((p - Vector2::new(0.0, -1.0)).norm() < 1e-12, "{p}");
        assert!((program_to_machine(p, 90.0) - v).norm() < 1e-12);
    }
}
