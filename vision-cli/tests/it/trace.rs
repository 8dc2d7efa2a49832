//! `mach-vision trace` through the built binary.

use std::io::Write as _;
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mach-vision"))
}

fn program(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../vision-gcode/tests/programs").join(name)
}

fn with_stdin(args: &[&str], input: &[u8]) -> Output {
    let mut child =
        bin().args(args).stdin(Stdio::piped()).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("spawn");
    child.stdin.take().expect("stdin").write_all(input).expect("write stdin");
    child.wait_with_output().expect("wait")
}

#[test]
fn traces_a_vision_program_and_reports_the_user_mcodes() {
    let out = bin().arg("trace").arg(program("example4_rectangle_fit.nc")).output().expect("run");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).expect("utf-8");
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines[0].starts_with("# ") && lines[0].ends_with("machine coordinates (spindle) in in"), "{}", lines[0]);
    assert!(text.contains("     6  tool   T98 loaded"), "{text}");
    assert!(text.contains("     7  user   M280 ( default 4-point rectangle fit )  -- not executed"), "{text}");
    assert!(text.contains("     8  rapid  X0.0000 Y0.0000 Z0.0000"), "{text}");
    assert!(text.contains("    10  rapid  X6.0000 Y0.0000 Z0.0000"), "{text}");
    assert_eq!(text.matches("user   M281").count(), 4);
    assert!(
        lines.last().expect("summary").starts_with("# ended by M30 at line 22; machine at X0.0000 Y4.0000"),
        "{text}"
    );
}

#[test]
fn json_lines_stream_and_end_with_a_summary() {
    let out = bin().args(["trace", "--json"]).arg(program("example7_job_switch.nc")).output().expect("run");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let records: Vec<serde_json::Value> = String::from_utf8(out.stdout)
        .expect("utf-8")
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON object per line"))
        .collect();
    let first = &records[0];
    assert_eq!(first["type"], "tool_change");
    assert_eq!(first["tool"], 98);
    let m284: Vec<&serde_json::Value> =
        records.iter().filter(|r| r["type"] == "user_mcode" && r["code"] == 284).collect();
    assert_eq!(m284.len(), 2);
    assert_eq!(m284[1]["words"]["P"], 2.0);
    assert_eq!(m284[1]["comments"][0], " camera job 2 = precise circle fit ");
    let summary = records.last().expect("summary");
    assert_eq!(summary["type"], "summary");
    assert_eq!(summary["outcome"], "ended");
    assert_eq!(summary["code"], 30);
    assert_eq!(summary["machine"], serde_json::json!([5.0, 3.0, 0.0]));
}

#[test]
fn machine_units_and_standard_input() {
    let out = with_stdin(&["trace", "--machine-units", "mm", "--json", "-"], b"G20 G0 X1\n");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).expect("utf-8");
    let first: serde_json::Value = serde_json::from_str(text.lines().next().expect("event")).expect("JSON");
    assert_eq!(first["end"], serde_json::json!([25.4, 0.0, 0.0]));
    assert!(text.lines().last().expect("summary").contains("\"machine_unit\":\"mm\""));
}

#[test]
fn a_failing_program_exits_1_naming_the_line() {
    let out = with_stdin(&["trace", "-"], b"G90 G0 X1\nG0 X2 H1000\nG0 X3\n");
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8(out.stderr).expect("utf-8");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("line 2: `H` word is not used"), "{err}");
    let text = String::from_utf8(out.stdout).expect("utf-8");
    assert!(text.contains("     1  rapid  X1.0000"), "events before the failure are printed: {text}");
    assert!(!text.contains("X3.0000"));
    // In JSON mode the failure is also the last record.
    let out = with_stdin(&["trace", "--json", "-"], b"G0 X1\nG0 X[1/0]\n");
    assert_eq!(out.status.code(), Some(1));
    let last: serde_json::Value =
        serde_json::from_str(String::from_utf8(out.stdout).expect("utf-8").lines().last().expect("record"))
            .expect("JSON");
    assert_eq!(last["type"], "error");
    assert_eq!(last["line"], 2);
}

#[test]
fn bad_input_exits_2() {
    let out = bin().args(["trace", "/nonexistent/program.nc"]).output().expect("run");
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read /nonexistent/program.nc"));
}

#[test]
fn latin1_comments_and_block_delete() {
    // A comment in Latin-1 (not UTF-8) is read, not refused.
    let out = with_stdin(&["trace", "--json", "-"], b"G0 X1 (\xd8 6 mm)\n/G0 X2\n");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).expect("utf-8");
    let ends: Vec<serde_json::Value> = text
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|e| e["type"] == "linear")
        .map(|e| e["end"][0].clone())
        .collect();
    // Block delete is off by default: the `/` line runs.
    assert_eq!(ends, vec![serde_json::json!(1.0), serde_json::json!(2.0)]);
    let out = with_stdin(&["trace", "--json", "--block-delete", "-"], b"G0 X1\n/G0 X2\n");
    let text = String::from_utf8(out.stdout).expect("utf-8");
    assert_eq!(text.lines().filter(|l| l.contains("\"linear\"")).count(), 1, "{text}");
}
