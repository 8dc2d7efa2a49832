//! `mach-vision trigger`: one `TRG` against a Keyence camera, real or emulated.

use std::time::Duration;

use clap::Args;
use serde_json::json;
use vision_core::{CameraDriver, VisionError};
use vision_driver_keyence::{KeyenceConfig, KeyenceDriver, MAX_TIMEOUT};

use crate::Failure;

/// Arguments of `mach-vision trigger`.
#[derive(Debug, Args)]
pub(crate) struct TriggerArgs {
    /// Camera address.
    #[arg(long)]
    ip: String,
    /// Camera port.
    #[arg(long, default_value_t = 8500, allow_negative_numbers = true)]
    port: u16,
    /// Seconds for the whole exchange (connect, send, reply).
    #[arg(long, default_value_t = 3.0, allow_negative_numbers = true)]
    timeout: f64,
    /// Print the reading as one JSON object.
    #[arg(long)]
    json: bool,
}

/// Triggers once and prints the decoded reading (native pixels).
pub(crate) fn run(args: &TriggerArgs) -> Result<String, Failure> {
    let timeout = timeout(args.timeout).map_err(Failure::Input)?;
    let config = KeyenceConfig::new(args.ip.clone(), args.port).with_timeout(timeout);
    let mut driver = KeyenceDriver::new(config).map_err(|e| Failure::Input(e.to_string()))?;
    // Through VisionError, so the operator reads what M281 would report.
    let r = driver.measure().map_err(|e| Failure::Run(VisionError::Driver(e.into()).to_string()))?;
    let warning = driver.reading_warning(&r);
    let judgment = r.judgment.label();
    if args.json {
        let v = json!({
            "judgment": judgment, "count": r.count, "x_px": r.x_px, "y_px": r.y_px,
            "width_px": r.width_px, "height_px": r.height_px, "angle_deg": r.angle_deg, "score": r.score,
            "found": r.found(), "warning": warning,
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
        if r.found() {
            warning.map_or_else(String::new, |w| format!("  warning: {w}\n"))
        } else {
            "  no usable mark (NG or count 0): M281 would stop here\n".to_string()
        }
    ))
}

/// `--timeout` as a duration: more than 0 and at most the driver's [`MAX_TIMEOUT`] (300 s).
fn timeout(seconds: f64) -> Result<Duration, String> {
    // A huge value reads better as 1e30 than as its 31 digits.
    let shown = vision_math::show::number(seconds);
    if !(seconds > 0.0) {
        return Err(format!("--timeout {shown} must be more than 0 s (seconds for the whole exchange)"));
    }
    match Duration::try_from_secs_f64(seconds) {
        Ok(t) if t <= MAX_TIMEOUT => Ok(t),
        _ => Err(format!(
            "--timeout {shown} s is longer than {} s, the longest the camera driver waits",
            MAX_TIMEOUT.as_secs()
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_timeout_option_is_checked_in_its_own_name() {
        assert_eq!(timeout(0.25), Ok(Duration::from_millis(250)));
        assert_eq!(timeout(300.0), Ok(MAX_TIMEOUT));
        for (seconds, want) in [
            (0.0, "--timeout 0 must be more than 0 s"),
            (-2.5, "--timeout -2.5 must be more than 0 s"),
            (f64::NAN, "--timeout NaN must be more than 0 s"),
            (301.0, "--timeout 301 s is longer than 300 s"),
            (1e30, "--timeout 1e30 s is longer than 300 s"),
            (f64::INFINITY, "--timeout inf s is longer than 300 s"),
        ] {
            let e = timeout(seconds).expect_err(want);
            assert!(e.starts_with(want), "{seconds}: {e}");
        }
    }
}
