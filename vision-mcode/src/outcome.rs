//! Running a [`VisionCall`] on the Vision module.

use vision_core::{AlignReport, CalReport, Capture, JobReport, Machine, Reply, RunMode, VisionError, VisionModule};

use crate::call::VisionCall;

/// What a Vision M-code did: the module's reply (the G-code it ran, and the report).
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// M280.
    Begin(Reply<RunMode>),
    /// M281.
    Capture(Reply<Capture>),
    /// M282.
    Apply(Reply<AlignReport>),
    /// M283.
    Calibrate(Reply<CalReport>),
    /// M284.
    SelectJob(Reply<JobReport>),
}

impl Outcome {
    /// The G-code lines the module ran on the machine, in order (M280's cancel line, M282's
    /// four modal lines, M283's moves; empty for M281 and M284). Not to be run again.
    #[must_use]
    pub fn gcode(&self) -> &[String] {
        match self {
            Outcome::Begin(r) => &r.gcode,
            Outcome::Capture(r) => &r.gcode,
            Outcome::Apply(r) => &r.gcode,
            Outcome::Calibrate(r) => &r.gcode,
            Outcome::SelectJob(r) => &r.gcode,
        }
    }
}

impl VisionCall {
    /// Runs the call on `module` with `machine` as the host.
    ///
    /// # Errors
    /// The module's [`VisionError`]; see each of `VisionModule::m280` … `m284` for what is left
    /// unchanged.
    pub fn run(self, module: &mut VisionModule, machine: &mut dyn Machine) -> Result<Outcome, VisionError> {
        Ok(match self {
            VisionCall::Begin(mode) => Outcome::Begin(module.m280(machine, mode)?),
            VisionCall::Capture { keep_image } => Outcome::Capture(module.m281(machine, keep_image)?),
            VisionCall::Apply(pieces) => Outcome::Apply(module.m282(machine, pieces)?),
            VisionCall::Calibrate(mode) => Outcome::Calibrate(module.m283(machine, mode)?),
            VisionCall::SelectJob(job) => Outcome::SelectJob(module.m284(job)?),
        })
    }
}
