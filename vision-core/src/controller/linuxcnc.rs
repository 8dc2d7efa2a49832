//! LinuxCNC 2.9 (SPEC §9): no G68 and no G51, so M282 rotates the active G5x system
//! ([`MachineCommand::SetWorkRotation`], about its origin) and shifts
//! ([`MachineCommand::SetShift`], kept in the G92 registers), and cannot scale
//! ([`vision_math::linuxcnc`]).
//!
//! LinuxCNC keeps the G5x rotation and the G92/G52 offset in its var file, across M2 and
//! restarts, so an alignment outlives the program and the session that made it. M280 must then
//! put back the rotation the operator had before M282 (θ₀), which the controller no longer
//! shows. The module keeps θ₀ and an "alignment active" flag in two numbered parameters.
//! LinuxCNC keeps a numbered parameter (#31–#5000) across restarts only when the var file
//! already lists it, so the install guide and the tests' var file list
//! [`PERSISTENT_PARAMS`].

use vision_math::linuxcnc::LinuxCncAlignment;
use vision_math::{bounds, AlignmentChain, MathError, Point2, Vector2};

use super::{Applied, AppliedBy, Controller, HowApplied, ScaleLeftOut, WorkRotation};
use crate::command::MachineCommand;
use crate::error::VisionError;
use crate::machine::{checked, Machine, MachineError};

/// LinuxCNC 2.9. Its tool table holds the offset LinuxCNC *adds* to a programmed point
/// (`machine = g5x + R·(p + g92) + tool`), the negative of the module's. A remap only queues
/// G-code, and a capture waits for the machine first (`yield INTERP_EXECUTE_FINISH`), so the
/// bridge runs M281 stepwise when it re-centres ([`crate::VisionModule::m281_begin`]: the
/// handler yields again after each move) and M283 stepwise
/// ([`crate::VisionModule::m283_begin`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct LinuxCnc;

impl Controller for LinuxCnc {
    fn name(&self) -> &'static str {
        "linuxcnc"
    }

    fn title(&self) -> &'static str {
        "LinuxCNC"
    }

    /// M283's sheet is `Pn` on LinuxCNC, the manual's `Cn`: C is an axis word, which the task
    /// refuses ("Bad character 'c' used") on a machine without a C axis before any remap runs,
    /// and moves on a machine with one. `C` that reaches here (rs274, a C-axis machine) is
    /// refused naming `P`; `P` that is no sheet number, or `P` with `Q`, in LinuxCNC's words.
    fn manual_words(&self, m: u32, words: &[(char, f64)]) -> Result<Vec<(char, f64)>, VisionError> {
        if m != 283 {
            return Ok(words.to_vec());
        }
        let refuse = |message: String| Err(VisionError::DialectWord { message });
        let find = |letter: char| words.iter().find(|(l, _)| l.eq_ignore_ascii_case(&letter)).map(|(_, v)| *v);
        if let Some(c) = find('C') {
            return refuse(format!(
                "M283 C{c}: on LinuxCNC the sheet number is P: write M283 P{c} (C is an axis word)"
            ));
        }
        let Some(p) = find('P') else { return Ok(words.to_vec()) };
        if find('Q').is_some() {
            return refuse("M283 takes one of Qd (quick, dot diameter d) or Pn (sheet n), not both".to_string());
        }
        if !(p >= 1.0 && p.fract() == 0.0) {
            return refuse(format!("M283 P{p} is invalid: P is a calibration sheet number (P1)"));
        }
        Ok(words.iter().map(|&(l, v)| if l.eq_ignore_ascii_case(&'P') { ('C', v) } else { (l, v) }).collect())
    }

    fn sheet_calibration(&self) -> &'static str {
        "M283 P1"
    }

    fn dialect(&self) -> &'static str {
        "linuxcnc"
    }

    fn tool_table_sign(&self) -> f64 {
        -1.0
    }

    /// Runs [`cancel_commands`] of θ₀, then clears the flag. When a command is refused the flag
    /// stays set, so the next M280 restores θ₀ again.
    fn cancel_alignment(&self, machine: &mut dyn Machine) -> Result<Vec<String>, VisionError> {
        let lines = machine.run(&cancel_commands(self.base_rotation(machine)?)?)?;
        machine.set_pound(ALIGNMENT_ACTIVE_PARAM, 0.0)?;
        Ok(lines)
    }

    /// LinuxCNC's own refusal comes before the quality gates: a scale beyond the gate
    /// (`VisionFitMaxScaleDev`) cannot be applied ("LinuxCNC cannot scale: …").
    fn check_fit(&self, full: &AlignmentChain, max_scale_dev_pct: f64) -> Result<(), VisionError> {
        LinuxCncAlignment::from_chain(full, 0.0, max_scale_dev_pct)?;
        Ok(())
    }

    /// Stores θ₀ and sets the flag first (so that an M280 after a refused line still restores
    /// θ₀), then runs [`alignment_commands`]; the scale is left out and reported.
    fn apply_alignment(&self, machine: &mut dyn Machine, chain: &AlignmentChain) -> Result<Applied, VisionError> {
        let alignment = LinuxCncAlignment::from_chain(chain, self.base_rotation(machine)?, 0.0)?;
        let commands = alignment_commands(&alignment)?;
        machine.set_pound(BASE_ROTATION_PARAM, alignment.base_rotation_deg)?;
        machine.set_pound(ALIGNMENT_ACTIVE_PARAM, 1.0)?;
        let gcode = machine.run(&commands)?;
        let how = HowApplied {
            controller: self.name(),
            by: AppliedBy::Machine,
            scale_left_out: Some(ScaleLeftOut { scale: alignment.ignored_scale, reason: CANNOT_SCALE }),
            work_rotation: Some(WorkRotation {
                rotation_deg: alignment.rotation_deg,
                base_rotation_deg: alignment.base_rotation_deg,
                shift: alignment.g52,
            }),
        };
        Ok(Applied { gcode, chain: chain.rigid(), how })
    }

    /// Read whole from the machine (the flag and θ₀ in persistent parameters, the G5x rotation
    /// and the G92/G52 offset): it survives restarts and sessions, so `remembered` is not used.
    fn active_alignment(
        &self,
        machine: &dyn Machine,
        _remembered: Option<AlignmentChain>,
    ) -> Result<Option<AlignmentChain>, MachineError> {
        Ok(active_chain(
            machine.pound(ALIGNMENT_ACTIVE_PARAM)?,
            checked::rotation_deg(BASE_ROTATION_WHAT, machine.pound(BASE_ROTATION_PARAM)?)?,
            checked::rotation_deg(G5X_ROTATION_WHAT, machine.xy_rotation_deg()?)?,
            checked::offset("the G92/G52 offset", machine.g92_offset()?)?,
        ))
    }

    /// The stored θ₀ while an alignment is active (also after a restart), else the G5x
    /// rotation now.
    fn base_rotation(&self, machine: &dyn Machine) -> Result<f64, MachineError> {
        if flag_set(machine.pound(ALIGNMENT_ACTIVE_PARAM)?) {
            checked::rotation_deg(BASE_ROTATION_WHAT, machine.pound(BASE_ROTATION_PARAM)?)
        } else {
            checked::rotation_deg(G5X_ROTATION_WHAT, machine.xy_rotation_deg()?)
        }
    }
}

