//! [`Publisher`]: a session's state written into its panel folder by a thread of its own.
//!
//! Decision: the controller's thread only copies the state into a slot (a lock held for a copy,
//! never for I/O) and wakes the writer; the writer takes the newest state and writes it (temp
//! file in the folder, then rename). States that arrive while it writes are merged into the
//! next write, so a slow disk costs updates, never the controller's time. At the end of an
//! M-code the session gives the writer [`SETTLE`] to catch up ([`Publisher::settle`]), so the
//! folder shows the call before the program goes on (or the controller exits); a writer that
//! misses it once is never waited on again.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use vision_core::{Dot, ParamValue, Telemetry, TelemetrySink, VisionModule};
use vision_math::LengthUnit;
use vision_mcode::Outcome;

use super::state::{
    self, LastCall, PanelCalibration, PanelDot, PanelState, PanelUnit, PanelValue, CALIBRATION_PARAMS, FRAME_FILE,
    MAX_CALIBRATIONS, STATE_FILE,
};

/// The most run captures a state lists.
pub const MAX_DOTS: usize = 1000;

/// How long dropping a publisher waits for its last write, at most (a session is dropped when a
/// bridge reopens it or the controller exits).
const DROP_WAIT: Duration = Duration::from_millis(250);

/// The most an M-code's end waits for the writer ([`Publisher::settle`]); a write of the
/// state takes well under a millisecond on a local disk.
pub const SETTLE: Duration = Duration::from_millis(50);

/// How many times a file's replacement is tried, [`RENAME_PAUSE`] apart.
const RENAME_TRIES: u32 = 20;

/// The pause between two tries of a replacement.
const RENAME_PAUSE: Duration = Duration::from_millis(10);

/// What the next write takes: the newest of everything the session handed over.
#[derive(Default)]
struct Snapshot {
    params: Vec<(&'static str, ParamValue)>,
    telemetry: Telemetry,
    last: Option<(u32, Result<Outcome, String>)>,
    dots: Vec<Dot>,
    /// The last image M281 kept, to copy to `frame.png` (PNG; JPEG and BMP re-encoded).
    image: Option<PathBuf>,
}

/// The slot between the session and the writer.
#[derive(Default)]
struct Slot {
    snapshot: Snapshot,
    /// The sequence number of the newest state handed over.
    submitted: u64,
    /// The sequence number of the newest state written (or failed).
    written: u64,
    stop: bool,
    /// The first write failure, until the session takes it; then `reported`.
    problem: Option<String>,
    reported: bool,
    /// The calibrations seen, oldest first (carried on from the folder's last state).
    history: Vec<PanelCalibration>,
}

struct Shared {
    slot: Mutex<Slot>,
    wake: Condvar,
}

impl Shared {
    /// The slot; a poisoned lock (a panic in another holder) still holds plain data.
    fn lock(&self) -> MutexGuard<'_, Slot> {
        self.slot.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// Applies `edit` to the snapshot as a new state and wakes the writer.
    fn submit(&self, edit: impl FnOnce(&mut Snapshot)) {
        let mut slot = self.lock();
        edit(&mut slot.snapshot);
        slot.submitted += 1;
        drop(slot);
        self.wake.notify_all();
    }
}

/// Writes a session's state into its panel folder (`state.json`, `frame.png`) from a thread of
/// its own; see the module's decision. Dropping it waits up to 250 ms for the last write.
pub struct Publisher {
    shared: Arc<Shared>,
    dir: PathBuf,
    /// Set when a [`Publisher::settle`] ran out of time: never wait again.
    slow: std::sync::atomic::AtomicBool,
}

impl std::fmt::Debug for Publisher {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Publisher").field("dir", &self.dir).finish_non_exhaustive()
    }
}

