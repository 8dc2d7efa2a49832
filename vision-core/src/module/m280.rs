//! M280: begin an alignment run.

use super::{Reply, Run, VisionModule};
use crate::error::VisionError;
use crate::machine::Machine;
use crate::pound::PoundBlock;

/// The fit an alignment run solves at M282.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RunMode {
    /// `P4` or omitted: rectangle fit (shift, rotation, X and Y scale); needs 4 marks.
    #[default]
    Rectangle,
    /// `P3`: similarity fit (shift, rotation, one uniform scale); needs 3 marks.
    Similarity,
}

impl RunMode {
    /// The manual's code (`VisionRun_Mode`): 4 rectangle, 3 similarity.
    #[must_use]
    pub fn code(self) -> i64 {
        match self {
            RunMode::Rectangle => 4,
            RunMode::Similarity => 3,
        }
    }

    /// Marks the fit needs: 4 rectangle, 3 similarity.
    #[must_use]
    pub fn min_marks(self) -> usize {
        match self {
            RunMode::Rectangle => 4,
            RunMode::Similarity => 3,
        }
    }

    /// The fit's name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            RunMode::Rectangle => "rectangle",
            RunMode::Similarity => "similarity",
        }
    }
}

impl VisionModule {
    /// **M280**: begins an alignment run in `mode`.
    ///
    /// Validates the pound-variable base, cancels any earlier alignment as the machine's
    /// controller does ([`crate::Controller::cancel_alignment`]: `G69 G50 G52 X0 Y0` on Mach4;
    /// `G52 X0 Y0` and `G10 L2 P0 R{θ₀}` on LinuxCNC), then opens a fresh [`Run`] (empty dot list) and writes
    /// `Run_Active` = 1, `Run_Mode`, `Run_DotCount` = 0. Needs no camera and no calibration.
    ///
    /// # Errors
    /// [`VisionError::NotEnabled`], [`VisionError::WrongTool`],
    /// [`VisionError::PoundBaseReserved`], [`VisionError::PoundBlockMissing`], or the machine's
    /// refusal of the cancel line ([`VisionError::Machine`]); the run is unchanged.
    pub fn m280(&mut self, machine: &mut dyn Machine, mode: RunMode) -> Result<Reply<RunMode>, VisionError> {
        self.check_enabled()?;
        self.check_tool(machine)?;
        self.check_calibration_record(machine)?;
        PoundBlock::on_machine(self.params.pound_var_base(), machine)?;
        let gcode = machine.controller().cancel_alignment(machine)?;
        self.alignment = None;
        self.run = Run { mode, active: true, dots: Vec::new(), scale: vision_math::ScaleEvidence::default() };
        self.publish_run();
        Ok(Reply { gcode, report: mode })
    }

    /// True between M280 and a successful M282.
    #[must_use]
    pub fn run_active(&self) -> bool {
        self.run.active
    }
}
