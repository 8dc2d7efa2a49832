//! [`Session`]: one Vision module kept alive between a controller's M-code calls.

use std::cell::RefCell;
use std::path::Path;

use vision_core::{DriverRegistry, Machine, MachineError, ProfileStore, Timestamp, VisionModule};
use vision_math::{AlignmentChain, LengthUnit, Point2, Vector2};
use vision_mcode::{McodeError, Outcome, VisionCall};

use crate::error::HostError;
use crate::host::Host;

/// The camera drivers a real machine can pick by `VisionDriver` (the simulator is not one).
#[must_use]
pub fn registry() -> DriverRegistry {
    let mut registry = DriverRegistry::new();
    vision_driver_keyence::register(&mut registry);
    registry
}

/// The Vision module of one controller, between M-code calls: parameters, the run's dot list,
/// the camera connection, the profile it saves to, and the alignment its last M282 left active.
pub struct Session {
    module: VisionModule,
    /// The G51/G68/G52 chain this session's M282 made active (`None` after M280).
    alignment: Option<AlignmentChain>,
}

impl std::fmt::Debug for Session {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Session").field("module", &self.module).field("alignment", &self.alignment).finish()
    }
}

impl Session {
    /// A session around `module` (its driver and profile already set), no alignment active.
    #[must_use]
    pub fn new(module: VisionModule) -> Session {
        Session { module, alignment: None }
    }

    /// The session of the profile file `profile` (TOML; a missing file starts a fresh,
    /// disabled profile), with the driver `VisionDriver` names from `registry`. M283 and M284
    /// save back to the same file.
    ///
    /// # Errors
    /// [`HostError::Setup`] when the profile cannot be read or the driver cannot be created.
    pub fn open(profile: &Path, registry: &DriverRegistry) -> Result<Session, HostError> {
        let setup = |e: vision_core::VisionError| HostError::Setup { message: format!("{}: {e}", profile.display()) };
        let store = ProfileStore::new(profile);
        let params = store.load_or_default().map_err(setup)?;
        let module = VisionModule::from_registry(params, registry).map_err(setup)?.with_profile(store);
        Ok(Session::new(module))
    }

    /// The Vision module (parameters, dot list, driver).
    #[must_use]
    pub fn module(&self) -> &VisionModule {
        &self.module
    }

    /// The alignment this session's last M282 made active (`None` after M280 or before any).
    #[must_use]
    pub fn alignment(&self) -> Option<&AlignmentChain> {
        self.alignment.as_ref()
    }

    /// Runs Vision M-code `m` (280–284) with the words of its line on `host` (the module runs
    /// the G-code it emits on the host as it goes) and tells the operator what happened.
    ///
    /// # Errors
    /// [`HostError::Mcode`] (a bad word or the module's refusal, in the manual's words) or the
    /// controller's [`HostError::Host`]. A refusal changes nothing; a controller failure during
    /// the call is reported even when the module itself succeeded.
    pub fn mcode(&mut self, host: &mut dyn Host, m: u32, words: &[(char, f64)]) -> Result<Outcome, HostError> {
        let call = VisionCall::parse(m, words)?;
        if host.alignment_active()? == Some(false) {
            self.alignment = None;
        }
        let mut machine = HostMachine { host, alignment: self.alignment, failure: RefCell::new(None) };
        let result = call.run(&mut self.module, &mut machine);
        if let Some(failure) = machine.failure.into_inner() {
            return Err(failure);
        }
        let outcome = result.map_err(McodeError::from)?;
        self.track(&outcome);
        host.message(&summary(&outcome));
        Ok(outcome)
    }

    /// Tracks the alignment `outcome` leaves active. The module already ran its G-code on the
    /// host, through [`HostMachine::run_gcode`]: the one path by which it reaches a controller
    /// (where a host dialect of M282's output will translate it).
    fn track(&mut self, outcome: &Outcome) {
        match outcome {
            Outcome::Begin(_) => self.alignment = None,
            Outcome::Apply(reply) => self.alignment = Some(reply.report.chain),
            _ => {}
        }
    }
}

