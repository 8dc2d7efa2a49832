//! [`Session`]: one Vision module kept alive between a controller's M-code calls.

use std::cell::RefCell;
use std::path::Path;

use vision_core::{
    linuxcnc, Controller, DriverRegistry, Machine, MachineError, ProfileStore, StepwiseWalk, Timestamp, VisionError,
    VisionModule,
};
use vision_math::linuxcnc::LinuxCncAlignment;
use vision_math::{AlignmentChain, LengthUnit, Point2, Vector2};
use vision_mcode::{McodeError, Outcome, VisionCall};

use crate::error::HostError;
use crate::host::Host;

/// The camera drivers a real machine can pick by `VisionDriver` (the simulator is not one).
#[must_use]
pub fn registry() -> DriverRegistry {
    crate::cameras(None)
}

/// The Vision module of one controller, between M-code calls: parameters, the run's dot list,
/// the camera connection, the profile it saves to, and the alignment its last M282 left active.
pub struct Session {
    module: VisionModule,
    /// The G51/G68/G52 chain this session's M282 made active (`None` after M280); on LinuxCNC
    /// read from the host at every call.
    alignment: Option<AlignmentChain>,
    /// The stepwise M283 walk in progress ([`Session::walk_begin`]).
    walk: Option<StepwiseWalk>,
}

impl std::fmt::Debug for Session {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Session")
            .field("module", &self.module)
            .field("alignment", &self.alignment)
            .field("walk", &self.walk)
            .finish()
    }
}

impl Session {
    /// A session around `module` (its driver and profile already set), no alignment active.
    #[must_use]
    pub fn new(module: VisionModule) -> Session {
        Session { module, alignment: None, walk: None }
    }

    /// The session of the profile file `profile` (TOML; a missing file starts a fresh,
    /// disabled profile), with the driver `VisionDriver` names from `registry`. M283 and M284
    /// save back to the same file.
    ///
    /// # Errors
    /// [`HostError::Setup`] when the profile cannot be read or the driver cannot be created.
    pub fn open(profile: &Path, registry: &DriverRegistry) -> Result<Session, HostError> {
        let setup = |e: vision_core::VisionError| HostError::Setup { message: format!("{}: {e}", profile.display()) };
        let store = ProfileStore::new(profile).with_defaults(registry.params());
        let params = store.load_or_default().map_err(setup)?;
        let module = VisionModule::from_registry(params, registry).map_err(setup)?.with_profile(store);
        Ok(Session::new(module))
    }

    /// The Vision module (parameters, dot list, driver).
    #[must_use]
    pub fn module(&self) -> &VisionModule {
        &self.module
    }

