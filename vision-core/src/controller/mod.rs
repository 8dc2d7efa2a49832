//! The controller a machine is: every rule that differs between Mach4, LinuxCNC and seed 002's
//! MachineMotion interface, behind one trait, one file per controller (SPEC §9, §10).
//!
//! A [`crate::Machine`] says which controller it is ([`crate::Machine::controller`]); the
//! Vision module asks the controller, never "is this LinuxCNC?". The rules:
//! how an alignment is applied ([`Controller::apply_alignment`]) and cancelled
//! ([`Controller::cancel_alignment`]), whether a fit can be applied at all (scale,
//! [`Controller::check_fit`]), where the alignment's state lives
//! ([`Controller::active_alignment`]), the G5x rotation under it ([`Controller::base_rotation`]),
//! the tool table's sign ([`Controller::tool_table_sign`]) and the G-code dialect its
//! interpreter follows ([`Controller::dialect`]).
//!
//! Adding a controller: one file here implementing [`Controller`], one line in
//! [`CONTROLLERS`], and its bridge crate implementing [`crate::Machine`] (see
//! `docs/add-a-controller.md`).

mod grbl;
pub mod linuxcnc;
mod mach4;
mod machinemotion;

use std::fmt;

use vision_math::{AlignmentChain, MathError, Matrix2, Vector2};

use crate::command::MachineCommand;
use crate::error::VisionError;
use crate::machine::{checked, Machine, MachineError};

pub use grbl::Grbl;
pub use linuxcnc::LinuxCnc;
pub use mach4::Mach4;
pub use machinemotion::MachineMotion;

/// What an alignment became on the machine ([`Controller::apply_alignment`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Applied {
    /// The lines run, in order.
    pub gcode: Vec<String>,
    /// The chain applied (program frame → work frame, current units): the fit's, or its rigid
    /// part where the controller cannot scale.
    pub chain: AlignmentChain,
    /// How it was applied, in terms every controller fills.
    pub how: HowApplied,
}

/// How an alignment was applied: who applies it, the scale left out, and the work-offset
/// rotation where a controller rotates its work offset instead of a rotation modal.
///
/// Serialized (inside M282's report) as nothing, or, for a controller that rotates its work
/// offset, one entry named after the controller: `{ rotation_deg, g52, base_rotation_deg,
/// ignored_scale }`; `"applied_by": "host"` where the host applies it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HowApplied {
    /// The controller's name ([`Controller::name`]).
    pub controller: &'static str,
    /// Who maps the program's points.
    pub by: AppliedBy,
    /// The fit's scale that was not applied, on a controller that cannot scale (`(1, 1)` when
    /// the fit had none); `None` where the scale is applied.
    pub scale_left_out: Option<ScaleLeftOut>,
    /// The rotation put in the work offset and the shift under it, on a controller that
    /// rotates its work offset; `None` where the rotation is a modal of its own.
    pub work_rotation: Option<WorkRotation>,
}

impl HowApplied {
    /// Applied on the machine with its own modals: nothing left out, no work-offset rotation.
    #[must_use]
    pub fn modal(controller: &'static str) -> HowApplied {
        HowApplied { controller, by: AppliedBy::Machine, scale_left_out: None, work_rotation: None }
    }
}

/// Who maps the program's points through the alignment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AppliedBy {
    /// The controller, with the commands the module ran (Mach4, LinuxCNC, MachineMotion).
    Machine,
    /// The host, rewriting the program's points before the controller sees them (a controller
    /// with no alignment modal and no work-offset rotation, such as Grbl's).
    Host,
}

/// A scale a controller could not apply.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScaleLeftOut {
    /// The per-axis factors left out (dimensionless).
    pub scale: Vector2<f64>,
    /// Why, in the operator's words (`LinuxCNC cannot scale`).
    pub reason: &'static str,
}

impl ScaleLeftOut {
    /// Largest deviation of the scale left out from 1, percent (0 when there was none).
    #[must_use]
    pub fn dev_pct(&self) -> f64 {
        (self.scale.x - 1.0).abs().max((self.scale.y - 1.0).abs()) * 100.0
    }

