//! `mach-vision panel --profile P` without `--camera`: the page follows what a controller's
//! session publishes in `P.panel/` — no state yet, a state with its frame searched, a refusal,
//! and a garbage file — and never stops on any of them.

use std::path::Path;
use std::time::{Duration, Instant};

use serde_json::{json, Value};

use crate::panel::{frame, get, panel};

/// Replaces `dir/state.json` as the session does (a temp file, then a rename).
fn publish(dir: &Path, text: &str) {
    let temp = dir.join("state.json.tmp");
    std::fs::write(&temp, text).expect("written");
    std::fs::rename(&temp, dir.join("state.json")).expect("renamed");
}

/// A state numbered `seq` whose last call is `last`, with the frame beside it.
fn state(seq: u64, last: &Value) -> String {
    json!({
        "format": 1, "seq": seq, "time_unix": 1_790_000_000.5, "profile": "profile.toml",
        "params": {"VisionCameraMarkDiameterPx": 40.0, "VisionUnits": "in"},
        "telemetry": {"VisionLastStatus": "OK", "VisionRun_Captures": 2},
        "last": last, "dots": [], "frame": "frame.png",
    })
    .to_string()
}

/// The page's state once `ready` holds (a minute at most).
fn until(addr: &str, ready: impl Fn(&Value) -> bool) -> Value {
    let start = Instant::now();
    loop {
        let state: Value = serde_json::from_slice(&get(addr, "/state.json").1).expect("JSON");
        if ready(&state) {
            return state;
        }
        assert!(start.elapsed() < Duration::from_secs(60), "not in a minute: {state}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn the_page_follows_the_panel_folder_and_survives_garbage() {
    let dir = std::env::temp_dir().join(format!("mv-panel-folder-{}", std::process::id()));
    let folder = dir.join("profile.panel");
    std::fs::create_dir_all(&folder).expect("dir");
    let profile = dir.join("profile.toml");
    std::fs::write(&profile, "[vision]\n[camera]\nVisionCameraMarkDiameterPx = 40.0\n").expect("profile");
    let mut running = panel(&["--profile", profile.to_str().expect("utf-8")]);
    let why = |s: &Value| s["why_ng"].as_str().unwrap_or("").to_string();

    let empty = until(&running.1, |s| s["seq"].as_u64() > Some(0));
    assert!(why(&empty).contains("no panel state yet"), "{empty}");

    frame(&folder.join("frame.png"), Some((110.0, 70.0)));
    let ok = json!({"mcode": 281, "ok": true, "message": "mark found", "gcode": ["G0 X1 Y2"], "report": null});
    publish(&folder, &state(3, &ok));
    let shown = until(&running.1, |s| s["source"].as_str().is_some_and(|t| t.ends_with("(state 3)")));
    assert_eq!(shown["found"], true, "the frame is searched: {shown}");
    assert!((shown["mark"]["x"].as_f64().expect("x") - 109.5).abs() < 0.5, "{shown}");
    assert!(shown["telemetry"].as_array().expect("rows").contains(&json!(["VisionRun_Captures", "2"])), "{shown}");
    assert_eq!(shown["call"], json!({"mcode": 281, "ok": true, "message": "mark found", "gcode": ["G0 X1 Y2"]}));
    assert!(shown["why_ng"].is_null(), "{shown}");

    let refused = json!({"mcode": 282, "ok": false, "message": "M282: no calibration", "gcode": [], "report": null});
    publish(&folder, &state(4, &refused));
    let shown = until(&running.1, |s| s["source"].as_str().is_some_and(|t| t.ends_with("(state 4)")));
    assert_eq!(why(&shown), "M282: no calibration", "{shown}");
    assert_eq!(shown["call"]["ok"], false, "{shown}");

    publish(&folder, "{ not json");
    let garbage = until(&running.1, |s| why(s).contains("not a panel state"));
    assert!(running.0.try_wait().expect("status").is_none(), "the panel runs on: {garbage}");
    drop(running);
    let _ = std::fs::remove_dir_all(&dir);
}
