//! [`View`]: one look through the camera, as the page shows it — the frame, the mark the finder
//! located on it (or why none), and the parameters beside them.

use std::sync::Arc;

use serde_json::{json, Value};
use vision_driver_camera::Frame;

/// A located mark, in `mach-vision locate`'s convention: pixel-centre coordinates ((0, 0) is
/// the centre of the top-left pixel, y down).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mark {
    /// Centre x, pixels.
    pub x: f64,
    /// Centre y, pixels.
    pub y: f64,
    /// Diameter (a cross's bar length), pixels.
    pub diameter: f64,
    /// The finder's score, 0–1.
    pub score: f64,
}

/// The last Vision M-code a controller's session ran, as its panel folder tells it.
#[derive(Debug, Clone, PartialEq)]
pub struct Call {
    /// The M number (280–284).
    pub mcode: u32,
    /// Whether it succeeded.
    pub ok: bool,
    /// The status line on success, the refusal's message otherwise.
    pub message: String,
    /// The G-code lines it ran (a record).
    pub gcode: Vec<String>,
}

/// What the finder searched for, as `mach-vision locate`'s options say it.
#[derive(Debug, Clone, PartialEq)]
pub struct Spec {
    /// `dot`, `ring` or `cross`.
    pub kind: String,
    /// `dark` or `light`.
    pub polarity: String,
    /// Expected diameter, pixels.
    pub diameter_px: f64,
    /// Accepted size deviation, percent.
    pub tolerance_pct: f64,
}

/// The mark's offset from the camera position in machine units (through K).
#[derive(Debug, Clone, PartialEq)]
pub struct MachineOffset {
    /// X, `unit`.
    pub x: f64,
    /// Y, `unit`.
    pub y: f64,
    /// The unit's short name (`in`, `mm`).
    pub unit: String,
}

/// The last fit or calibration of a run, as its report shows it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Fit {
    /// What it was (`M282 rectangle fit, line 20`).
    pub title: String,
    /// The program line of the M-code.
    pub line: u32,
    /// The figures under the title: transform, RMS, predicted error, K.
    pub lines: Vec<String>,
    /// The predicted 99 % bound of the error over the part, `unit`; `None` for a calibration.
    pub bound99: Option<f64>,
    /// The unit's short name (`in`, `mm`).
    pub unit: String,
    /// The G-code the fit emitted (none for a calibration).
    pub gcode: Vec<String>,
    /// The picture: marks with their residual arrows magnified by the factor its legend states
    /// (SVG, served as `/fit.svg`).
    pub svg: Option<Arc<String>>,
}

/// One look through the camera. Built by [`crate::observe`] for a live camera, or by any
/// publisher (a run) from what it has; [`crate::PanelHandle::publish`] hands it to the page.
#[derive(Debug, Clone, Default)]
pub struct View {
    /// The frame searched; `None` when the camera gave none.
    pub frame: Option<Arc<Frame>>,
    /// The mark located on it.
    pub mark: Option<Mark>,
    /// Why there is no mark (the finder's reason) or no frame (the camera's error).
    pub why_ng: Option<String>,
    /// A controller's last call (`None` for a camera's live view).
    pub call: Option<Call>,
    /// What was searched for.
    pub spec: Option<Spec>,
    /// The search radius about the image centre, pixels; `None`: the whole frame.
    pub search_radius_px: Option<f64>,
    /// The mark's offset from the image centre, pixels (x right, y down).
    pub offset_px: Option<(f64, f64)>,
    /// The mark's offset from the camera position, machine units; `None` without K.
    pub offset_machine: Option<MachineOffset>,
    /// Where the frames come from.
    pub source: String,
    /// Parameters shown read-only, name and value.
    pub params: Vec<(String, String)>,
    /// Telemetry shown read-only, name and value (a run's; empty otherwise).
    pub telemetry: Vec<(String, String)>,
    /// A run's last fit or calibration.
    pub fit: Option<Fit>,
    /// The calibrations seen, newest first: the date and K, the camera tool's offset and the
    /// pixel centre, as one line each.
    pub history: Vec<(String, String)>,
}

impl View {
    /// The JSON the page reads (`/state.json` and each event), numbered `seq`.
    #[must_use]
    pub fn to_json(&self, seq: u64) -> Value {
        let finite = |v: f64| if v.is_finite() { json!(v) } else { Value::Null };
        let pairs = |list: &[(String, String)]| Value::Array(list.iter().map(|(n, v)| json!([n, v])).collect());
        json!({
            "seq": seq,
            "width": self.frame.as_ref().map(|f| f.width()),
            "height": self.frame.as_ref().map(|f| f.height()),
            "found": self.mark.is_some(),
            "mark": self.mark.map(|m| json!({
                "x": finite(m.x), "y": finite(m.y), "diameter": finite(m.diameter), "score": finite(m.score),
            })),
            "why_ng": self.why_ng,
            "call": self.call.as_ref().map(|c| json!({
                "mcode": c.mcode, "ok": c.ok, "message": c.message, "gcode": c.gcode,
            })),
            "spec": self.spec.as_ref().map(|s| json!({
                "kind": s.kind, "polarity": s.polarity,
                "diameter_px": finite(s.diameter_px), "tolerance_pct": finite(s.tolerance_pct),
            })),
            "search_radius_px": self.search_radius_px.map(finite),
            "offset_px": self.offset_px.map(|(x, y)| json!([finite(x), finite(y)])),
            "offset_machine": self.offset_machine.as_ref().map(|o| json!({
                "x": finite(o.x), "y": finite(o.y), "unit": o.unit,
            })),
            "source": self.source,
            "params": pairs(&self.params),
            "telemetry": pairs(&self.telemetry),
            "history": pairs(&self.history),
            "fit": self.fit.as_ref().map(|f| json!({
                "title": f.title, "line": f.line, "lines": f.lines, "bound99": f.bound99.map(finite),
                "unit": f.unit, "gcode": f.gcode, "svg": f.svg.is_some(),
            })),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_non_finite_number_is_null_in_the_json() {
        let view =
            View { mark: Some(Mark { x: f64::NAN, y: 2.0, diameter: f64::INFINITY, score: 0.5 }), ..View::default() };
        let text = view.to_json(7).to_string();
        let back: Value = serde_json::from_str(&text).expect("valid JSON");
        assert_eq!(back["seq"], 7);
        assert_eq!(back["mark"]["x"], Value::Null);
        assert_eq!(back["mark"]["y"], 2.0);
        assert_eq!(back["found"], true);
    }
}
