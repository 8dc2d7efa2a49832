//! M281: capture one mark.

use std::time::Duration;

use vision_math::Point2;

use super::capture::{mark_size, observe, pixel_chain, require_mark, Capture};
use super::{Dot, Reply, VisionModule};
use crate::error::VisionError;
use crate::image_grab;
use crate::machine::Machine;
use crate::pound::{PoundBlock, SlotValues, SLOTS};

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
    /// `keep_image` (D1): when `VisionImageWatchDir` is set and the driver advertises
    /// `grab_image`, the image the camera pushed for this trigger is copied into the images
    /// folder ([`crate::image_grab`]); a missing image is a warning in `LastStatus`
    /// (`OK (warning: …)`) and [`Capture::warning`], not a failed capture.
    ///
    /// # Errors
    /// [`VisionError::NotEnabled`], [`VisionError::WrongTool`],
    /// [`VisionError::PoundBaseReserved`], [`VisionError::PoundBlockMissing`],
    /// [`VisionError::NotCalibrated`] (all before the trigger: nothing changes);
    /// [`VisionError::NoDriver`]; after the trigger [`VisionError::Driver`] or
    /// [`VisionError::NoMark`] (only `LastJudgment` and `LastStatus` change, recording the failed
    /// trigger); a failed pound-variable write (the variables already written are restored). The dot list, the slots and `Run_DotCount` change only on
    /// success.
    pub fn m281(&mut self, machine: &mut dyn Machine, keep_image: bool) -> Result<Reply<Capture>, VisionError> {
        self.check_enabled()?;
        self.check_tool(machine)?;
        let block = PoundBlock::on_machine(self.params.pound_var_base(), machine)?;
        let unit = machine.units();
        let chain = pixel_chain(&self.params, unit)?;
        let trigger_time = machine.now();
        let reading = match self.driver_mut()?.trigger() {
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
        let native = Point2::new(reading.x_px, reading.y_px);
        let offset = chain.delta(native);
        let (commanded, observed) = observe(machine, offset)?;
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

        // Committed: the capture counts from here on.
        if in_run {
            self.run.dots.push(Dot { commanded, observed, unit });
            self.publish_run();
        }
        let p = &mut self.telemetry;
        let centred = chain.centred(native);
        p.last_judgment = i64::from(reading.judgment.code());
        p.last_offset_px_x = centred.x;
        p.last_offset_px_y = centred.y;
        p.last_offset_x = offset.x;
        p.last_offset_y = offset.y;
        p.last_width = width;
        p.last_height = height;
        p.last_angle = reading.angle_deg;
        p.last_score = reading.score;
        p.last_status = "OK".to_string();

        let mut image = None;
        let mut warning = None;
        if keep_image {
            let watch = self.params.image_watch_dir().to_string();
            let pushes = self.driver.as_deref().is_some_and(|d| d.capabilities().grab_image);
            if watch.is_empty() {
                warning = Some("image not saved: VisionImageWatchDir is empty".to_string());
            } else if !pushes {
                warning = Some(format!(
                    "image not saved: camera driver {} does not push images",
                    self.driver.as_deref().map_or("?", |d| d.name())
                ));
            } else {
                let timeout =
                    Duration::try_from_secs_f64(self.params.image_grab_timeout_s()).unwrap_or(Duration::from_secs(2));
                match image_grab::grab(
                    watch.as_ref(),
                    &self.images_dir,
                    trigger_time.time,
                    timeout,
                    &trigger_time.file_stamp(),
                ) {
                    Ok(path) => image = Some(path),
                    Err(reason) => warning = Some(format!("image not saved: {reason}")),
                }
            }
        }
        if let Some(note) = self.driver.as_deref().and_then(|d| d.reading_warning(&reading)) {
            warning = Some(warning.map_or_else(|| note.clone(), |w| format!("{note}; {w}")));
        }
        if let Some(w) = &warning {
            self.telemetry.last_status = format!("OK (warning: {w})");
        }
        Ok(Reply {
            gcode: Vec::new(),
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
            },
        })
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