/// Why the scale is left out, in the operator's words.
const CANNOT_SCALE: &str = "LinuxCNC cannot scale";

/// The commands that make `alignment` the one active: the G5x rotation, then the shift under
/// it; both replace what an earlier M282 set, so a second M282 never compounds.
///
/// # Errors
/// [`MathError::NonFinite`] or [`MathError::BeyondBound`] ([`LinuxCncAlignment::check`]).
pub fn alignment_commands(alignment: &LinuxCncAlignment) -> Result<[MachineCommand; 2], MathError> {
    alignment.check()?;
    Ok([MachineCommand::SetWorkRotation { deg: alignment.rotation_deg }, MachineCommand::SetShift(alignment.g52)])
}

/// The commands that cancel an alignment (M280, an abort): clear the shift and put the G5x
/// rotation back to `base_rotation_deg` (θ₀, degrees counter-clockwise).
///
/// # Errors
/// [`MathError::NonFinite`] or [`MathError::BeyondBound`] for a θ₀ past
/// [`bounds::MAX_ROTATION_DEG`].
pub fn cancel_commands(base_rotation_deg: f64) -> Result<[MachineCommand; 2], MathError> {
    let deg = bounds::rotation_deg("the G5x rotation before the alignment", base_rotation_deg)?;
    Ok([MachineCommand::ClearShift, MachineCommand::SetWorkRotation { deg }])
}

/// What a θ₀ read from [`BASE_ROTATION_PARAM`] is called in a message.
const BASE_ROTATION_WHAT: &str = "#3991 (the G5x rotation before the alignment)";
/// What the G5x rotation read is called in a message.
const G5X_ROTATION_WHAT: &str = "the G5x rotation";

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cancel_restores_the_base_rotation_and_refuses_a_far_one() {
        let want = [MachineCommand::ClearShift, MachineCommand::SetWorkRotation { deg: -12.25 }];
        assert_eq!(cancel_commands(-12.25), Ok(want));
        for far in [f64::NAN, 1e308, -2e6] {
            assert!(cancel_commands(far).is_err(), "{far}");
        }
    }

    #[test]
    fn active_chain_reads_the_flag_and_rotates_the_g92_shift() {
        assert!(active_chain(0.0, 10.0, 12.0, Vector2::new(1.0, 0.0)).is_none());
        let chain = active_chain(1.0, 10.0, 100.0, Vector2::new(1.0, 0.0)).expect("flag set");
        // θ = 90°: (1, 0) + g92 = (2, 0) → (0, 2).
        let p = chain.apply(Point2::new(1.0, 0.0));
        assert!((p - Point2::new(0.0, 2.0)).norm() < 1e-12, "{p}");
    }
}
