//! `run --panel`: the operator panel (`vision-panel`) served while the run goes on. The run's
//! camera driver is wrapped so that each trigger publishes what it saw (the frame it searched,
//! for a camera that has one, and the located mark); after each Vision M-code the run publishes
//! the telemetry and calibration, and after a fit or sheet calibration its picture (the one
//! `--report` writes). Publishing never waits on a browser; the panel ends with the process.

use std::net::SocketAddr;
use std::path::Path;
use std::sync::{Arc, Mutex, PoisonError};

use vision_core::{CameraDriver, DriverError, Params, Reading, Telemetry};
use vision_driver_camera::Frame;
use vision_host::Record;
use vision_panel::{Fit, Mark, Panel, PanelHandle, View};

use super::report::{step, Step};
use super::{pictures, CameraWrap, RunArgs};
use crate::hooked::Hooked;
use crate::picture::svg;
use crate::Failure;

/// The parameter the page's click suggests a value for.
const DIAMETER_PARAM: &str = "VisionCameraMarkDiameterPx";

/// The panel a run serves, and the view it shows: the last capture and the last fit.
pub(crate) struct RunPanel {
    /// Keeps the server up for the run.
    _panel: Panel,
    shared: Shared,
}

#[derive(Clone)]
struct Shared {
    handle: PanelHandle,
    view: Arc<Mutex<View>>,
}

impl Shared {
    /// Changes the view with `change` and publishes it whole (the lock is not held while
    /// publishing).
    fn update(&self, change: impl FnOnce(&mut View)) {
        let mut view = self.view.lock().unwrap_or_else(PoisonError::into_inner);
        change(&mut view);
        let copy = view.clone();
        drop(view);
        self.handle.publish(copy);
    }
}

impl RunPanel {
    /// The panel `args` ask for (`--panel`, `--panel-token`), serving; its address is printed
    /// on standard error (`panel at http://…`). `None` without `--panel`.
    ///
    /// # Errors
    /// [`Failure::Input`] for a token without `--panel`, an address other than loopback without
    /// a token, a bad token or an address that cannot be bound.
    pub(crate) fn start(args: &RunArgs) -> Result<Option<RunPanel>, Failure> {
        let Some(addr) = args.panel else {
            return match args.panel_token {
                Some(_) => Err(Failure::Input("--panel-token needs --panel ADDRESS:PORT".into())),
                None => Ok(None),
            };
        };
        let panel = bind(addr, args.panel_token.as_deref())?;
        let page = match &args.panel_token {
            Some(t) => format!("{}?token={t}", panel.url()),
            None => panel.url(),
        };
        crate::terminal::show(&format!("panel at {page} (until the run ends)"));
        let shared = Shared { handle: panel.handle(), view: Arc::new(Mutex::new(View::default())) };
        Ok(Some(RunPanel { _panel: panel, shared }))
    }

    /// The wrapper that makes each camera driver the run builds publish its triggers.
    pub(crate) fn wrap(&self) -> CameraWrap {
        let shared = self.shared.clone();
        Box::new(move |inner| {
            let shared = shared.clone();
            Box::new(Hooked::after(inner, Box::new(move |driver, result| publish(&shared, driver, result))))
        })
    }

    /// Names the camera on the page (the report's description of it).
    pub(crate) fn set_source(&self, camera: &str) {
        self.shared.view.lock().unwrap_or_else(PoisonError::into_inner).source = format!("run: {camera}");
    }

    /// After a Vision M-code of `program` (its `records` so far, the last one this M-code's):
    /// publishes the telemetry and calibration, and the fit or calibration it made.
    pub(crate) fn after_mcode(
        &self,
        program: &str,
        records: &[Record],
        params: &Params,
        telemetry: &Telemetry,
        world_unit: &str,
    ) {
        let fit = records.last().and_then(|r| fit(program, records, r, params, world_unit));
        let plain = |name: &str| match params.get(name).ok()? {
            vision_core::ParamValue::Text(t) => Some(t),
            other => Some(other.to_string()),
        };
        let date = plain("VisionCal_Date").filter(|d| !d.is_empty());
        self.shared.update(|view| {
            // A calibration not seen before (another date) heads the history.
            if let Some(date) = date.filter(|d| view.history.first().is_none_or(|(seen, _)| seen != d)) {
                view.history.insert(0, (date, vision_panel::calibration_line(&plain)));
            }
            view.params = vision_panel::calibration(params);
            if let Ok(d) = params.get(DIAMETER_PARAM) {
                view.params.push((DIAMETER_PARAM.to_string(), d.to_string()));
            }
            view.telemetry = pairs(telemetry);
            if fit.is_some() {
                view.fit = fit;
            }
        });
    }
}