impl Publisher {
    /// A publisher writing into `dir` (created when missing) for the session of `profile`.
    /// Sequence numbers go on from the folder's last state. A folder that cannot be written,
    /// or a writer thread that cannot start, is a [`Publisher::take_problem`], not an error.
    #[must_use]
    pub fn start(dir: PathBuf, profile: &Path) -> Publisher {
        let (seq, history) = state::read(&dir).map_or((0, Vec::new()), |s| (s.seq, s.calibrations));
        let slot = Slot { submitted: seq, written: seq, history, ..Slot::default() };
        let shared = Arc::new(Shared { slot: Mutex::new(slot), wake: Condvar::new() });
        let writer = Writer { shared: Arc::clone(&shared), dir: dir.clone(), profile: profile.display().to_string() };
        let spawned = std::thread::Builder::new().name("vision-panel".to_string()).spawn(move || writer.run());
        if let Err(e) = spawned {
            let mut slot = shared.lock();
            slot.stop = true;
            slot.problem = Some(format!("the panel's writer thread did not start: {e}"));
        }
        Publisher { shared, dir, slow: std::sync::atomic::AtomicBool::new(false) }
    }

    /// The panel folder.
    #[must_use]
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// A telemetry sink for the module: each write of the telemetry becomes a new state.
    #[must_use]
    pub fn sink(&self) -> TelemetrySink {
        let shared = Arc::clone(&self.shared);
        Box::new(move |t: &Telemetry| shared.submit(|s| s.telemetry = t.clone()))
    }

    /// A new state from `module` (its parameters, telemetry and run captures) after a call,
    /// with the call's result (M-code `mcode`; the refusal's message on failure), if any.
    pub fn record(&self, module: &VisionModule, call: Option<(u32, Result<Outcome, String>)>) {
        let params = module.params().config_values();
        let telemetry = module.telemetry().clone();
        let dots = module.dots().iter().take(MAX_DOTS).copied().collect();
        self.shared.submit(|s| {
            s.params = params;
            s.telemetry = telemetry;
            s.dots = dots;
            if let Some((mcode, result)) = call {
                if let Ok(Outcome::Capture(reply)) = &result {
                    if let Some(image) = &reply.report.image {
                        s.image = Some(image.clone());
                    }
                }
                s.last = Some((mcode, result));
            }
        });
    }

    /// The first write failure, once (later calls answer `None`): for the operator's message.
    pub fn take_problem(&self) -> Option<String> {
        let mut slot = self.shared.lock();
        if slot.reported {
            return None;
        }
        let problem = slot.problem.take();
        slot.reported = problem.is_some();
        problem
    }

    /// Waits up to [`SETTLE`] for the writer, at an M-code's end; once that runs out, not
    /// again until the writer has caught up by itself (a slow or stuck disk then costs the
    /// controller nothing, and one busy moment does not leave the folder behind for good).
    pub fn settle(&self) {
        use std::sync::atomic::Ordering;
        if self.slow.load(Ordering::Relaxed) {
            if self.flush(Duration::ZERO) {
                self.slow.store(false, Ordering::Relaxed);
            }
        } else if !self.flush(SETTLE) {
            self.slow.store(true, Ordering::Relaxed);
        }
    }

    /// Waits up to `timeout` until every state handed over is written (or failed); true when
    /// it was.
    pub fn flush(&self, timeout: Duration) -> bool {
        let deadline = Instant::now() + timeout;
        let mut slot = self.shared.lock();
        while slot.written < slot.submitted && !slot.stop {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return false;
            }
            slot = self.shared.wake.wait_timeout(slot, left).map_or_else(|e| e.into_inner().0, |(s, _)| s);
        }
        slot.written >= slot.submitted
    }
}

impl Drop for Publisher {
    fn drop(&mut self) {
        self.flush(DROP_WAIT);
        self.shared.lock().stop = true;
        self.shared.wake.notify_all();
    }
}

/// The writer thread's side.
struct Writer {
    shared: Arc<Shared>,
    dir: PathBuf,
    profile: String,
}

