//! Seed 002's MachineMotion path interface.

use vision_math::AlignmentChain;

use super::{modal, Applied, Controller};
use crate::error::VisionError;
use crate::machine::{Machine, MachineError};

/// Seed 002's MachineMotion control, with the G-code the vision programs use on it (SPEC §6):
/// the alignment as on Mach4 (`G51`/`G68`/`G52` modals, cancelled by `G69 G50 G52 X0 Y0`,
/// remembered by the module), the tool table holding the module's offset, and moves that finish
/// before the next line, so M281 may re-centre. Its interpreter's rules differ from Mach4's
/// (`G92`, tool offsets from `M6`, nested comments).
#[derive(Debug, Clone, Copy, Default)]
pub struct MachineMotion;

impl Controller for MachineMotion {
    fn name(&self) -> &'static str {
        "machinemotion"
    }

    fn dialect(&self) -> &'static str {
        "machinemotion"
    }

    fn tool_table_sign(&self) -> f64 {
        1.0
    }

    fn may_recentre(&self) -> bool {
        true
    }

    fn cancel_alignment(&self, machine: &mut dyn Machine) -> Result<Vec<String>, VisionError> {
        modal::cancel(machine)
    }

    fn check_fit(&self, _full: &AlignmentChain, _max_scale_dev_pct: f64) -> Result<(), VisionError> {
        Ok(())
    }

    fn apply_alignment(&self, machine: &mut dyn Machine, chain: &AlignmentChain) -> Result<Applied, VisionError> {
        modal::apply(machine, chain)
    }

    fn active_alignment(
        &self,
        machine: &dyn Machine,
        remembered: Option<AlignmentChain>,
    ) -> Result<Option<AlignmentChain>, MachineError> {
        modal::active(machine, remembered)
    }

    fn base_rotation(&self, _machine: &dyn Machine) -> Result<f64, MachineError> {
        Ok(0.0)
    }
}
