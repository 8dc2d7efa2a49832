//! The telemetry the module writes (`Last*`, `Run_*`), and who watches it as it is written.
//!
//! Decision: telemetry is write-only for the module (it never reads a value back to decide
//! anything), so every write goes through [`Dro`], which hands the new values to the host's
//! [`TelemetrySink`] at once. A long call (M283 triggers some thirty times) then shows each
//! trigger on the DRO as it happens, as the manual's "written after every trigger" asks.

use vision_math::{PixelChain, Point2, Vector2};

use crate::driver::Reading;
use crate::error::VisionError;
use crate::params::Telemetry;

/// Receives the whole telemetry each time the module writes it during a call: after every
/// trigger (a failed one too), every `LastStatus` change and every `Run_*` update. A host
/// bridge copies it to its DROs; the module never waits on it.
pub type TelemetrySink = Box<dyn FnMut(&Telemetry) + Send>;

/// Where M283's walk is, handed to the host's [`ProgressSink`] as the walk reaches each stage,
/// so a long calibration (some eighty triggers) can show the operator how far it got.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum WalkProgress {
    /// The sheet walk moves to dot `dot` (1-based) of the sheet's `dots`, to centre and probe it.
    SheetDot {
        /// The dot, 1-based.
        dot: usize,
        /// The sheet's dots.
        dots: usize,
    },
    /// The lens grid over the last dot (the lens distortion) starts.
    Lens,
    /// The calibration lift over the last dot (the optical centre) starts.
    Lift,
    /// The verify pass moves to dot `dot` (1-based) of `dots`.
    Verify {
        /// The dot, 1-based.
        dot: usize,
        /// The sheet's dots.
        dots: usize,
    },
}

impl std::fmt::Display for WalkProgress {
    /// The operator's words: `M283: dot 3 of 5`, `M283: lift over the last dot`,
    /// `M283: verify dot 2 of 5`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            WalkProgress::SheetDot { dot, dots } => write!(f, "M283: dot {dot} of {dots}"),
            WalkProgress::Lens => f.write_str("M283: lens grid over the last dot (the lens distortion)"),
            WalkProgress::Lift => f.write_str("M283: lift over the last dot (the optical centre)"),
            WalkProgress::Verify { dot, dots } => write!(f, "M283: verify dot {dot} of {dots}"),
        }
    }
}

/// Receives M283's [`WalkProgress`] while the walk runs (not on a stepwise walk's replays).
pub type ProgressSink = Box<dyn FnMut(WalkProgress) + Send>;

/// The module's telemetry and its sinks.
#[derive(Default)]
pub(crate) struct Dro {
    values: Telemetry,
    sink: Option<TelemetrySink>,
    progress: Option<ProgressSink>,
}

impl std::fmt::Debug for Dro {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Dro")
            .field("values", &self.values)
            .field("sink", &self.sink.is_some())
            .field("progress", &self.progress.is_some())
            .finish()
    }
}

impl Dro {
    /// The values written so far.
    pub(crate) fn values(&self) -> &Telemetry {
        &self.values
    }

    /// Replaces the sink (`None` removes it).
    pub(crate) fn set_sink(&mut self, sink: Option<TelemetrySink>) {
        self.sink = sink;
    }

    /// Replaces the progress sink (`None` removes it).
    pub(crate) fn set_progress_sink(&mut self, sink: Option<ProgressSink>) {
        self.progress = sink;
    }

    /// Hands `progress` to the progress sink.
    pub(crate) fn progress(&mut self, progress: WalkProgress) {
        if let Some(sink) = self.progress.as_mut() {
            sink(progress);
        }
    }

    /// Applies `edit` to the values, then hands them to the sink.
    pub(crate) fn write(&mut self, edit: impl FnOnce(&mut Telemetry)) {
        edit(&mut self.values);
        if let Some(sink) = self.sink.as_mut() {
            sink(&self.values);
        }
    }

    /// A usable reading at centred pixel offset `centred` (pixels), `LastStatus` = `OK`. The
    /// offsets and size in units go through `chain`; without one (a calibration's first
    /// triggers, before any K) they are 0.
    pub(crate) fn reading(&mut self, chain: Option<&PixelChain>, centred: Vector2<f64>, reading: &Reading) {
        let native = Point2::new(reading.x_px, reading.y_px);
        let offset = chain.map_or_else(Vector2::zeros, |c| c.delta(native));
        let (width, height) = chain.map_or((0.0, 0.0), |c| super::capture::mark_size(c, reading));
        self.write(|t| {
            t.last_judgment = i64::from(reading.judgment.code());
            t.last_offset_px_x = centred.x;
            t.last_offset_px_y = centred.y;
            t.last_offset_x = offset.x;
            t.last_offset_y = offset.y;
            t.last_width = width;
            t.last_height = height;
            t.last_angle = reading.angle_deg;
            t.last_score = reading.score;
            t.last_status = "OK".to_string();
        });
    }

    /// A failed operation in `LastStatus`; for a failed trigger (`judgment` given) also
    /// `LastJudgment`, and the offsets, size, angle and score are cleared so a DRO never shows
    /// the previous mark's.
    pub(crate) fn failure(&mut self, judgment: Option<i64>, e: &VisionError) {
        self.write(|t| {
            if let Some(j) = judgment {
                t.last_judgment = j;
                t.last_offset_px_x = 0.0;
                t.last_offset_px_y = 0.0;
                t.last_offset_x = 0.0;
                t.last_offset_y = 0.0;
                t.last_width = 0.0;
                t.last_height = 0.0;
                t.last_angle = 0.0;
                t.last_score = 0.0;
            }
            t.last_status = e.to_string();
        });
    }

    /// `LastStatus` = `OK`, or `OK (warning: …)` with `warning`.
    pub(crate) fn ok(&mut self, warning: Option<&str>) {
        let status = warning.map_or_else(|| "OK".to_string(), |w| format!("OK (warning: {w})"));
        self.write(|t| t.last_status = status);
    }
}