impl Writer {
    fn run(self) {
        let mut framed: Option<PathBuf> = None;
        loop {
            let (seq, state, image) = {
                let mut slot = self.shared.lock();
                while slot.written == slot.submitted && !slot.stop {
                    slot = self.shared.wake.wait(slot).unwrap_or_else(std::sync::PoisonError::into_inner);
                }
                if slot.written == slot.submitted {
                    return;
                }
                let seq = slot.submitted;
                let image = slot.snapshot.image.clone().filter(|i| framed.as_ref() != Some(i));
                let slot = &mut *slot;
                note_calibration(&mut slot.history, &slot.snapshot.params);
                let state = PanelState { calibrations: slot.history.clone(), ..self.state(&slot.snapshot, seq) };
                (seq, state, image)
            };
            let mut result = std::fs::create_dir_all(&self.dir).map_err(|e| e.to_string());
            if let (Ok(()), Some(image)) = (&result, &image) {
                result = self.copy_frame(image).map(|copied| {
                    if copied {
                        framed = Some(image.clone());
                    }
                });
            }
            let state = PanelState { frame: framed.as_ref().map(|_| FRAME_FILE.to_string()), ..state };
            if result.is_ok() {
                result = serde_json::to_vec_pretty(&state)
                    .map_err(|e| e.to_string())
                    .and_then(|json| self.replace(STATE_FILE, &json));
            }
            let mut slot = self.shared.lock();
            slot.written = seq;
            if let Err(e) = result {
                if slot.problem.is_none() && !slot.reported {
                    slot.problem = Some(format!("the panel folder {} cannot be written: {e}", self.dir.display()));
                }
            }
            drop(slot);
            self.shared.wake.notify_all();
        }
    }

    /// The state of `snapshot` as sequence number `seq` (no frame yet).
    fn state(&self, snapshot: &Snapshot, seq: u64) -> PanelState {
        let telemetry = Telemetry::SPECS.iter().filter_map(|s| {
            let value = snapshot.telemetry.get(s.name)?;
            Some((s.name.to_string(), PanelValue::from(value)))
        });
        PanelState {
            format: state::FORMAT,
            seq,
            time_unix: SystemTime::now().duration_since(UNIX_EPOCH).map_or(0.0, |d| d.as_secs_f64()),
            profile: self.profile.clone(),
            params: snapshot.params.iter().map(|(k, v)| ((*k).to_string(), PanelValue::from(v.clone()))).collect(),
            telemetry: telemetry.collect(),
            last: snapshot.last.as_ref().map(|(mcode, result)| last_call(*mcode, result)),
            dots: snapshot.dots.iter().filter_map(panel_dot).collect(),
            frame: None,
            calibrations: Vec::new(),
        }
    }

    /// Copies `image` to `frame.png` (re-encoded when it is not a PNG); `Ok(false)` for a file
    /// that is no image the panel reads (left out).
    fn copy_frame(&self, image: &Path) -> Result<bool, String> {
        match frame_png(image)? {
            Some(bytes) => self.replace(FRAME_FILE, &bytes).map(|()| true),
            None => Ok(false),
        }
    }

    /// Writes `bytes` to `name` in the folder atomically: a temp file beside it, then a rename.
    /// The rename is tried [`RENAME_TRIES`] times: Windows refuses to replace a file a reader
    /// (the panel) has open at that moment.
    fn replace(&self, name: &str, bytes: &[u8]) -> Result<(), String> {
        let temp = self.dir.join(format!(".{name}.{}.tmp", std::process::id()));
        let target = self.dir.join(name);
        let rename = || {
            let mut result = std::fs::rename(&temp, &target);
            for _ in 1..RENAME_TRIES {
                if result.is_ok() {
                    break;
                }
                std::thread::sleep(RENAME_PAUSE);
                result = std::fs::rename(&temp, &target);
            }
            result
        };
        std::fs::write(&temp, bytes).and_then(|()| rename()).map_err(|e| {
            let _ = std::fs::remove_file(&temp);
            format!("{}: {e}", target.display())
        })
    }
}

