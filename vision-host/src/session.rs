//! [`Session`]: one Vision module kept alive between a controller's M-code calls.

use std::path::Path;

use vision_core::controller::ScaleLeftOut;
use vision_core::{
    CaptureStep, DriverRegistry, Machine, ParamValue, ProfileStore, StepwiseCapture, StepwiseWalk, VisionError,
    VisionModule, WalkTarget,
};
use vision_math::AlignmentChain;
use vision_mcode::{McodeError, Outcome, VisionCall};

use crate::error::HostError;
use crate::panel::{panel_dir, Publisher};
use vision_core::text::{printable_line, MAX_MESSAGE_CHARS};

/// The camera drivers a real machine can pick by `VisionDriver` (the simulator is not one).
#[must_use]
pub fn registry() -> DriverRegistry {
    crate::cameras(None)
}

/// The Vision module of one controller, between M-code calls: parameters, the run's dot list,
/// the camera connection, the profile it saves to, and the alignment its last M282 left active.
/// Every front end runs the M-codes through it: the CLI on the simulated machine, the Mach4
/// and LinuxCNC bridges on theirs.
pub struct Session {
    module: VisionModule,
    /// The stepwise M283 walk in progress ([`Session::walk_begin`]).
    walk: Option<StepwiseWalk>,
    /// The stepwise M281 between its re-centring moves ([`Session::capture_begin`]).
    capture: Option<StepwiseCapture>,
    /// Where the session's state goes for the panel ([`Session::publish`]).
    publisher: Option<Publisher>,
}

impl std::fmt::Debug for Session {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Session")
            .field("module", &self.module)
            .field("walk", &self.walk)
            .field("capture", &self.capture)
            .field("publisher", &self.publisher)
            .finish()
    }
}

