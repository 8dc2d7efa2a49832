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

pub mod linuxcnc;
mod mach4;
mod machinemotion;

use std::fmt;

use vision_math::chain::CANCEL_LINE;
use vision_math::linuxcnc::LinuxCncAlignment;
use vision_math::{AlignmentChain, Matrix2, Vector2};

use crate::error::VisionError;
use crate::machine::{checked, Machine, MachineError};

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
    /// LinuxCNC's form of it (rotation of the G5x system, G52 shift, the scale left out).
    pub linuxcnc: Option<LinuxCncAlignment>,
}

/// The rules of one controller. Implementations are unit structs listed in [`CONTROLLERS`].
pub trait Controller: fmt::Debug + Send + Sync {
    /// Its name on the command line and in world files: `mach4`, `linuxcnc`, `machinemotion`.
    fn name(&self) -> &'static str;

    /// The name of the G-code dialect its interpreter follows (`vision_gcode::Dialect::name`);
    /// the simulator maps it to the interpreter's dialect in one place.
    fn dialect(&self) -> &'static str;

    /// The tool table's sign against the Vision module's tool offset (where the tool's point
    /// lies from the spindle: commanding P puts the spindle at P − offset): 1 where the table
    /// holds exactly that, −1 where the controller *adds* the table value to a programmed point
    /// (LinuxCNC).
    fn tool_table_sign(&self) -> f64;

    /// M280: cancels any alignment on `machine`; returns the lines run.
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

    /// M282: makes `chain` the active alignment on `machine`.
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
        "M283 C1"
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

/// Every controller, by [`Controller::name`].
pub static CONTROLLERS: [&dyn Controller; 3] = [&Mach4, &LinuxCnc, &MachineMotion];

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
/// modals (Mach4, seed 002): cancelled with `G69 G50 G52 X0 Y0`, applied as the chain's four
/// lines and remembered by the module; a tool table that holds the module's offset; moves that
/// finish before the next line, so M281 may re-centre; no G5x rotation under the alignment.
macro_rules! modal_controller {
    ($controller:ty, name = $name:literal, dialect = $dialect:literal) => {
        impl $crate::controller::Controller for $controller {
            fn name(&self) -> &'static str {
                $name
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

/// The alignment of a controller with G68/G51/G52 modals: cancelled with `G69 G50 G52 X0 Y0`,
/// applied as the chain's four lines, state kept by the module.
mod modal {
    use super::{Applied, CANCEL_LINE};
    use crate::error::VisionError;
    use crate::machine::{Machine, MachineError};
    use vision_math::AlignmentChain;

    pub(super) fn cancel(machine: &mut dyn Machine) -> Result<Vec<String>, VisionError> {
        let gcode = vec![CANCEL_LINE.to_string()];
        machine.run_gcode(&gcode)?;
        Ok(gcode)
    }

    pub(super) fn apply(machine: &mut dyn Machine, chain: &AlignmentChain) -> Result<Applied, VisionError> {
        let gcode = chain.gcode()?.to_vec();
        machine.run_gcode(&gcode)?;
        Ok(Applied { gcode, chain: *chain, linuxcnc: None })
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
        assert_eq!(e.to_string(), "unknown controller 'fanuc' — known controllers: mach4, linuxcnc, machinemotion");
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
    fn machine_axes_turn_into_the_program_frame_and_back() {
        let v = Vector2::new(1.0, 0.0);
        assert_eq!(machine_to_program(v, 0.0), v);
        let p = machine_to_program(v, 90.0);
        assert!((p - Vector2::new(0.0, -1.0)).norm() < 1e-12, "{p}");
        assert!((program_to_machine(p, 90.0) - v).norm() < 1e-12);
    }
}
