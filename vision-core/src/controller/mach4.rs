//! Mach4, the manual's controller.

use vision_math::AlignmentChain;

use super::{modal, Applied, Controller};
use crate::error::VisionError;
use crate::machine::{Machine, MachineError};

/// Mach4: M282 aligns with `G51` scale, `G68` rotation about a centre and a `G52` shift; M280
/// cancels with `G69 G50 G52 X0 Y0`. Mach4 does not report the chain it has active, so the
/// module remembers its own M282's. The tool table holds the offset as the module does, and
/// `GcodeExecuteWait` returns after motion, so M281 may re-centre.
#[derive(Debug, Clone, Copy, Default)]
pub struct Mach4;

impl Controller for Mach4 {
    fn name(&self) -> &'static str {
        "mach4"
    }

    fn dialect(&self) -> &'static str {
        "mach4"
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