impl Session {
    /// A session around `module` (its driver and profile already set), no alignment active.
    #[must_use]
    pub fn new(module: VisionModule) -> Session {
        Session { module, walk: None, capture: None, publisher: None }
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

    /// The Vision module, mutably (e.g. to change a parameter between programs).
    pub fn module_mut(&mut self) -> &mut VisionModule {
        &mut self.module
    }

    /// Reads parameter `name` (case-insensitive): configuration, calibration, a driver's
    /// setting or telemetry (`VisionLastStatus`, `VisionRun_*`), as a controller's screen shows it.
    ///
    /// # Errors
    /// [`HostError::Param`] for a name no parameter has.
    pub fn param(&self, name: &str) -> Result<ParamValue, HostError> {
        self.module.param(name).map_err(HostError::Param)
    }

    /// Starts publishing the session's state into the panel folder beside its profile
    /// (`P.toml` → `P.panel/`, see [`crate::panel`]) after every call and every telemetry
    /// write, and returns the folder; `None` without a profile. A folder that cannot be
    /// written is told to the operator once, at the next call, and never fails one.
    pub fn publish(&mut self) -> Option<&Path> {
        let profile = self.module.profile()?.path().to_path_buf();
        let publisher = Publisher::start(panel_dir(&profile), &profile);
        self.module.set_telemetry_sink(Some(publisher.sink()));
        publisher.record(&self.module, None);
        self.publisher = Some(publisher);
        self.publisher.as_ref().map(Publisher::dir)
    }

    /// The panel's publisher, when [`Session::publish`] started one.
    #[must_use]
    pub fn publisher(&self) -> Option<&Publisher> {
        self.publisher.as_ref()
    }

    /// Tells the operator the publisher's problem, once, before a call's own messages.
    fn tell_panel_problem(&self, machine: &mut dyn Machine) {
        if let Some(problem) = self.publisher.as_ref().and_then(Publisher::take_problem) {
            machine.message(&format!("Vision panel: {problem}"));
        }
    }

    /// Hands the state after M-code `m` (its outcome or refusal) to the publisher, and lets it
    /// settle ([`Publisher::settle`]).
    fn published(&self, m: u32, result: Result<&Outcome, &HostError>) {
        let Some(publisher) = &self.publisher else { return };
        let call = match result {
            Ok(outcome) => Ok(outcome.clone()),
            Err(e) => Err(printable_line(&e.to_string(), MAX_MESSAGE_CHARS)),
        };
        publisher.record(&self.module, Some((m, call)));
        publisher.settle();
    }

    /// Hands the state after a step of M-code `m` to the publisher when the step failed.
    fn published_failure<T>(&self, m: u32, result: &Result<T, HostError>) {
        if let Err(e) = result {
            self.published(m, Err(e));
        }
    }

    /// The alignment active as of the last call ([`VisionModule::alignment`]): the one this
    /// session's last M282 applied, or what the controller reported.
    #[must_use]
    pub fn alignment(&self) -> Option<&AlignmentChain> {
        self.module.alignment()
    }

    /// Runs Vision M-code `m` (280–284) with the words of its line on `machine` (the module
    /// runs the G-code it emits on the machine as it goes) and tells the operator what happened
    /// ([`Machine::message`]).
    ///
    /// # Errors
    /// [`HostError::Mcode`]: a bad word, the module's refusal in the manual's words, or the
    /// machine's failure during the call ([`VisionError::Machine`], with its kind). A refusal
    /// changes nothing.
    pub fn mcode(&mut self, machine: &mut dyn Machine, m: u32, words: &[(char, f64)]) -> Result<Outcome, HostError> {
        self.tell_panel_problem(machine);
        let result = self.run_mcode(machine, m, words);
        self.published(m, result.as_ref());
        result
    }

    /// [`Session::mcode`] without the panel.
    fn run_mcode(&mut self, machine: &mut dyn Machine, m: u32, words: &[(char, f64)]) -> Result<Outcome, HostError> {
        let words = machine.controller().manual_words(m, words).map_err(McodeError::from)?;
        let call = VisionCall::parse(m, &words)?;
        let outcome = call.run(&mut self.module, machine).map_err(McodeError::from)?;
        machine.message(&summary(&outcome));
        Ok(outcome)
    }

    /// Runs M281 stepwise, for a host whose M-code only queues G-code and must wait for the
    /// machine itself (LinuxCNC's remap yields after each move): M281's words (`D`) and the
    /// first trigger where the machine stands. `Ok(true)`: a re-centring move was handed to the
    /// machine; wait until the machine is there, then call [`Session::capture_next`].
    /// `Ok(false)`: the capture is done and the operator told, as [`Session::mcode`] does. A
    /// capture already in progress is dropped.
    ///
    /// # Errors
    /// A bad word or M281's refusal ([`HostError::Mcode`]); no capture is in progress then.
    pub fn capture_begin(&mut self, machine: &mut dyn Machine, words: &[(char, f64)]) -> Result<bool, HostError> {
        self.tell_panel_problem(machine);
        let result = self.capture_start(machine, words);
        self.published_failure(281, &result);
        result
    }

    /// [`Session::capture_begin`] without the panel.
    fn capture_start(&mut self, machine: &mut dyn Machine, words: &[(char, f64)]) -> Result<bool, HostError> {
        self.capture = None;
        let words = machine.controller().manual_words(281, words).map_err(McodeError::from)?;
        let VisionCall::Capture { keep_image } = VisionCall::parse(281, &words)? else {
            // `parse(281, …)` answers only Capture; kept typed all the same.
            return Err(HostError::Mcode(McodeError::BadWord {
                mcode: "M281",
                word: String::new(),
                reason: "M281 takes D0 or D1".to_string(),
            }));
        };
        let step = self.module.m281_begin(machine, keep_image).map_err(McodeError::from)?;
        Ok(self.capture_step(machine, step))
    }

    /// M281's next step, once the machine has reached the move [`Session::capture_begin`] or
    /// the last `capture_next` asked for: answers as `capture_begin` does.
    ///
    /// # Errors
    /// No capture in progress, or M281's failure ([`HostError::Mcode`]; the capture is dropped,
    /// nothing written, the program's modal state put back).
    pub fn capture_next(&mut self, machine: &mut dyn Machine) -> Result<bool, HostError> {
        self.tell_panel_problem(machine);
        let result = self.capture_continue(machine);
        self.published_failure(281, &result);
        result
    }

    /// [`Session::capture_next`] without the panel.
    fn capture_continue(&mut self, machine: &mut dyn Machine) -> Result<bool, HostError> {
        let Some(capture) = self.capture.take() else {
            return Err(HostError::Mcode(McodeError::from(VisionError::CaptureOrder {
                what: "no re-centring is in progress; M281 starts one",
            })));
        };
        let step = self.module.m281_next(machine, capture).map_err(McodeError::from)?;
        Ok(self.capture_step(machine, step))
    }

    /// Keeps a capture that moves; reports a finished one.
    fn capture_step(&mut self, machine: &mut dyn Machine, step: CaptureStep) -> bool {
        match step {
            CaptureStep::Moving(capture) => {
                self.capture = Some(capture);
                true
            }
            CaptureStep::Done(reply) => {
                let outcome = Outcome::Capture(reply);
                machine.message(&summary(&outcome));
                self.published(281, Ok(&outcome));
                false
            }
        }
    }

    /// Starts M283 stepwise, for a host whose M-code cannot both move and trigger (LinuxCNC's
    /// `m283.ngc`): M283's words (`Q` or `C`) and all of M283's checks, nothing moved. Then
    /// loop [`Session::walk_next`] → move there → [`Session::walk_capture`] until `walk_next`
    /// answers `None`, and finish with [`Session::walk_finish`]. A walk already in progress is
    /// dropped.
    ///
    /// # Errors
    /// A bad word or M283's refusal ([`HostError::Mcode`]), or the controller's
    /// the machine's failure; no walk is in progress then.
    pub fn walk_begin(&mut self, machine: &mut dyn Machine, words: &[(char, f64)]) -> Result<(), HostError> {
        self.tell_panel_problem(machine);
        let result = self.walk_start(machine, words);
        self.published_failure(283, &result);
        result
    }

    /// [`Session::walk_begin`] without the panel.
    fn walk_start(&mut self, machine: &mut dyn Machine, words: &[(char, f64)]) -> Result<(), HostError> {
        self.walk = None;
        let words = machine.controller().manual_words(283, words).map_err(McodeError::from)?;
        let VisionCall::Calibrate(mode) = VisionCall::parse(283, &words)? else {
            // `parse(283, …)` answers only Calibrate; kept typed all the same.
            return Err(HostError::Mcode(McodeError::BadWord {
                mcode: "M283",
                word: String::new(),
                reason: "give exactly one of Qd or Cn".to_string(),
            }));
        };
        self.walk = Some(self.module.m283_begin(machine, mode).map_err(McodeError::from)?);
        Ok(())
    }

    /// The next target of the walk (program frame X/Y and the height above the walk's start Z,
    /// current units; move Z first), or `None` when the walk has every capture it needs. It
    /// depends on the captures so far.
    ///
    /// # Errors
    /// No walk in progress, the walk failed on its captures (M283's message; the walk is
    /// dropped and nothing written), or the machine's failure.
    pub fn walk_next(&mut self, machine: &mut dyn Machine) -> Result<Option<WalkTarget>, HostError> {
        self.walk_step(machine, |module, machine, walk| module.m283_next(machine, walk))
    }

    /// Triggers here, for the point [`Session::walk_next`] gave; call it once the machine has
    /// arrived there.
    ///
    /// # Errors
    /// No walk in progress or no capture pending; the camera's failure or an NG (M283's
    /// message: the walk is dropped, nothing written), or the machine's failure.
    pub fn walk_capture(&mut self, machine: &mut dyn Machine) -> Result<(), HostError> {
        self.walk_step(machine, |module, machine, walk| module.m283_capture(machine, walk))
    }

    /// Solves the walk and commits it as M283 does (K, the camera tool's offset, the profile:
    /// all or nothing), tells the operator, and ends the walk.
    ///
    /// # Errors
    /// No walk in progress; the walk still needs captures (the walk is kept); otherwise as
    /// M283 (the walk is dropped, nothing written).
    pub fn walk_finish(&mut self, machine: &mut dyn Machine) -> Result<Outcome, HostError> {
        let reply = self.walk_step(machine, |module, machine, walk| module.m283_finish(machine, walk))?;
        self.walk = None;
        let outcome = Outcome::Calibrate(reply);
        machine.message(&summary(&outcome));
        self.published(283, Ok(&outcome));
        Ok(outcome)
    }

    /// Runs `step` on the walk in progress. A failure drops the walk, except a step out of order
    /// (the walk is still good).
    fn walk_step<T>(
        &mut self,
        machine: &mut dyn Machine,
        step: impl FnOnce(&mut VisionModule, &mut dyn Machine, &mut StepwiseWalk) -> Result<T, VisionError>,
    ) -> Result<T, HostError> {
        let Some(mut walk) = self.walk.take() else {
            return Err(HostError::Mcode(McodeError::from(VisionError::WalkOrder {
                what: "no M283 walk is in progress; M283 starts one",
            })));
        };
        let result = step(&mut self.module, machine, &mut walk).map_err(|e| HostError::Mcode(e.into()));
        self.published_failure(283, &result);
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
}

/// The operator's status line after a successful call, with the call's warning (a mark outside
/// the image, a height change, …) when it has one. On a controller that cannot scale, M282 says
/// which scale it left out.
pub(crate) fn summary(outcome: &Outcome) -> String {
    let (done, warning) = match outcome {
        Outcome::Begin(_) => ("M280: Vision run started".to_string(), None),
        Outcome::Capture(r) => ("M281: mark captured".to_string(), r.report.warning.as_deref()),
        Outcome::Apply(reply) => (apply_summary(reply.report.how.scale_left_out.as_ref()), None),
        Outcome::Calibrate(r) => ("M283: calibration done and saved".to_string(), r.report.warning()),
        Outcome::SelectJob(_) => ("M284: camera job selected".to_string(), None),
    };
    match warning {
        Some(w) => format!("{done} (warning: {w})"),
        None => done,
    }
}

/// M282's status line: the scale the controller could not apply, and why, when there was any.
fn apply_summary(left_out: Option<&ScaleLeftOut>) -> String {
    match left_out {
        Some(l) if l.is_scaled() => format!(
            "M282: alignment applied without scale ({}): scale X {:.6} / Y {:.6} ignored, {:.4} % from 1",
            l.reason,
            l.scale.x,
            l.scale.y,
            l.dev_pct()
        ),
        _ => "M282: alignment applied".to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vision_core::{Capture, Judgment, Reply};
    use vision_math::{LengthUnit, Point2, Vector2};

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
