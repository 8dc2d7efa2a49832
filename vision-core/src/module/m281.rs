//! M281: capture one mark.

use vision_math::{AlignmentChain, LengthUnit, PixelChain, Point2, ScaleEvidence, Vector2};

use super::capture::{mark_size, observe, outside_image_note, pixel_chain, require_mark, Capture, Recentred};
use super::height::{self, NextMove};
use super::m283::{absolute_move, relative_move};
use super::{Dot, Reply, VisionModule};
use crate::driver::{ImageRequest, Reading};
use crate::error::VisionError;
use crate::machine::{checked, Machine, Timestamp};
use crate::pound::{PoundBlock, SlotValues, SLOTS};

/// An M281 between its re-centring moves ([`VisionModule::m281_begin`]): the readings so far
/// and the program's state to put back. Opaque; hand it to [`VisionModule::m281_next`] once the
/// machine has reached the move it asked for.
#[derive(Debug)]
pub struct StepwiseCapture {
    keep_image: bool,
    block: PoundBlock,
    chain: PixelChain,
    unit: LengthUnit,
    alignment: Option<AlignmentChain>,
    /// Where the program put the camera, program frame.
    commanded: Point2<f64>,
    /// The first reading's centred pixel offset, pixels.
    first_px: Vector2<f64>,
    /// The reading kept as the capture: the one nearest the image centre (a scale error of K
    /// acts on the offset it read).
    best: Kept,
    /// Every reading of this mark inside the image: the camera's position and the offset read
    /// from it (program frame), the evidence of the image scale at the part's height.
    readings: Vec<(Point2<f64>, Vector2<f64>)>,
    /// The scale evidence of `readings`.
    mark_scale: ScaleEvidence,
    /// One reading's noise, machine units.
    noise: f64,
    /// True once a probe move was made.
    probed: bool,
    /// The G-code run so far (the re-centring moves).
    gcode: Vec<String>,
    /// Re-centring moves made.
    passes: i64,
    /// True once the program's modal state is saved (before the first move).
    saved: bool,
}

/// Where an M281 stands after [`VisionModule::m281_begin`] or [`VisionModule::m281_next`].
#[derive(Debug)]
#[expect(
    clippy::large_enum_variant,
    reason = "One value per machine move, moved a few times: its size costs nothing worth a box."
)]
pub enum CaptureStep {
    /// A re-centring move was handed to the machine: wait until the machine is there, then
    /// call [`VisionModule::m281_next`] with this.
    Moving(StepwiseCapture),
    /// The capture, committed; the G-code that puts the camera back where the program had it
    /// and the program's modal state back was handed to the machine last.
    Done(Reply<Capture>),
}

impl VisionModule {
    /// **M281**: triggers at the current commanded position and stores the observed point.
    ///
    /// `O = C + K·R·(p − res/2 − PxCenterOffset)` with K converted from `Cal_Units` to the
    /// machine's unit; with an alignment active, `O` is reported in the program frame (SPEC §2).
    /// In a run the capture is appended to the dot list, written to slot `n` (n = 1–4, the n-th
    /// capture; later captures only feed the fit) and mirrored to slot 0, and `Run_DotCount`
    /// grows; outside a run only slot 0 and the telemetry are written. Every success writes the
    /// `Last*` telemetry with `LastStatus` = `OK`.
    ///
    /// A mark read off the image centre may move the camera over it or past it; the capture is
    /// the reading nearest the centre, then the camera and the program's modal state go back
    /// ([`Machine::save_modal_state`]), on success and failure alike (`docs/vision-module.md`,
    /// M281's moves). This runs [`VisionModule::m281_begin`] and [`VisionModule::m281_next`].
    ///
    /// `keep_image` (D1): keeps the reported reading's image when the driver advertises
    /// [`crate::CameraDriver::grab_image`]; no image is a warning ([`Capture::warning`]).
    ///
    /// # Errors
    /// [`VisionError::NotEnabled`], [`VisionError::WrongTool`], [`VisionError::ToolOffsetNotApplied`],
    /// [`VisionError::PoundBaseReserved`], [`VisionError::PoundBlockMissing`],
    /// [`VisionError::NotCalibrated`] (before the trigger: only `LastStatus` changes);
    /// [`VisionError::NoDriver`]; [`VisionError::Driver`] or [`VisionError::NoMark`] (the failed
    /// trigger is recorded, the other `Last*` cleared); [`VisionError::Machine`] for a refused
    /// move; a failed pound-variable write (those written are restored). The dot list, the
    /// slots and `Run_DotCount` change only on success.
    pub fn m281(&mut self, machine: &mut dyn Machine, keep_image: bool) -> Result<Reply<Capture>, VisionError> {
        let mut step = self.m281_begin(machine, keep_image)?;
        loop {
            match step {
                CaptureStep::Done(reply) => return Ok(reply),
                CaptureStep::Moving(capture) => step = self.m281_next(machine, capture)?,
            }
        }
    }