    /// The alignment this session's last M282 made active (`None` after M280 or before any); on
    /// LinuxCNC the one the host reported at the last call (see [`Host::controller`]).
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
        let outcome = self.on_machine(host, |module, machine| call.run(module, machine))?;
        self.track(&outcome);
        host.message(&summary(&outcome));
        Ok(outcome)
    }

    /// Starts M283 stepwise, for a host whose M-code cannot both move and trigger (LinuxCNC's
    /// `m283.ngc`): M283's words (`Q` or `C`) and all of M283's checks, nothing moved. Then
    /// loop [`Session::walk_next`] → move there → [`Session::walk_capture`] until `walk_next`
    /// answers `None`, and finish with [`Session::walk_finish`]. A walk already in progress is
    /// dropped.
    ///
    /// # Errors
    /// A bad word or M283's refusal ([`HostError::Mcode`]), or the controller's
    /// [`HostError::Host`]; no walk is in progress then.
    pub fn walk_begin(&mut self, host: &mut dyn Host, words: &[(char, f64)]) -> Result<(), HostError> {
        self.walk = None;
        let VisionCall::Calibrate(mode) = VisionCall::parse(283, words)? else {
            // `parse(283, …)` answers only Calibrate; kept typed all the same.
            return Err(HostError::Mcode(McodeError::BadWord {
                mcode: "M283",
                word: String::new(),
                reason: "give exactly one of Qd or Cn".to_string(),
            }));
        };
        self.walk = Some(self.on_machine(host, |module, machine| module.m283_begin(machine, mode))?);
        Ok(())
    }

    /// The next point of the walk to move to (program frame, current units), or `None` when
    /// the walk has every capture it needs. It depends on the captures so far.
    ///
    /// # Errors
    /// No walk in progress, the walk failed on its captures (M283's message; the walk is
    /// dropped and nothing written), or the controller's [`HostError::Host`].
    pub fn walk_next(&mut self, host: &mut dyn Host) -> Result<Option<Point2<f64>>, HostError> {
        self.walk_step(host, |module, machine, walk| module.m283_next(machine, walk))
    }

    /// Triggers here, for the point [`Session::walk_next`] gave; call it once the machine has
    /// arrived there.
    ///
    /// # Errors
    /// No walk in progress or no capture pending; the camera's failure or an NG (M283's
    /// message: the walk is dropped, nothing written), or the controller's [`HostError::Host`].
    pub fn walk_capture(&mut self, host: &mut dyn Host) -> Result<(), HostError> {
        self.walk_step(host, |module, machine, walk| module.m283_capture(machine, walk))
    }

    /// Solves the walk and commits it as M283 does (K, the camera tool's offset, the profile:
    /// all or nothing), tells the operator, and ends the walk.
    ///
    /// # Errors
    /// No walk in progress; the walk still needs captures (the walk is kept); otherwise as
    /// M283 (the walk is dropped, nothing written).
    pub fn walk_finish(&mut self, host: &mut dyn Host) -> Result<Outcome, HostError> {
        let reply = self.walk_step(host, |module, machine, walk| module.m283_finish(machine, walk))?;
        self.walk = None;
        let outcome = Outcome::Calibrate(reply);
        host.message(&summary(&outcome));
        Ok(outcome)
    }

    /// Runs `step` on the walk in progress. A failure drops the walk, except a step out of order
    /// (the walk is still good).
    fn walk_step<T>(
        &mut self,
        host: &mut dyn Host,
        step: impl FnOnce(&mut VisionModule, &mut dyn Machine, &mut StepwiseWalk) -> Result<T, VisionError>,
    ) -> Result<T, HostError> {
        let Some(mut walk) = self.walk.take() else {
            return Err(HostError::Mcode(McodeError::from(VisionError::WalkOrder {
                what: "no M283 walk is in progress; M283 starts one",
            })));
        };
        let result = self.on_machine(host, |module, machine| step(module, machine, &mut walk));
        let keep = match &result {
            Ok(_) => true,
            Err(HostError::Mcode(McodeError::Vision(VisionError::WalkOrder { .. }))) => true,
            Err(_) => false,
        };
        if keep {
            self.walk = Some(walk);
        }
        result
    }

    /// Runs `f` on the module and the host as a [`Machine`], the alignment brought up to date
    /// first; a controller failure during it wins over the module's result.
    fn on_machine<T>(
        &mut self,
        host: &mut dyn Host,
        f: impl FnOnce(&mut VisionModule, &mut dyn Machine) -> Result<T, VisionError>,
    ) -> Result<T, HostError> {
        self.refresh_alignment(host)?;
        let mut machine = HostMachine { host, alignment: self.alignment, failure: RefCell::new(None) };
        let result = f(&mut self.module, &mut machine);
        if let Some(failure) = machine.failure.into_inner() {
            return Err(failure);
        }
        Ok(result.map_err(McodeError::from)?)
    }

    /// Brings the tracked alignment up to date with what the host can tell: LinuxCNC's is read
    /// whole from the host (the flag and θ₀ in persistent parameters, the G5x rotation and the
    /// G92/G52 offset: it survives restarts and sessions); a Mach4 host that says none is active
    /// makes the session forget its own.
    fn refresh_alignment(&mut self, host: &dyn Host) -> Result<(), HostError> {
        match host.controller() {
            Controller::LinuxCnc => {
                self.alignment = linuxcnc::active_chain(
                    host.pound(linuxcnc::ALIGNMENT_ACTIVE_PARAM)?,
                    host.pound(linuxcnc::BASE_ROTATION_PARAM)?,
                    host.xy_rotation_deg()?,
                    host.g92_offset()?,
                );
            }
            Controller::Mach4 => {
                if host.alignment_active()? == Some(false) {
                    self.alignment = None;
                }
            }
        }
        Ok(())
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
/// the image, a height change, …) when it has one. On LinuxCNC, M282 says which scale it left
/// out.
fn summary(outcome: &Outcome) -> String {
    let (done, warning) = match outcome {
        Outcome::Begin(_) => ("M280: Vision run started".to_string(), None),
        Outcome::Capture(r) => ("M281: mark captured".to_string(), r.report.warning.as_deref()),
        Outcome::Apply(reply) => (apply_summary(reply.report.linuxcnc.as_ref()), None),
        Outcome::Calibrate(r) => ("M283: calibration done and saved".to_string(), r.report.warning()),
        Outcome::SelectJob(_) => ("M284: camera job selected".to_string(), None),
    };
    match warning {
        Some(w) => format!("{done} (warning: {w})"),
        None => done,
    }
}

/// M282's status line: the scale a LinuxCNC alignment could not apply, when there was any.
fn apply_summary(linuxcnc: Option<&LinuxCncAlignment>) -> String {
    match linuxcnc {
        Some(a) if a.ignored_scale != Vector2::new(1.0, 1.0) => format!(
            "M282: alignment applied without scale (LinuxCNC cannot scale): scale X {:.6} / Y {:.6} ignored, {:.4} % \
             from 1",
            a.ignored_scale.x,
            a.ignored_scale.y,
            a.ignored_scale_dev_pct()
        ),
        _ => "M282: alignment applied".to_string(),
    }
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

impl HostMachine<'_> {
    /// The sign between the host's tool table and the module's offset: −1 on LinuxCNC (see
    /// [`Host::controller`]), else 1.
    fn table_sign(&self) -> f64 {
        match self.host.controller() {
            Controller::LinuxCnc => -1.0,
            Controller::Mach4 => 1.0,
        }
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

    fn controller(&self) -> Controller {
        self.host.controller()
    }

    fn xy_rotation_deg(&self) -> f64 {
        self.keep(self.host.xy_rotation_deg(), 0.0)
    }

    fn tool_offset(&self, tool: u32) -> Result<Vector2<f64>, MachineError> {
        let table = self.host.tool_offset(tool).map_err(machine_error)?;
        Ok(self.table_sign() * table)
    }

    fn set_tool_offset(&mut self, tool: u32, offset: Vector2<f64>) -> Result<(), MachineError> {
        let table = self.table_sign() * offset;
        self.host.set_tool_offset(tool, table).map_err(machine_error)
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