    /// True when a factor differs from 1 (the fit had a scale, and it was left out).
    #[must_use]
    pub fn is_scaled(&self) -> bool {
        self.scale != Vector2::new(1.0, 1.0)
    }
}

/// The alignment as a rotation of the active work offset about its origin and a shift under it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorkRotation {
    /// The work offset's rotation after the alignment, degrees counter-clockwise: the base
    /// rotation plus the fit's.
    pub rotation_deg: f64,
    /// The work offset's rotation before the alignment, degrees counter-clockwise; the cancel
    /// restores it.
    pub base_rotation_deg: f64,
    /// The local shift, current units, in the rotated frame.
    pub shift: Vector2<f64>,
}

/// The rules of one controller. Implementations are unit structs listed in [`CONTROLLERS`].
pub trait Controller: fmt::Debug + Send + Sync {
    /// Its name on the command line and in world files: `mach4`, `linuxcnc`, `machinemotion`.
    fn name(&self) -> &'static str;

    /// Its name in messages to the operator: `Mach4`, `LinuxCNC`, `MachineMotion`.
    fn title(&self) -> &'static str;

    /// The name of the G-code dialect its interpreter follows (`vision_gcode::Dialect::name`);
    /// the simulator maps it to the interpreter's dialect in one place.
    fn dialect(&self) -> &'static str;

    /// The tool table's sign against the Vision module's tool offset (where the tool's point
    /// lies from the spindle: commanding P puts the spindle at P − offset): 1 where the table
    /// holds exactly that, −1 where the controller *adds* the table value to a programmed point
    /// (LinuxCNC).
    fn tool_table_sign(&self) -> f64;

    /// M280: cancels any alignment on `machine` (the commands it needs); returns the lines run.
    ///
    /// # Errors
    /// The machine's refusal ([`VisionError::Machine`]).
    fn cancel_alignment(&self, machine: &mut dyn Machine) -> Result<Vec<String>, VisionError>;

    /// M282, before the quality gates: refuses a fit (`full`, the run's whole fit) the
    /// controller cannot apply; `max_scale_dev_pct` is the scale gate (percent, 0 = off).
    ///
    /// # Errors
    /// Why it cannot be applied, in the operator's words.
    fn check_fit(&self, full: &AlignmentChain, max_scale_dev_pct: f64) -> Result<(), VisionError>;

    /// M282: makes `chain` the active alignment on `machine`, with the commands this
    /// controller needs.
    ///
    /// # Errors
    /// The machine's refusal; the lines before the refused one have run.
    fn apply_alignment(&self, machine: &mut dyn Machine, chain: &AlignmentChain) -> Result<Applied, VisionError>;

    /// The alignment active on `machine`, given the one this module's last M282 applied
    /// (`remembered`; `None` after M280): read from the machine where it keeps it, else
    /// `remembered` unless the machine says none is active.
    ///
    /// # Errors
    /// The machine's refusal of a read.
    fn active_alignment(
        &self,
        machine: &dyn Machine,
        remembered: Option<AlignmentChain>,
    ) -> Result<Option<AlignmentChain>, MachineError>;

    /// θ₀: the G5x rotation the program frame has without the alignment, degrees
    /// counter-clockwise. The camera's K and its tool offset are measured along the machine
    /// axes and turned by it into the program frame.
    ///
    /// # Errors
    /// The machine's refusal of a read.
    fn base_rotation(&self, machine: &dyn Machine) -> Result<f64, MachineError>;

    /// How an operator calls the manual's sheet calibration on this controller, for advice in
    /// messages: `M283 C1`, or what [`Controller::manual_words`] takes instead of `C`.
    fn sheet_calibration(&self) -> &'static str {
        MANUAL_SHEET_CALIBRATION
    }

    /// Vision M-code `m`'s words as the manual writes them, from the words of its line in this
    /// controller's dialect (letters in either case). The default takes them as they are.
    ///
    /// # Errors
    /// [`VisionError::DialectWord`]: a word this controller writes otherwise, with the
    /// replacement.
    fn manual_words(&self, m: u32, words: &[(char, f64)]) -> Result<Vec<(char, f64)>, VisionError> {
        let _ = m;
        Ok(words.to_vec())
    }
}