    /// M281's first step: the checks, the first trigger where the machine stands, then either
    /// the capture committed ([`CaptureStep::Done`]) or the first re-centring move handed to
    /// the machine ([`CaptureStep::Moving`]; the modal state saved first).
    ///
    /// # Errors
    /// As [`VisionModule::m281`].
    pub fn m281_begin(&mut self, machine: &mut dyn Machine, keep_image: bool) -> Result<CaptureStep, VisionError> {
        let ready = self.check_enabled().and_then(|()| self.check_tool(machine)).and_then(|()| {
            self.check_calibration_record(machine)?;
            self.check_camera_offset(machine)?;
            let block = PoundBlock::on_machine(self.params.pound_var_base(), machine)?;
            let unit = machine.units()?;
            Ok((block, pixel_chain(&self.params, unit)?, unit, self.refresh_alignment(machine)?))
        });
        let (block, chain, unit, alignment) = match ready {
            Ok(r) => r,
            Err(e) => {
                // The DRO shows why nothing was read.
                self.publish_failure(None, &e);
                return Err(e);
            }
        };
        let trigger_time = machine.now();
        let reading = self.trigger_mark(machine.controller().sheet_calibration())?;
        let native = Point2::new(reading.x_px, reading.y_px);
        let (commanded, observed) = self.observe(machine, alignment, chain.delta(native))?;
        let noise = height::noise_px(&self.params) * chain.k().singular_values().max();
        let capture = StepwiseCapture {
            keep_image,
            block,
            chain,
            unit,
            alignment,
            commanded,
            first_px: chain.centred(native),
            best: Kept { time: trigger_time, reading, native, observed, camera: commanded },
            readings: vec![(commanded, observed - commanded)],
            mark_scale: ScaleEvidence::default(),
            noise,
            probed: false,
            gcode: Vec::new(),
            passes: 0,
            saved: false,
        };
        self.recentre_or_commit(machine, capture)
    }

    /// M281's next step, once the machine has reached the re-centring move: settles
    /// `VisionTriggerSettleSec`, triggers and observes again, then moves again or commits as
    /// [`VisionModule::m281_begin`] does.
    ///
    /// # Errors
    /// As [`VisionModule::m281`]; the modal state is restored first (the camera stays where it
    /// moved).
    pub fn m281_next(
        &mut self,
        machine: &mut dyn Machine,
        mut capture: StepwiseCapture,
    ) -> Result<CaptureStep, VisionError> {
        let pass = machine.dwell(self.params.trigger_settle_s()).map_err(VisionError::from).and_then(|()| {
            // M281 D1 keeps the image of the reading reported.
            let time = machine.now();
            let reading = self.trigger_mark(machine.controller().sheet_calibration())?;
            let native = Point2::new(reading.x_px, reading.y_px);
            let (camera, observed) = observe(machine, capture.alignment, capture.chain.delta(native))?;
            Ok(Kept { time, reading, native, observed, camera })
        });
        match pass {
            Ok(pass) => {
                if outside_image_note(&self.params, pass.native).is_none() {
                    capture.readings.push((pass.camera, pass.observed - pass.camera));
                    // One regression over all of the mark's readings (recomputed whole); a
                    // refused one (a non-finite noise from a broken K) adds nothing.
                    let mut fresh = ScaleEvidence::default();
                    if fresh.add_mark(&capture.readings, capture.noise).is_ok() {
                        capture.mark_scale = fresh;
                    }
                    let chain = &capture.chain;
                    if chain.centred(pass.native).norm() <= chain.centred(capture.best.native).norm() {
                        capture.best = pass;
                    }
                }
                self.recentre_or_commit(machine, capture)
            }
            Err(e) => Err(self.abandon(machine, &capture, e)),
        }
    }

