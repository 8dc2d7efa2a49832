//! `mach-vision panel --profile P` without `--camera`: the panel beside a real controller. It
//! shows what the controller's session published in `P.panel` (`vision_host::panel`): the
//! state is polled, and each new `seq` becomes a new view — `frame.png` searched with the
//! profile's mark settings as the live view searches a frame, the last call, why it was
//! refused, and the parameters and telemetry, read-only. A folder without a readable state
//! shows the reader's message, and the polling goes on. Nothing in the folder is written.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use vision_core::Params;
use vision_driver_camera::{CameraConfig, FileSource, FrameDriver, FrameSource};
use vision_host::panel::{self, PanelState, PanelValue, FRAME_FILE};
use vision_panel::{observe, Call, PanelHandle, View};

/// The shortest time between two reads of `state.json` (at most 5 a second).
const POLL_PERIOD: Duration = Duration::from_millis(200);

/// What the page shows now, so that only a change is published.
#[derive(Debug, PartialEq)]
enum Shown {
    Nothing,
    /// The state with this `seq`.
    State(u64),
    /// The reader's message.
    Unreadable(String),
}

/// Polls panel folder `dir` for ever, publishing to `handle`. `params` are the profile's (its
/// mark settings and K search and describe the frame).
pub(crate) fn watch(handle: &PanelHandle, dir: &Path, params: &Params) -> ! {
    let mut shown = Shown::Nothing;
    loop {
        let start = Instant::now();
        let now = match panel::read(dir) {
            Ok(state) => {
                Shown::State(state.seq).ne(&shown).then(|| (Shown::State(state.seq), view(dir, &state, params)))
            }
            Err(e) => {
                let message = e.to_string();
                let unreadable = Shown::Unreadable(message.clone());
                let view = View { why_ng: Some(message), source: dir.display().to_string(), ..View::default() };
                (unreadable != shown).then_some((unreadable, view))
            }
        };
        if let Some((next, view)) = now {
            handle.publish(view);
            shown = next;
        }
        std::thread::sleep(POLL_PERIOD.saturating_sub(start.elapsed()));
    }
}

/// The view of `state`, read from folder `dir`.
fn view(dir: &Path, state: &PanelState, params: &Params) -> View {
    let mut view = match &state.frame {
        Some(_) => searched(&dir.join(FRAME_FILE), params),
        None => View::default(),
    };
    view.source = format!("{} (state {})", dir.display(), state.seq);
    view.params = pairs(&state.params);
    view.telemetry = pairs(&state.telemetry);
    view.history = state
        .calibrations
        .iter()
        .rev()
        .map(|c| {
            let text = |name: &str| c.values.get(name).map(panel_text);
            (c.date.clone(), vision_panel::calibration_line(&text))
        })
        .collect();
    if let Some(last) = &state.last {
        if !last.ok {
            view.why_ng = Some(last.message.clone());
        }
        view.call =
            Some(Call { mcode: last.mcode, ok: last.ok, message: last.message.clone(), gcode: last.gcode.clone() });
    }
    view
}

/// `frame`, searched as the camera driver searches a frame with `params`'s mark settings; when
/// they are unusable (no mark diameter), the frame alone with the reason.
fn searched(frame: &Path, params: &Params) -> View {
    let mut params = params.clone();
    let path = PathBuf::from(frame);
    let driver = params
        .set("VisionCameraSource", frame.display().to_string().as_str())
        .map_err(|e| e.to_string())
        .and_then(|()| CameraConfig::from_params(&params).map_err(|e| e.to_string()))
        .and_then(|config| FrameDriver::new(config, FileSource::new(path.clone())).map_err(|e| e.to_string()));
    match driver {
        Ok(mut driver) => observe(&mut driver, &params),
        Err(reason) => match FileSource::new(path).frame() {
            Ok(f) => {
                View { frame: Some(Arc::new(f)), why_ng: Some(format!("not searched: {reason}")), ..View::default() }
            }
            Err(e) => View { why_ng: Some(format!("{}: {e}", frame.display())), ..View::default() },
        },
    }
}

/// The values as the page's tables show them.
fn pairs(values: &std::collections::BTreeMap<String, PanelValue>) -> Vec<(String, String)> {
    values.iter().map(|(name, v)| (name.clone(), panel_text(v))).collect()
}

/// A published value as the page shows it.
fn panel_text(v: &PanelValue) -> String {
    match v {
        PanelValue::Bool(b) => b.to_string(),
        PanelValue::Int(i) => i.to_string(),
        PanelValue::Number(x) => x.to_string(),
        PanelValue::Text(t) => t.clone(),
    }
}
