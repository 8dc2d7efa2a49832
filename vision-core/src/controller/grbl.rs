//! Grbl 1.1 (and the firmwares like it) behind mach-vision as the sender: no G68, G51 or G52
//! and no user M-codes on the firmware, so the program runs in the host's interpreter and the
//! host maps every move through M282's alignment ([`MachineCommand::AlignMoves`]). The host can
//! scale, so the whole chain is applied; only the scale gate refuses a scale.

use vision_math::AlignmentChain;

use super::{Applied, AppliedBy, Controller, HowApplied};
use crate::command::MachineCommand;
use crate::error::VisionError;
use crate::machine::{Machine, MachineError};

/// Grbl 1.1. The firmware has no tool table: the host keeps it, with the tool's point where it
/// lies from the spindle (as Mach4's), and applies its X/Y at M6, which never reaches the
/// firmware. The alignment lives in the host, remembered by the module.
#[derive(Debug, Clone, Copy, Default)]
pub struct Grbl;

impl Controller for Grbl {
    fn name(&self) -> &'static str {
        "grbl"
    }

    fn title(&self) -> &'static str {
        "Grbl"
    }

    fn dialect(&self) -> &'static str {
        "grbl"
    }

    fn tool_table_sign(&self) -> f64 {
        1.0
    }

    fn cancel_alignment(&self, machine: &mut dyn Machine) -> Result<Vec<String>, VisionError> {
        Ok(machine.run(&[MachineCommand::CancelMoveAlignment])?)
    }

    /// The host scales as exactly as it rotates: nothing is refused here (the quality gates,
    /// the scale gate among them, still apply).
    fn check_fit(&self, _full: &AlignmentChain, _max_scale_dev_pct: f64) -> Result<(), VisionError> {
        Ok(())
    }

    /// The whole chain, scale included, handed to the host in one command.
    fn apply_alignment(&self, machine: &mut dyn Machine, chain: &AlignmentChain) -> Result<Applied, VisionError> {
        chain.check()?;
        let gcode = machine.run(&[MachineCommand::AlignMoves(*chain)])?;
        let how =
            HowApplied { controller: self.name(), by: AppliedBy::Host, scale_left_out: None, work_rotation: None };
        Ok(Applied { gcode, chain: *chain, how })
    }

    /// The remembered chain, unless the machine says no alignment is active.
    fn active_alignment(
        &self,
        machine: &dyn Machine,
        remembered: Option<AlignmentChain>,
    ) -> Result<Option<AlignmentChain>, MachineError> {
        Ok(if machine.alignment_active()? == Some(false) { None } else { remembered })
    }

    /// Grbl's work systems have no rotation.
    fn base_rotation(&self, _machine: &dyn Machine) -> Result<f64, MachineError> {
        Ok(0.0)
    }
}