    /// After a reading: move again (re-centre or probe, as [`VisionModule::m281`] describes),
    /// or, when the budget says stay or the passes are spent, commit.
    fn recentre_or_commit(
        &mut self,
        machine: &mut dyn Machine,
        mut capture: StepwiseCapture,
    ) -> Result<CaptureStep, VisionError> {
        // A reading outside the image is no distance to move by (a wrong resolution or K):
        // every move stays within the field of view.
        let target = if capture.passes < self.params.recenter_passes()
            && outside_image_note(&self.params, capture.best.native).is_none()
        {
            let sigma = self.run.scale.merged(capture.mark_scale).estimate().map(|e| e.sigma);
            let best = &capture.best;
            match height::next_move(&self.params, capture.chain.centred(best.native).norm(), sigma, capture.probed) {
                NextMove::Stay => None,
                NextMove::Recentre => Some(best.observed),
                NextMove::Probe => {
                    // The mark lands `VisionHeightProbePx` on the far side of the centre.
                    let reach = best.observed - best.camera;
                    let away = if reach.norm() > 0.0 { reach / reach.norm() } else { Vector2::x() };
                    capture.probed = true;
                    let k = capture.chain.k().singular_values().max();
                    Some(best.observed + away * (self.params.height_probe_px() * k))
                }
            }
        } else {
            None
        };
        if let Some(target) = target {
            // The program's modal state is saved before the first move and put back after the
            // last, whatever happens in between: a feed move after M281 stays a feed move.
            if !capture.saved {
                if let Err(e) = machine.save_modal_state() {
                    return Err(self.abandon(machine, &capture, e.into()));
                }
                capture.saved = true;
            }
            let moved = checked::program_position(machine)
                .map_err(VisionError::from)
                .and_then(|at| machine.command(&relative_move(target - at)).map_err(VisionError::from));
            return match moved {
                Ok(lines) => {
                    capture.gcode.extend(lines);
                    capture.passes += 1;
                    Ok(CaptureStep::Moving(capture))
                }
                Err(e) => Err(self.abandon(machine, &capture, e)),
            };
        }
        if capture.passes > 0 {
            // Back where the program put the camera: the program goes on from its own point.
            match machine.command(&absolute_move(capture.commanded)) {
                Ok(lines) => capture.gcode.extend(lines),
                Err(e) => return Err(self.abandon(machine, &capture, e.into())),
            }
        }
        if capture.saved {
            if let Err(e) = machine.restore_modal_state() {
                let e = VisionError::from(e);
                self.publish_failure(None, &e);
                return Err(e);
            }
        }
        self.commit_capture(machine, capture).map(CaptureStep::Done)
    }

    /// A failed step: the modal state put back when it was saved (the first failure is the one
    /// reported), the failure shown in `LastStatus`.
    fn abandon(&mut self, machine: &mut dyn Machine, capture: &StepwiseCapture, e: VisionError) -> VisionError {
        if capture.saved {
            // The first failure is the operator's news; a failed restore after it adds nothing.
            let _ = machine.restore_modal_state();
        }
        self.publish_failure(None, &e);
        e
    }

