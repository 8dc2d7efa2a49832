//! M281: capture one mark.

use vision_math::{LengthUnit, Point2, ScaleEvidence, Vector2};

use super::capture::{mark_size, observe, outside_image_note, pixel_chain, require_mark, Capture, Recentred};
use super::height::{self, NextMove};
use super::{Dot, Reply, VisionModule};
use crate::calibrate::{absolute_move, relative_move};
use crate::driver::{ImageRequest, Reading};
use crate::error::VisionError;
use crate::machine::{checked, Machine, Timestamp};
use crate::pound::{PoundBlock, SlotValues, SLOTS};

impl VisionModule {
    /// **M281**: triggers at the current commanded position and stores the observed point.
    ///
    /// Moves (re-centring and probes, issue 28): a mark read off the image centre carries K's
    /// error at the part's height times its distance from the centre. After each reading M281
    /// decides from the error budget whether to move (`VisionRecenterTolerance` 0, the
    /// default): it moves when the scale's 1σ the run has measured so far (6 % before any
    /// move) times the distance of the reading nearest the centre exceeds 0.3 × the camera's
    /// noise (`VisionCameraNoisePx`). It then moves the camera over that reading (re-centring)
    /// or, when the mark is closer to the centre than a quarter of `VisionHeightProbePx` and not yet
    /// probed, so that the mark lands `VisionHeightProbePx` on the far side (a probe: a long
    /// baseline for the scale). Each move is an incremental `G91 G0`, then `G90`, a settle of
    /// `VisionTriggerSettleSec` and a trigger, at most `VisionRecenterPasses` times (0 reads in
    /// one shot); `VisionRecenterTolerance` > 0 is issue 25's fixed rule instead (re-centre
    /// while farther than it, no probes). The capture is the reading nearest the image centre;
    /// every reading of the mark inside the image measures the image scale at the part's
    /// height ([`vision_math::scale`]), which the run collects for M282. `commanded` stays
    /// where the program put the camera, and the reply lists the moves.
    /// After the last reading the camera moves back to where the program put it, and the
    /// program's modal state, saved before the first move, is restored
    /// ([`Machine::save_modal_state`]), on success and failure alike: the program goes on from
    /// its own point in the modes it had (a feed move stays a feed move). Only a reading inside the image is
    /// moved from, so a move never exceeds the field of view. A controller may forbid moving
    /// ([`crate::Controller::may_recentre`]: LinuxCNC triggers after waiting for the machine,
    /// after which a remap may not queue G-code); M281 then reads in one shot.
    ///
    /// `O = C + K·R·(p − res/2 − PxCenterOffset)` with K converted from `Cal_Units` to the
    /// machine's unit; with an alignment active, `O` is reported in the program frame (SPEC §2).
    /// In a run the capture is appended to the dot list, written to slot `n` (n = 1–4, the n-th
    /// capture; later captures only feed the fit) and mirrored to slot 0, and `Run_DotCount`
    /// grows; outside a run only slot 0 and the telemetry are written. Every success writes the
    /// `Last*` telemetry with `LastStatus` = `OK`.
    ///
    /// `keep_image` (D1): when the driver advertises `grab_image`, it keeps the image of the
    /// reading reported in the images folder ([`crate::CameraDriver::grab_image`]); no image
    /// is a warning in `LastStatus` (`OK (warning: …)`) and [`Capture::warning`], not a failed
    /// capture.
    ///
    /// # Errors
    /// [`VisionError::NotEnabled`], [`VisionError::WrongTool`],
    /// [`VisionError::PoundBaseReserved`], [`VisionError::PoundBlockMissing`],
    /// [`VisionError::NotCalibrated`] (all before the trigger: only `LastStatus` changes);
    /// [`VisionError::NoDriver`]; after a trigger [`VisionError::Driver`] or
    /// [`VisionError::NoMark`] (`LastJudgment` and `LastStatus` record the failed trigger and the
    /// other `Last*` values are cleared); [`VisionError::Machine`] for a refused re-centring move
    /// (a camera that re-centred stays where it moved); a failed pound-variable write (the
    /// variables already written are restored). The dot list, the slots and `Run_DotCount`
    /// change only on success.
    pub fn m281(&mut self, machine: &mut dyn Machine, keep_image: bool) -> Result<Reply<Capture>, VisionError> {
        let ready = self.check_enabled().and_then(|()| self.check_tool(machine)).and_then(|()| {
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
        let reading = self.trigger_mark()?;
        let native = Point2::new(reading.x_px, reading.y_px);
        let (commanded, observed) = self.observe(machine, alignment, chain.delta(native))?;
        let first_px = chain.centred(native);
        // Every reading of this mark: the camera's position and the offset read from it
        // (program frame), the evidence of the image scale at the part's height.
        let noise = height::noise_px(&self.params) * chain.k().singular_values().max();
        let mut readings = vec![(commanded, observed - commanded)];
        // The capture is the reading nearest the image centre: a scale error of K acts on
        // the offset it read.
        let mut best = Kept { time: trigger_time, reading, native, observed, camera: commanded };
        let mut mark_scale = ScaleEvidence::default();
        let (mut passes, mut probed) = (0, false);
        let max_passes = if machine.controller().may_recentre() { self.params.recenter_passes() } else { 0 };
        // The program's modal state is saved before the first move and put back after the
        // last, whatever happens in between: a feed move after M281 stays a feed move.
        let mut saved = false;
        let mut failure = None;
        let mut gcode = Vec::new();
        // A reading outside the image is no distance to move by (a wrong resolution or K):
        // every move stays within the field of view.
        while passes < max_passes && outside_image_note(&self.params, best.native).is_none() {
            let sigma = self.run.scale.merged(mark_scale).estimate().map(|e| e.sigma);
            let step = height::next_move(&self.params, chain.centred(best.native).norm(), sigma, probed);
            let target = match step {
                NextMove::Stay => break,
                NextMove::Recentre => best.observed,
                NextMove::Probe => {
                    // The mark lands `VisionHeightProbePx` on the far side of the centre.
                    let reach = best.observed - best.camera;
                    let away = if reach.norm() > 0.0 { reach / reach.norm() } else { Vector2::x() };
                    probed = true;
                    best.observed + away * (self.params.height_probe_px() * chain.k().singular_values().max())
                }
            };
            if !saved {
                if let Err(e) = machine.save_modal_state() {
                    failure = Some(VisionError::from(e));
                    break;
                }
                saved = true;
            }
            match self.recentre_pass(machine, &chain, target, alignment) {
                Ok(pass) => {
                    gcode.extend(pass.lines);
                    let inside = outside_image_note(&self.params, pass.native).is_none();
                    if inside {
                        readings.push((pass.camera, pass.observed - pass.camera));
                        // One regression over all of the mark's readings (recomputed whole);
                        // a refused one (a non-finite noise from a broken K) adds nothing.
                        let mut fresh = ScaleEvidence::default();
                        if fresh.add_mark(&readings, noise).is_ok() {
                            mark_scale = fresh;
                        }
                    }
                    if inside && chain.centred(pass.native).norm() <= chain.centred(best.native).norm() {
                        best = Kept {
                            time: pass.time,
                            reading: pass.reading,
                            native: pass.native,
                            observed: pass.observed,
                            camera: pass.camera,
                        };
                    }
                }
                Err(e) => {
                    failure = Some(e);
                    break;
                }
            }
            passes += 1;
        }
        if passes > 0 && failure.is_none() {
            // Back where the program put the camera: the program goes on from its own point.
            let lines = vec![absolute_move(commanded)];
            match machine.run_gcode(&lines).map(|()| lines) {
                Ok(lines) => gcode.extend(lines),
                Err(e) => failure = Some(e.into()),
            }
        }
        if saved {
            if let Err(e) = machine.restore_modal_state() {
                failure.get_or_insert(VisionError::from(e));
            }
        }
        if let Some(e) = failure {
            self.publish_failure(None, &e);
            return Err(e);
        }
        let Kept { time: trigger_time, reading, native, observed, camera } = best;
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
            self.run.dots.push(Dot { commanded, observed, unit, reach: observed - camera, mark_size });
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
    /// no driver in `LastStatus`.
    fn trigger_mark(&mut self) -> Result<crate::driver::Reading, VisionError> {
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
        if let Err(e) = require_mark(&reading) {
            self.publish_failure(Some(i64::from(reading.judgment.code())), &e);
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

/// One pass: the move to a target point (over the mark, or a probe beside it), and the
/// reading there.
struct Pass {
    lines: Vec<String>,
    time: Timestamp,
    reading: Reading,
    native: Point2<f64>,
    observed: Point2<f64>,
    /// The camera's position at the reading, program frame.
    camera: Point2<f64>,
}

/// The reading M281 keeps as its capture: the one nearest the image centre.
struct Kept {
    time: Timestamp,
    reading: Reading,
    native: Point2<f64>,
    observed: Point2<f64>,
    /// The camera's position at the reading, program frame.
    camera: Point2<f64>,
}

impl VisionModule {
    /// Moves the camera to `target` (program frame), settles, triggers and observes again.
    fn recentre_pass(
        &mut self,
        machine: &mut dyn Machine,
        chain: &vision_math::PixelChain,
        target: Point2<f64>,
        alignment: Option<vision_math::AlignmentChain>,
    ) -> Result<Pass, VisionError> {
        let lines = relative_move(target - checked::program_position(machine)?);
        machine.run_gcode(&lines)?;
        machine.dwell(self.params.trigger_settle_s())?;
        // M281 D1 keeps the image of the reading reported.
        let time = machine.now();
        let reading = self.trigger_mark()?;
        let native = Point2::new(reading.x_px, reading.y_px);
        let (camera, observed) = observe(machine, alignment, chain.delta(native))?;
        Ok(Pass { lines, time, reading, native, observed, camera })
    }

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
