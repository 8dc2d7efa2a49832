//! `mach-vision trigger`: one `TRG` against a Keyence camera, real or emulated.

use std::time::Duration;

use clap::Args;
use serde_json::json;
use vision_core::VisionError;
use vision_driver_keyence::{KeyenceConfig, KeyenceDriver};

use crate::Failure;

/// Arguments of `mach-vision trigger`.
#[derive(Debug, Args)]
pub(crate) struct TriggerArgs {
    /// Camera address.
    #[arg(long)]
    ip: String,
    /// Camera port.
    #[arg(long, default_value_t = 8500)]
    port: u16,
    /// Seconds for the whole exchange (connect, send, reply).
    #[arg(long, default_value_t = 3.0)]
    timeout: f64,
    /// Print the reading as one JSON object.
    #[arg(long)]
    json: bool,
}

/// Triggers once and prints the decoded reading (native pixels).
pub(crate) fn run(args: &TriggerArgs) -> Result<String, Failure> {
    let timeout = Duration::try_from_secs_f64(args.timeout)
        .ok()
        .filter(|t| !t.is_zero())
        .ok_or_else(|| Failure::Input(format!("--timeout {} must be a positive number of seconds", args.timeout)))?;
    let config = KeyenceConfig::new(args.ip.clone(), args.port).with_timeout(timeout);
    let mut driver = KeyenceDriver::new(config).map_err(|e| Failure::Input(e.to_string()))?;
    // Through VisionError, so the operator reads the manual's fix with the camera's words.
    let r = driver.measure().map_err(|e| Failure::Run(VisionError::Driver(e.into()).to_string()))?;
    let judgment = r.judgment.label();
    if args.json {
        let v = json!({
            "judgment": judgment, "count": r.count, "x_px": r.x_px, "y_px": r.y_px,
            "width_px": r.width_px, "height_px": r.height_px, "angle_deg": r.angle_deg, "score": r.score,
            "found": r.found(),
        });
        return Ok(format!("{v}\n"));
    }
    let count = r.count.map_or_else(|| "not reported".to_string(), |c| c.to_string());
    Ok(format!(
        "{}:{}: judgment {judgment}, count {count}\n  mark at x {:.3} y {:.3} px, {:.3} x {:.3} px, angle {:.3} deg, score {:.3}\n{}",
        args.ip,
        args.port,
        r.x_px,
        r.y_px,
        r.width_px,
        r.height_px,
        r.angle_deg,
        r.score,
        if r.found() { "" } else { "  no usable mark (NG or count 0): M281 would stop here\n" }
    ))
}