    /// Writes the capture (slots, dot list, telemetry, image) and reports it.
    fn commit_capture(
        &mut self,
        machine: &mut dyn Machine,
        capture: StepwiseCapture,
    ) -> Result<Reply<Capture>, VisionError> {
        let StepwiseCapture {
            keep_image,
            block,
            chain,
            unit,
            commanded,
            first_px,
            best: Kept { time: trigger_time, reading, native, observed, camera },
            mark_scale,
            probed,
            gcode,
            passes,
            readings,
            noise,
            ..
        } = capture;
        let turn_note = match turn_check(&readings, noise, machine.controller().sheet_calibration()) {
            Ok(note) => note,
            Err(e) => {
                self.publish_failure(None, &e);
                return Err(e);
            }
        };
        let offset = chain.delta(native);
        let (width, height) = mark_size(&chain, &reading);
        let values = SlotValues {
            x: observed.x,
            y: observed.y,
            width,
            height,
            angle_deg: reading.angle_deg,
            score: reading.score,
        };

        let in_run = self.run_active();
        let dot_index = in_run.then(|| self.run.dots.len() + 1);
        let slot = dot_index.and_then(|i| u32::try_from(i).ok()).filter(|s| *s < SLOTS);
        let mut writes = block.slot_writes(0, &values);
        if let Some(s) = slot {
            writes.extend(block.slot_writes(s, &values));
        }
        write_pounds(machine, &writes)?;

        // Committed: the capture counts from here on, and so does its evidence of the scale.
        self.run.scale = self.run.scale.merged(mark_scale);
        if in_run {
            let mark_size = (width.abs() + height.abs()) / 2.0;
            let lens_along = chain.lens_sensitivity(native);
            self.run.dots.push(Dot { commanded, observed, unit, reach: observed - camera, mark_size, lens_along });
            self.publish_run();
        }
        let centred = chain.centred(native);
        self.dro.reading(Some(&chain), centred, &reading);

        let mut image = None;
        let mut warning = None;
        if let Some(driver) = self.driver.as_deref_mut().filter(|_| keep_image) {
            if driver.capabilities().grab_image {
                let stamp = trigger_time.file_stamp();
                let request = ImageRequest { dir: &self.images_dir, since: trigger_time.time, stamp: &stamp };
                match driver.grab_image(&request) {
                    Ok(path) => image = Some(path),
                    Err(e) => warning = Some(format!("image not saved: {e}")),
                }
            } else {
                warning = Some(format!("image not saved: camera driver {} cannot keep images", driver.name()));
            }
        }
        let notes = [
            self.driver.as_deref().and_then(|d| d.reading_warning(&reading)),
            outside_image_note(&self.params, native),
            self.height_note(width, height, unit),
            turn_note,
            self.mark_note(),
        ];
        for note in notes.into_iter().flatten() {
            warning = Some(warning.map_or_else(|| note.clone(), |w| format!("{note}; {w}")));
        }
        if let Some(w) = &warning {
            self.dro.ok(Some(w));
        }
        Ok(Reply {
            gcode,
            report: Capture {
                unit,
                commanded,
                observed,
                offset,
                centred_px: centred,
                width,
                height,
                angle_deg: reading.angle_deg,
                score: reading.score,
                judgment: reading.judgment,
                dot_index,
                slot,
                image,
                warning,
                recentred: (passes > 0).then_some(Recentred { passes, first_px, probe: probed }),
            },
        })
    }

    /// Triggers; a failed trigger or no mark is recorded in `LastJudgment` / `LastStatus`, and
    /// no driver in `LastStatus`. The frame's size is checked against the calibration's
    /// ([`VisionModule::check_resolution`]; `sheet` names the controller's sheet calibration).
    fn trigger_mark(&mut self, sheet: &str) -> Result<crate::driver::Reading, VisionError> {
        let driver = match self.driver_mut() {
            Ok(d) => d,
            Err(e) => {
                self.publish_failure(None, &e);
                return Err(e);
            }
        };
        let reading = match driver.trigger() {
            Ok(r) => r,
            Err(e) => {
                let e = VisionError::from(e);
                self.publish_failure(Some(-1), &e);
                return Err(e);
            }
        };
        if let Err(e) = require_mark(&reading, &*driver) {
            self.publish_failure(Some(i64::from(reading.judgment.code())), &e);
            return Err(e);
        }
        if let Err(e) = self.check_resolution(sheet) {
            self.publish_failure(None, &e);
            return Err(e);
        }
        Ok(reading)
    }