/// The call as the panel lists it.
fn last_call(mcode: u32, result: &Result<Outcome, String>) -> LastCall {
    match result {
        Ok(outcome) => LastCall {
            mcode,
            ok: true,
            message: crate::session::summary(outcome),
            gcode: outcome.gcode().to_vec(),
            report: report(outcome),
        },
        Err(message) => LastCall { mcode, ok: false, message: message.clone(), gcode: Vec::new(), report: None },
    }
}

/// The call's report as `run --json` writes it.
fn report(outcome: &Outcome) -> Option<serde_json::Value> {
    let value = match outcome {
        Outcome::Begin(r) => serde_json::to_value(r.report),
        Outcome::Capture(r) => serde_json::to_value(&r.report),
        Outcome::Apply(r) => serde_json::to_value(&r.report),
        Outcome::Calibrate(r) => serde_json::to_value(&r.report),
        Outcome::SelectJob(r) => serde_json::to_value(r.report),
    };
    value.ok()
}

/// The capture as the panel lists it; `None` for a non-finite one (JSON has no such number).
fn panel_dot(d: &Dot) -> Option<PanelDot> {
    let finite = [d.commanded.x, d.commanded.y, d.observed.x, d.observed.y].iter().all(|x| x.is_finite());
    finite.then(|| PanelDot {
        commanded: [d.commanded.x, d.commanded.y],
        observed: [d.observed.x, d.observed.y],
        unit: match d.unit {
            LengthUnit::Inch => PanelUnit::Inch,
            LengthUnit::Millimetre => PanelUnit::Millimetre,
        },
    })
}

/// Adds the calibration `params` hold to `history` when it is a new one (another
/// `VisionCal_Date`; none before the first M283), keeping the last [`MAX_CALIBRATIONS`].
fn note_calibration(history: &mut Vec<PanelCalibration>, params: &[(&'static str, ParamValue)]) {
    let date = match params.iter().find(|(n, _)| *n == "VisionCal_Date") {
        Some((_, ParamValue::Text(d))) if !d.is_empty() => d.clone(),
        _ => return,
    };
    if history.last().is_some_and(|c| c.date == date) {
        return;
    }
    let values = params
        .iter()
        .filter(|(n, _)| CALIBRATION_PARAMS.contains(n))
        .map(|(n, v)| ((*n).to_string(), PanelValue::from(v.clone())))
        .collect();
    history.push(PanelCalibration { date, values });
    let excess = history.len().saturating_sub(MAX_CALIBRATIONS);
    history.drain(..excess);
}

/// The largest side (pixels) of an image the panel folder takes as its frame.
pub const MAX_FRAME_SIDE: u32 = 16_384;

/// The PNG bytes of the image a camera kept at `path`: a PNG as it is, a JPEG or BMP (a
/// Keyence camera's) re-encoded; `None` for another format, or an image over
/// [`MAX_FRAME_SIDE`] a side.
///
/// # Errors
/// The file cannot be read, or is damaged.
pub fn frame_png(path: &Path) -> Result<Option<Vec<u8>>, String> {
    let failed = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let bytes = std::fs::read(path).map_err(|e| failed(&e))?;
    let format = match image::guess_format(&bytes) {
        Ok(image::ImageFormat::Png) => return Ok(Some(bytes)),
        Ok(f @ (image::ImageFormat::Jpeg | image::ImageFormat::Bmp)) => f,
        _ => return Ok(None),
    };
    let mut reader = image::ImageReader::with_format(std::io::Cursor::new(&bytes), format);
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_FRAME_SIDE);
    limits.max_image_height = Some(MAX_FRAME_SIDE);
    reader.limits(limits);
    let decoded = match reader.decode() {
        Ok(img) => img,
        Err(image::ImageError::Limits(_)) => return Ok(None),
        Err(e) => return Err(failed(&e)),
    };
    let mut png = std::io::Cursor::new(Vec::new());
    decoded.write_to(&mut png, image::ImageFormat::Png).map_err(|e| failed(&e))?;
    Ok(Some(png.into_inner()))
}