/// The manual's sheet calibration call, [`Controller::sheet_calibration`] unless a controller
/// calls it otherwise.
pub const MANUAL_SHEET_CALIBRATION: &str = "M283 C1";

/// The sheet calibration as every controller calls it, for advice given where the machine's
/// controller is not known: the manual's call, then `on {title} {call}` for each controller
/// that calls it otherwise (`M283 C1, on LinuxCNC M283 P1`).
#[must_use]
pub fn sheet_calibrations() -> String {
    let mut advice = MANUAL_SHEET_CALIBRATION.to_string();
    for c in CONTROLLERS.iter().filter(|c| c.sheet_calibration() != MANUAL_SHEET_CALIBRATION) {
        advice.push_str(&format!(", on {} {}", c.title(), c.sheet_calibration()));
    }
    advice
}

/// Every controller, by [`Controller::name`].
pub static CONTROLLERS: [&dyn Controller; 4] = [&Mach4, &LinuxCnc, &MachineMotion, &Grbl];

/// The controller named `name` (case-insensitive).
///
/// # Errors
/// [`VisionError::UnknownController`] listing the known names.
pub fn by_name(name: &str) -> Result<&'static dyn Controller, VisionError> {
    CONTROLLERS
        .iter()
        .copied()
        .find(|c| c.name().eq_ignore_ascii_case(name))
        .ok_or_else(|| VisionError::UnknownController { name: name.to_string(), known: names().join(", ") })
}

/// The known controllers' names, in [`CONTROLLERS`] order.
#[must_use]
pub fn names() -> Vec<&'static str> {
    CONTROLLERS.iter().map(|c| c.name()).collect()
}

/// The Vision module's offset of `tool` (where its point lies from the spindle, current units),
/// from `machine`'s table and its controller's sign.
pub(crate) fn tool_offset(machine: &dyn Machine, tool: u32) -> Result<Vector2<f64>, MachineError> {
    Ok(machine.controller().tool_table_sign()
        * checked::offset("the tool table's X/Y offset", machine.tool_offset(tool)?)?)
}

/// Writes the Vision module's offset `offset` of `tool` into `machine`'s table, with its
/// controller's sign.
pub(crate) fn set_tool_offset(machine: &mut dyn Machine, tool: u32, offset: Vector2<f64>) -> Result<(), MachineError> {
    let table = machine.controller().tool_table_sign() * offset;
    machine.set_tool_offset(tool, table)
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

/// Implements [`Controller`] for `$controller`, a controller whose alignment is the G68/G51/G52
/// modals (Mach4, seed 002): cancelled with [`MachineCommand::CancelAlignment`], applied with
/// [`modal_commands`] and remembered by the module; a tool table that holds the module's offset; moves that
/// finish before the next line, so M281 may re-centre; no G5x rotation under the alignment.
macro_rules! modal_controller {
    ($controller:ty, name = $name:literal, title = $title:literal, dialect = $dialect:literal) => {
        impl $crate::controller::Controller for $controller {
            fn name(&self) -> &'static str {
                $name
            }

            fn title(&self) -> &'static str {
                $title
            }

            fn dialect(&self) -> &'static str {
                $dialect
            }

            fn tool_table_sign(&self) -> f64 {
                1.0
            }

            fn cancel_alignment(&self, machine: &mut dyn $crate::Machine) -> Result<Vec<String>, $crate::VisionError> {
                $crate::controller::modal::cancel(machine)
            }

            fn check_fit(
                &self,
                _full: &vision_math::AlignmentChain,
                _max_scale_dev_pct: f64,
            ) -> Result<(), $crate::VisionError> {
                Ok(())
            }

            fn apply_alignment(
                &self,
                machine: &mut dyn $crate::Machine,
                chain: &vision_math::AlignmentChain,
            ) -> Result<$crate::controller::Applied, $crate::VisionError> {
                $crate::controller::modal::apply(machine, chain)
            }

            fn active_alignment(
                &self,
                machine: &dyn $crate::Machine,
                remembered: Option<vision_math::AlignmentChain>,
            ) -> Result<Option<vision_math::AlignmentChain>, $crate::MachineError> {
                $crate::controller::modal::active(machine, remembered)
            }

            fn base_rotation(&self, _machine: &dyn $crate::Machine) -> Result<f64, $crate::MachineError> {
                Ok(0.0)
            }
        }
    };
}
use modal_controller;

