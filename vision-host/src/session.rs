//! [`Session`]: one Vision module kept alive between a controller's M-code calls.

use std::cell::RefCell;
use std::path::Path;

use vision_core::{linuxcnc, Controller, DriverRegistry, Machine, MachineError, ProfileStore, Timestamp, VisionModule};
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
        self.refresh_alignment(host)?;
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

/// The operator's status line after a successful call. On LinuxCNC, M282 says which scale it
/// left out.
fn summary(outcome: &Outcome) -> String {
    let line = match outcome {
        Outcome::Begin(_) => "M280: Vision run started",
        Outcome::Capture(_) => "M281: mark captured",
        Outcome::Apply(reply) => match &reply.report.linuxcnc {
            Some(a) if a.ignored_scale != Vector2::new(1.0, 1.0) => {
                return format!(
                    "M282: alignment applied without scale (LinuxCNC cannot scale): scale X {:.6} / Y {:.6} \
                     ignored, {:.4} % from 1",
                    a.ignored_scale.x,
                    a.ignored_scale.y,
                    a.ignored_scale_dev_pct()
                );
            }
            _ => "M282: alignment applied",
        },
        Outcome::Calibrate(_) => "M283: calibration done and saved",
        Outcome::SelectJob(_) => "M284: camera job selected",
    };
    line.to_string()
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
