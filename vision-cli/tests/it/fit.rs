//! `mach-vision fit` through the built binary.

use std::io::Write as _;
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mach-vision"))
}

fn example4() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/fit/example4.json")
}

fn with_stdin(args: &[&str], input: &str) -> Output {
    let mut child =
        bin().args(args).stdin(Stdio::piped()).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("spawn");
    child.stdin.take().expect("stdin").write_all(input.as_bytes()).expect("write stdin");
    child.wait_with_output().expect("wait")
}

#[test]
fn solves_the_manual_example_4_geometry_as_json() {
    let out = bin().args(["fit", "--json"]).arg(example4()).output().expect("run");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(v["model"], "rectangle");
    assert_eq!(v["points"], 4);
    let theta = v["theta_deg"].as_f64().expect("theta");
    assert!((theta - 0.5).abs() < 1e-3, "θ = {theta}");
    let center = v["center"].as_array().expect("center");
    assert!((center[0].as_f64().expect("cx") - 3.0).abs() < 1e-12);
    assert!((center[1].as_f64().expect("cy") - 2.0).abs() < 1e-12);
    assert!(v["rms"].as_f64().expect("rms") < 1e-4);
    assert_eq!(v["residuals"].as_array().expect("residuals").len(), 4);
    let gcode: Vec<&str> = v["gcode"].as_array().expect("gcode").iter().map(|l| l.as_str().expect("line")).collect();
    assert_eq!(gcode.len(), 4);
    assert_eq!(gcode[0], "G69 G50 G52 X0 Y0");
    assert!(gcode[1].starts_with("G52 X0.08"), "{}", gcode[1]);
    assert!(gcode[2].starts_with("G68 X3.0000000 Y2.0000000 R0.50"), "{}", gcode[2]);
    assert!(gcode[3].starts_with("G51 X1.0000"), "{}", gcode[3]);
}

#[test]
fn readable_report_from_stdin_for_every_model() {
    let input = std::fs::read_to_string(example4()).expect("example");
    for model in ["rigid", "similarity", "rectangle", "affine"] {
        let out = with_stdin(&["fit", "--model", model], &input);
        assert!(out.status.success(), "{model}: {}", String::from_utf8_lossy(&out.stderr));
        let text = String::from_utf8(out.stdout).expect("utf-8");
        assert!(text.starts_with(&format!("{model} fit of 4 marks")), "{text}");
        assert!(text.contains("RMS"), "{text}");
        if model == "affine" {
            assert!(text.contains("no G-code"), "{text}");
        } else {
            assert!(text.contains("G68 X3.0000000 Y2.0000000 R"), "{text}");
        }
    }
}

#[test]
fn bad_input_exits_2_with_one_line() {
    let cases = [
        ("not json", "not valid fit JSON"),
        (r#"{"commanded": [[0,0],[1,0],[1,1]], "observed": [[0,0],[1,0]]}"#, "3 commanded points but 2 observed"),
        (r#"{"commanded": [[0,0],[1,1],[2,2]], "observed": [[0,0],[1,1],[2,2]]}"#, "collinear"),
        (r#"{"commanded": [[0,0],[1,0]], "observed": [[0,0],[1,0]]}"#, "at least 3 points"),
        (r#"{"commanded": [[0,0],[1,0],[1,1]], "observed": [[0,0],[1,0],[1,1e999]]}"#, "not valid fit JSON"),
        (r#"{"commanded": [], "observed": [], "extra": 1}"#, "unknown field"),
        (r#"{"commanded": [[0,0,0]], "observed": [[0,0]]}"#, "not valid fit JSON"),
    ];
    for (input, expected) in cases {
        let out = with_stdin(&["fit"], input);
        assert_eq!(out.status.code(), Some(2), "{input}");
        let err = String::from_utf8(out.stderr).expect("utf-8");
        assert!(err.contains(expected), "{input}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
        assert!(out.stdout.is_empty());
    }
    let out = bin().args(["fit", "/nonexistent/marks.json"]).output().expect("run");
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read /nonexistent/marks.json"));
}

/// Issue 17 item 13: degenerate or out-of-range geometry exits 2 with the reason, never a G51
/// that `trace` would refuse; a bare array is not the schema.
#[test]
fn degenerate_geometry_and_wrong_shapes_exit_2_with_the_reason() {
    for (input, reason) in [
        (r#"{"commanded":[[0,0],[1,0],[0,1]],"observed":[[0,0],[1,0],[2,0]]}"#, "collinear or collapse"),
        (r#"{"commanded":[[0,0],[1e-15,0],[0,1e-15]],"observed":[[0,0],[1,0],[0,1]]}"#, "commanded points coincide"),
        (r#"{"commanded":[[0,0],[1e200,0],[0,1e200]],"observed":[[0,0],[1,0],[0,1]]}"#, "no machine travels that far"),
        (r#"[[[0,0],[1,0],[0,1]],[[0,0],[1,0],[0,1]]]"#, "expected an object"),
    ] {
        let out = with_stdin(&["fit"], input);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{input}: {err}");
        assert!(err.contains(reason), "{input}: {err}");
        assert!(out.stdout.is_empty(), "{input}: no report, no G51");
    }
}