/// The commands that make `chain` the alignment on a controller with scale, rotation and shift
/// modals: cancel, then shift, rotation about the centre and scale, each replacing the one
/// before, so a second M282 never compounds.
///
/// # Errors
/// [`MathError::NonFinite`] or [`MathError::BeyondBound`] for a chain no controller can be
/// handed ([`AlignmentChain::check`]).
pub fn modal_commands(chain: &AlignmentChain) -> Result<[MachineCommand; 4], MathError> {
    chain.check()?;
    Ok([
        MachineCommand::CancelAlignment,
        MachineCommand::SetShift(chain.shift),
        MachineCommand::SetRotation { centre: chain.center, deg: chain.rotation_deg },
        MachineCommand::SetScale(chain.scale),
    ])
}

/// The alignment of a controller with scale, rotation and shift modals: cancelled with
/// [`MachineCommand::CancelAlignment`], applied with [`modal_commands`], state kept by the
/// module.
mod modal {
    use super::{modal_commands, Applied, HowApplied};
    use crate::command::MachineCommand;
    use crate::error::VisionError;
    use crate::machine::{Machine, MachineError};
    use vision_math::AlignmentChain;

    pub(super) fn cancel(machine: &mut dyn Machine) -> Result<Vec<String>, VisionError> {
        Ok(machine.run(&[MachineCommand::CancelAlignment])?)
    }

    pub(super) fn apply(machine: &mut dyn Machine, chain: &AlignmentChain) -> Result<Applied, VisionError> {
        let gcode = machine.run(&modal_commands(chain)?)?;
        Ok(Applied { gcode, chain: *chain, how: HowApplied::modal(machine.controller().name()) })
    }

    /// The remembered chain, unless the machine says no alignment is active.
    pub(super) fn active(
        machine: &dyn Machine,
        remembered: Option<AlignmentChain>,
    ) -> Result<Option<AlignmentChain>, MachineError> {
        Ok(if machine.alignment_active()? == Some(false) { None } else { remembered })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_controller_is_found_by_its_name_and_names_are_unique() {
        for c in CONTROLLERS {
            assert_eq!(by_name(&c.name().to_uppercase()).map(Controller::name), Ok(c.name()));
        }
        let mut names = names();
        names.dedup();
        assert_eq!(names.len(), CONTROLLERS.len());
        let e = by_name("fanuc").unwrap_err();
        assert_eq!(
            e.to_string(),
            "unknown controller 'fanuc' — known controllers: mach4, linuxcnc, machinemotion, grbl"
        );
    }

    #[test]
    fn every_controller_takes_the_sheet_calibration_its_advice_names() {
        for c in CONTROLLERS {
            let call = c.sheet_calibration();
            let word = call.strip_prefix("M283 ").expect("an M283 call");
            let (letter, value) = word.split_at(1);
            let words = [(letter.chars().next().expect("a letter"), value.parse::<f64>().expect("a number"))];
            assert_eq!(c.manual_words(283, &words).expect(call), vec![('C', 1.0)], "{}", c.name());
        }
    }

    #[test]
    fn advice_names_every_controllers_sheet_calibration() {
        assert_eq!(sheet_calibrations(), "M283 C1, on LinuxCNC M283 P1");
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