    /// The height check: the mark's measured size against `VisionMarkDiameter`. The image scale
    /// follows the working distance, so a mark measuring `m` instead of `d` sits about
    /// `d / m − 1` closer (negative) or farther than where K was calibrated.
    fn height_note(&self, width: f64, height: f64, unit: LengthUnit) -> Option<String> {
        let diameter = LengthUnit::Inch.convert(self.params.mark_diameter_in(), unit);
        let tolerance = self.params.mark_size_tolerance_pct();
        let measured = (width.abs() + height.abs()) / 2.0;
        if !(diameter > 0.0 && tolerance > 0.0 && measured > 0.0) {
            return None;
        }
        let off_pct = (measured / diameter - 1.0) * 100.0;
        let distance_pct = (diameter / measured - 1.0) * 100.0;
        (off_pct.abs() > tolerance).then(|| {
            let u = unit.short_name();
            format!(
                "the mark measures {measured:.4} {u} against VisionMarkDiameter {diameter:.4} {u} ({off_pct:+.2} %): \
                 the part is about {:.1} % {} than where K was calibrated; offsets far from the image centre carry \
                 that error (M282 measures it from the camera moves and corrects it) — check the part's height or recalibrate at it",
                distance_pct.abs(),
                if distance_pct < 0.0 { "closer to the camera" } else { "farther from the camera" }
            )
        })
    }
}

impl VisionModule {
    /// [`observe`], a failure shown in `LastStatus` (the trigger already happened).
    fn observe(
        &mut self,
        machine: &dyn Machine,
        alignment: Option<vision_math::AlignmentChain>,
        offset: vision_math::Vector2<f64>,
    ) -> Result<(Point2<f64>, Point2<f64>), VisionError> {
        observe(machine, alignment, offset).inspect_err(|e| self.publish_failure(None, e))
    }
}

/// A reading of the mark: when it was triggered, its native pixel, its observed point and the
/// camera's position at it (program frame).
#[derive(Debug)]
struct Kept {
    time: Timestamp,
    reading: Reading,
    native: Point2<f64>,
    observed: Point2<f64>,
    camera: Point2<f64>,
}

/// The largest turn of the image against K that M281 accepts with a warning, degrees: beyond
/// it the camera is turned on its mount (or another camera) and every capture off the image
/// centre is read in the wrong direction, so M281 refuses.
pub(crate) const TURN_REFUSE_DEG: f64 = 5.0;

/// The smallest turn M281 warns of, degrees (K's own rotation is known to a few hundredths).
pub(crate) const TURN_WARN_DEG: f64 = 0.5;

/// Checks the way the mark moved in the image as the camera moved against K
/// ([`vision_math::image_turn`]): a turn beyond 4σ and [`TURN_REFUSE_DEG`] refuses, beyond 4σ
/// and [`TURN_WARN_DEG`] is a warning; one reading says nothing. `sheet` names the controller's
/// sheet calibration for the advice.
fn turn_check(
    readings: &[(Point2<f64>, Vector2<f64>)],
    noise: f64,
    sheet: &str,
) -> Result<Option<String>, VisionError> {
    let Some(turn) = vision_math::image_turn(readings, noise) else { return Ok(None) };
    let (deg, sigma_deg) = (turn.angle.to_degrees(), turn.sigma.to_degrees());
    if deg.abs() <= 4.0 * sigma_deg || deg.abs() <= TURN_WARN_DEG {
        return Ok(None);
    }
    let seen = format!(
        "as the camera moved, the mark moved {deg:+.1}° (± {sigma_deg:.1}°) off the way K says it should (the camera \
         turned or mirrored on its mount)"
    );
    if deg.abs() > TURN_REFUSE_DEG {
        Err(VisionError::CalibrationChanged {
            what: "the camera's orientation",
            detail: seen,
            fix: format!("check the camera's mount, or run {sheet} to calibrate it as it is"),
        })
    } else {
        Ok(Some(format!(
            "{seen} since M283 calibrated K; captures off the image centre carry that turn — check the mount or \
             run {sheet}"
        )))
    }
}

/// Writes `(address, value)` pairs; on failure restores the ones already written.
fn write_pounds(machine: &mut dyn Machine, writes: &[(u32, f64)]) -> Result<(), VisionError> {
    let mut before = Vec::with_capacity(writes.len());
    for (addr, _) in writes {
        before.push((*addr, machine.pound(*addr)?));
    }
    for (i, (addr, value)) in writes.iter().enumerate() {
        if let Err(e) = machine.set_pound(*addr, *value) {
            for (a, v) in before[..i].iter().rev() {
                let _ = machine.set_pound(*a, *v);
            }
            return Err(e.into());
        }
    }
    Ok(())
}