/// The operator's status line after a successful call, with the call's warning (a mark outside
/// the image, a height change, …) when it has one.
fn summary(outcome: &Outcome) -> String {
    let (done, warning) = match outcome {
        Outcome::Begin(_) => ("M280: Vision run started", None),
        Outcome::Capture(r) => ("M281: mark captured", r.report.warning.as_deref()),
        Outcome::Apply(_) => ("M282: alignment applied", None),
        Outcome::Calibrate(r) => ("M283: calibration done and saved", r.report.warning()),
        Outcome::SelectJob(_) => ("M284: camera job selected", None),
    };
    warning.map_or_else(|| done.to_string(), |w| format!("{done} (warning: {w})"))
}

/// [`vision_core::Machine`] over a [`Host`]. The trait's reads cannot fail, so a controller
/// failure on one is kept and reported after the call, in place of the module's result.
struct HostMachine<'h> {
    host: &'h mut dyn Host,
    alignment: Option<AlignmentChain>,
    failure: RefCell<Option<HostError>>,
}

impl HostMachine<'_> {
    /// `value`, or `fallback` with the first failure kept.
    fn keep<T>(&self, value: Result<T, HostError>, fallback: T) -> T {
        value.unwrap_or_else(|e| {
            self.failure.borrow_mut().get_or_insert(e);
            fallback
        })
    }
}

fn machine_error(e: HostError) -> MachineError {
    MachineError::new(e.to_string())
}

impl Machine for HostMachine<'_> {
    fn program_position(&self) -> Point2<f64> {
        self.keep(self.host.position(), Point2::origin())
    }

    fn active_alignment(&self) -> Option<AlignmentChain> {
        self.alignment
    }

    fn run_gcode(&mut self, lines: &[String]) -> Result<(), MachineError> {
        lines.iter().try_for_each(|line| self.host.execute(line)).map_err(machine_error)
    }

    fn active_tool(&self) -> u32 {
        self.keep(self.host.active_tool(), 0)
    }

    fn tool_offset(&self, tool: u32) -> Result<Vector2<f64>, MachineError> {
        self.host.tool_offset(tool).map_err(machine_error)
    }

    fn set_tool_offset(&mut self, tool: u32, offset: Vector2<f64>) -> Result<(), MachineError> {
        self.host.set_tool_offset(tool, offset).map_err(machine_error)
    }

    fn units(&self) -> LengthUnit {
        self.keep(self.host.units(), LengthUnit::Inch)
    }

    fn pound(&self, index: u32) -> Result<f64, MachineError> {
        self.host.pound(index).map_err(machine_error)
    }

    fn set_pound(&mut self, index: u32, value: f64) -> Result<(), MachineError> {
        self.host.set_pound(index, value).map_err(machine_error)
    }

    fn dwell(&mut self, seconds: f64) {
        let done = self.host.dwell(seconds);
        self.keep(done, ());
    }

    fn now(&self) -> Timestamp {
        self.host.now()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vision_core::{Capture, Judgment, Reply};

    #[test]
    fn the_status_line_carries_the_calls_warning() {
        let capture = |warning: Option<&str>| {
            Outcome::Capture(Reply {
                gcode: Vec::new(),
                report: Capture {
                    unit: LengthUnit::Inch,
                    commanded: Point2::origin(),
                    observed: Point2::origin(),
                    offset: Vector2::zeros(),
                    centred_px: Vector2::zeros(),
                    width: 0.25,
                    height: 0.25,
                    angle_deg: 0.0,
                    score: 0.99,
                    judgment: Judgment::Ok,
                    dot_index: None,
                    slot: None,
                    image: None,
                    warning: warning.map(str::to_string),
                    recentred: None,
                },
            })
        };
        assert_eq!(summary(&capture(None)), "M281: mark captured");
        assert_eq!(
            summary(&capture(Some("the mark was reported at pixel (1900.0, 10.0)"))),
            "M281: mark captured (warning: the mark was reported at pixel (1900.0, 10.0))"
        );
    }
}
