//! Example 8: a CAM-style job (safety line, tool changes, spindle and coolant, G43, a G81
//! drilling cycle, an M98 subprogram with arcs, M30) aligned by a 4-mark rectangle fit runs on
//! the built-in world and reports its cut error.

use std::path::PathBuf;
use std::process::Command;

use serde_json::Value;

#[test]
fn the_cam_job_example_runs_aligned_on_the_built_in_world() {
    let program = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/programs/08-cam-job.nc");
    let out =
        Command::new(env!("CARGO_BIN_EXE_mach-vision")).args(["run", "--json"]).arg(&program).output().expect("spawn");
    assert!(out.status.success(), "stderr: {}", String::from_utf8_lossy(&out.stderr));
    let report: Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let run = &report["programs"][0];
    assert_eq!(run["error"], Value::Null);
    assert!(run["outcome"].as_str().expect("outcome").starts_with("ended by M30"), "{run}");
    // 4 drilled holes (5 moves each but the first) and two slot passes with arcs, plus the fit.
    assert!(run["moves"].as_u64().expect("moves") > 40, "{run}");
    let fit: Vec<&Value> = run["steps"].as_array().expect("steps").iter().filter(|s| s["type"] == "fit").collect();
    assert_eq!(fit.len(), 1);
    assert_eq!(fit[0]["residuals"].as_array().map(Vec::len), Some(4), "a 4-mark fit");
    // Both tools cut in the aligned frame: the drill T1, then the end mill T2; each measured.
    assert_eq!(fit[0]["cut_error"]["tools"], serde_json::json!([1, 2]), "the drill's and the end mill's cut error");
    assert!([1, 2].contains(&fit[0]["cut_error"]["tool"].as_u64().expect("tool")), "{}", fit[0]["cut_error"]);
    let worst = fit[0]["cut_error"]["max"].as_f64().expect("cut error");
    assert!(worst < 0.002, "cut error {worst} in");
}

#[test]
fn plan_runs_the_cam_job_with_its_subprogram() {
    let program = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/programs/08-cam-job.nc");
    let out = Command::new(env!("CARGO_BIN_EXE_mach-vision"))
        .args(["plan", "--accel", "20"])
        .arg(&program)
        .output()
        .expect("spawn");
    assert!(out.status.success(), "stderr: {}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).expect("utf-8");
    // The subprogram's last move ends the slot at X2 Y1; the job then lifts to Z0.5.
    assert!(text.contains("end         X2.0000 Y1.0000 Z0.5000"), "{text}");
}