fn bind(addr: SocketAddr, token: Option<&str>) -> Result<Panel, Failure> {
    Panel::bind(addr, token).map_err(|e| Failure::Input(format!("--panel: {e}")))
}

/// The telemetry as the page's name–value rows (its JSON fields, in order).
fn pairs(telemetry: &Telemetry) -> Vec<(String, String)> {
    let Ok(serde_json::Value::Object(fields)) = serde_json::to_value(telemetry) else { return Vec::new() };
    fields
        .into_iter()
        .map(|(name, value)| {
            let text = match value {
                serde_json::Value::String(s) => s,
                serde_json::Value::Null => "—".to_string(),
                other => other.to_string(),
            };
            (name, text)
        })
        .collect()
}

/// The fit or calibration record `last` made, as the page shows it; `None` for another M-code.
fn fit(program: &str, records: &[Record], last: &Record, params: &Params, world_unit: &str) -> Option<Fit> {
    let path = Path::new(program);
    let name = path.file_name().map_or_else(|| program.to_string(), |s| s.to_string_lossy().into_owned());
    match step(last, None) {
        Step::Fit { gcode, .. } => Some(Fit { gcode, ..picture(&name, path, records, world_unit)? }),
        Step::SheetCalibration { .. } => picture(&name, path, records, world_unit),
        Step::QuickCalibration { line, report } => Some(Fit {
            title: format!("{name}: M283 quick calibration, line {line}"),
            line,
            lines: vec![format!(
                "K = [{:.8} {:.8}; {:.8} {:.8}] {}/px",
                report.k[(0, 0)],
                report.k[(0, 1)],
                report.k[(1, 0)],
                report.k[(1, 1)],
                report.unit.short_name()
            )],
            unit: params.cal_units().short_name().to_string(),
            ..Fit::default()
        }),
        _ => None,
    }
}

/// The last picture `--report` would draw of `records`: the fit or sheet calibration just made.
fn picture(name: &str, path: &Path, records: &[Record], world_unit: &str) -> Option<Fit> {
    let stem = path.file_stem().map_or_else(|| "program".into(), |s| s.to_string_lossy().into_owned());
    let steps: Vec<Step> = records.iter().map(|r| step(r, None)).collect();
    let mut sheets = Vec::new();
    pictures::program(&mut sheets, &stem, name, &steps, world_unit);
    let (_, sheet) = sheets.pop()?;
    let line = records.last().map_or(0, |r| r.line);
    Some(Fit {
        title: sheet.title.clone(),
        line,
        lines: sheet.lines.clone(),
        bound99: sheet.band,
        unit: sheet.unit.to_string(),
        gcode: Vec::new(),
        svg: Some(Arc::new(svg(&sheet))),
    })
}

/// The capture `result` as the page shows it: the frame the driver searched (none for a
/// camera that sends only positions: then the reading alone) and the mark, or why none.
fn publish(shared: &Shared, driver: &dyn CameraDriver, result: &Result<Reading, DriverError>) {
    let frame = driver.last_frame().and_then(|f| f.downcast_ref::<Frame>()).map(|f| Arc::new(f.clone()));
    let miss = driver.miss_reason();
    let spec = driver.mark_spec();
    shared.update(|view| {
        view.offset_px = None;
        view.mark = None;
        view.why_ng = None;
        match result {
            Ok(r) if r.found() => {
                // The driver's native pixels (corner origin) → locate's pixel centres.
                view.mark = Some(Mark { x: r.x_px - 0.5, y: r.y_px - 0.5, diameter: r.width_px, score: r.score });
                view.offset_px =
                    frame.as_ref().map(|f| (r.x_px - f64::from(f.width()) / 2.0, r.y_px - f64::from(f.height()) / 2.0));
            }
            Ok(_) => view.why_ng = Some(miss.unwrap_or_else(|| "no mark".to_string())),
            Err(e) => view.why_ng = Some(format!("the camera: {e}")),
        }
        view.frame = frame;
        view.offset_machine = None;
        view.spec = None;
        view.search_radius_px = None;
        if let Some(spec) = spec {
            view.why_ng = view.why_ng.take().map(|w| format!("{w} (searched for: {spec})"));
        }
    });
}
