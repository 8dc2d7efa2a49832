//! `mach-vision plan` through the built binary.

use std::path::PathBuf;
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mach-vision"))
}

/// Writes `text` to a file of the test's own in the target's scratch directory.
fn program(name: &str, text: &str) -> PathBuf {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::write(&path, text).expect("write the program");
    path
}

fn plan(args: &[&str], path: &PathBuf) -> Output {
    bin().arg("plan").args(args).arg(path).output().expect("run")
}

fn report_value(text: &str, key: &str) -> String {
    text.lines()
        .find_map(|l| l.strip_prefix(key))
        .map(|v| v.trim().to_string())
        .unwrap_or_else(|| panic!("no {key} in\n{text}"))
}

#[test]
fn the_g61_square_takes_four_trapezoids() {
    let square = program("square.nc", "G91 G21 G61\nG0 X500\nY500\nX-500\nY-500\n");
    let out = plan(&["--accel", "1000", "--max-speed", "500", "--machine-units", "mm"], &square);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    // Each side: 0.5 s up, 0.5 s at 500 mm/s, 0.5 s down.
    assert_eq!(report_value(&text, "cycle time"), "6.000 s");
    assert_eq!(report_value(&text, "setpoints"), "6001");
    assert_eq!(report_value(&text, "end"), "X0.0000 Y0.0000 Z0.0000 (line 5)");
}

#[test]
fn the_seed_example_writes_every_setpoint_and_its_tool_events_to_csv() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/path/seed002-example.nc");
    let csv = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("seed.csv");
    let csv_arg = csv.to_str().unwrap();
    let out = plan(&["--accel", "1000", "--machine-units", "mm", "--period", "2", "--csv", csv_arg], &path);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    let setpoints: usize = report_value(&text, "setpoints").parse().unwrap();
    let rows = std::fs::read_to_string(&csv).unwrap();
    let mut lines = rows.lines();
    assert_eq!(lines.next(), Some("time_s,line,x,y,z,vx,vy,vz,event"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let events = csv_events(&csv);
    assert_eq!(events, [("12", "M3 $1"), ("18", "M5 $1")].map(|(l, e)| (l.to_string(), e.to_string())));
    assert_eq!(rows.len() - events.len(), setpoints);
    let last = rows.last().unwrap();
    assert_eq!(&last[2..5], &["1", "1", "0"]);
    let times: Vec<f64> = rows.iter().filter(|r| r[8].is_empty()).map(|r| r[0].parse().unwrap()).collect();
    assert!(times.windows(2).all(|w| (w[1] - w[0] - 0.002).abs() < 1e-9), "a fixed 2 ms period");
    assert_eq!(report_value(&text, "cycle time"), format!("{:.3} s", times.last().unwrap()));
}

/// The event column of every event row of `csv`, with its line.
fn csv_events(csv: &PathBuf) -> Vec<(String, String)> {
    let rows = std::fs::read_to_string(csv).unwrap();
    rows.lines()
        .skip(1)
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|r| !r[8].is_empty())
        .map(|r| (r[1].to_string(), r[8].to_string()))
        .collect()
}

#[test]
fn explicit_port_events_are_written_as_the_m_code_that_caused_them() {
    // Seed 002's explicit M4 snippet, and the same port driven by M3: each row names its own
    // code (an M4 is not an M3), and M5 names its port.
    let path = program("m4_port.nc", "G90 G21\nG0 X100 Y100\nM4 A1 P1\nG1 X200 Y200 F1000\nM5 A1 P1\nM3 A2 P0\n");
    let csv = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("m4_port.csv");
    let out = plan(&["--accel", "1000", "--machine-units", "mm", "--csv", csv.to_str().unwrap()], &path);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let expected = [("3", "M4 A1 P1"), ("5", "M5 A1 P1"), ("6", "M3 A2 P0")];
    assert_eq!(csv_events(&csv), expected.map(|(l, e)| (l.to_string(), e.to_string())));
}

#[test]
fn a_program_that_fails_at_a_line_exits_1_and_names_the_line() {
    let path = program("bad.nc", "G21 G90\nG0 X10\nG1 X20 Q7 F100\n");
    let out = plan(&["--accel", "1000", "--machine-units", "mm"], &path);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("line 3") && err.contains("Q"), "{err}");
    let path = program("no_feed.nc", "G21 G90\nG1 X10\n");
    let out = plan(&["--accel", "1000", "--machine-units", "mm"], &path);
    assert_eq!(out.status.code(), Some(1), "a feed move before any F");
    let out = plan(&["--accel", "1000", "--machine-units", "mm", "--default-feed", "600"], &path);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(report_value(&String::from_utf8(out.stdout).unwrap(), "end"), "X10.0000 Y0.0000 Z0.0000 (line 2)");
}

#[test]
fn bad_input_exits_2() {
    let path = program("ok.nc", "G21 G0 X1\n");
    for args in [
        &["--accel", "-5"][..],
        &["--accel", "1000", "--period", "0"],
        &["--accel", "1000", "--max-speed", "nan"],
        &["--accel", "1000", "--csv", "/nonexistent-dir/x.csv"],
        // Below the physical range: these made the planner run for ever or report 0 s.
        &["--accel", "1e-12"],
        &["--accel", "1e-300"],
        &["--accel", "1000", "--max-speed", "1e-12"],
        &["--accel", "1000", "--axis-accel", "1e-300"],
    ] {
        let out = plan(args, &path);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
        assert!(!out.stderr.is_empty());
    }
    let out = plan(&["--accel", "1000"], &PathBuf::from("/nonexistent/program.nc"));
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn a_bad_default_feed_is_a_bad_option_not_a_program_error() {
    let path = program("feed.nc", "G21 G90\nG1 X10\n");
    for feed in ["NaN", "inf", "0", "-1", "1e-12"] {
        let out = plan(&["--accel", "1000", "--machine-units", "mm", &format!("--default-feed={feed}")], &path);
        assert_eq!(out.status.code(), Some(2), "--default-feed {feed}");
        let err = String::from_utf8(out.stderr).unwrap();
        assert!(err.contains("--default-feed") && !err.contains("line 2"), "{err}");
    }
}

#[test]
fn a_tiny_program_feed_is_refused_at_its_line() {
    let path = program("tiny_feed.nc", "G20 G90\nG1 X1 F1e-12\n");
    let out = plan(&["--accel", "20"], &path);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("line 2") && err.contains("feed"), "{err}");
}

/// `plan --dialect linuxcnc` plans a LinuxCNC program (issue 22: it refused every one, since the
/// planner ran each line as a program of its own, which LinuxCNC's end rule refused), and
/// `trace` runs the same program to the same end.
#[test]
fn a_linuxcnc_program_plans_and_traces_under_the_linuxcnc_dialect() {
    let path = program("linuxcnc.ngc", "G20 G90 F10\nG1 X1\nM2\n");
    let out = plan(&["--accel", "10", "--dialect", "linuxcnc"], &path);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    // 1 in at 10 in/min, reached in 0.0167 s at 10 in/s².
    assert_eq!(report_value(&text, "cycle time"), "6.017 s");
    assert_eq!(report_value(&text, "setpoints"), "6018");
    assert_eq!(report_value(&text, "end"), "X1.0000 Y0.0000 Z0.0000 (line 3)");

    let out = bin().args(["trace", "--dialect", "linuxcnc"]).arg(&path).output().expect("run");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("     2  feed   X1.0000 Y0.0000 Z0.0000  F10.0000"), "{text}");
    assert!(text.contains("# ended by M2 at line 3; machine at X1.0000 Y0.0000 Z0.0000"), "{text}");
}

/// Under LinuxCNC a program that ends with no M2/M30 or closing `%` is refused by `plan` as by
/// `trace` (rs274 refuses it); under Mach4 both run it.
#[test]
fn a_program_without_its_end_is_refused_under_linuxcnc_only() {
    let path = program("no-end.ngc", "G20 G90 F10\nG1 X1\n");
    let out = plan(&["--accel", "10", "--dialect", "linuxcnc"], &path);
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("no-end.ngc: line 2: the program ended with no M2/M30"), "{err}");
    for tool in [&["plan", "--accel", "10"][..], &["trace"][..]] {
        let out = bin().args(tool).args(["--dialect", "linuxcnc"]).arg(&path).output().expect("run");
        assert_eq!(out.status.code(), Some(1), "{tool:?}");
        let err = String::from_utf8(out.stderr).unwrap();
        assert!(err.contains(": the program ended with no M2/M30 or closing %"), "{tool:?}: {err}");
        let out = bin().args(tool).args(["--dialect", "mach4"]).arg(&path).output().expect("run");
        assert!(out.status.success(), "{tool:?}: {}", String::from_utf8_lossy(&out.stderr));
    }
}

/// A closing `%` ends the program in `plan` as in `trace`: what follows it is not run (the
/// planner ran it, line by line, before issue 22).
#[test]
fn the_closing_percent_ends_the_plan() {
    let path = program("percent.ngc", "%\nG20 G90 F10\nG1 X1\n%\nG1 X5\n");
    for dialect in ["linuxcnc", "mach4", "machinemotion"] {
        let out = plan(&["--accel", "10", "--dialect", dialect], &path);
        assert!(out.status.success(), "{dialect}: {}", String::from_utf8_lossy(&out.stderr));
        let text = String::from_utf8(out.stdout).unwrap();
        assert_eq!(report_value(&text, "end"), "X1.0000 Y0.0000 Z0.0000 (line 4)", "{dialect}");
    }
    // From an o-word on, the rest of the text runs at once: the `%` that opened the program
    // still closes it there.
    let path =
        program("percent-sub.ngc", "%\nG20 G90 F10\no100 sub\nG1 X#1\no100 endsub\no100 call [2]\nG1 Y1\n%\nG1 X9\n");
    for dialect in ["linuxcnc", "mach4"] {
        let out = plan(&["--accel", "10", "--dialect", dialect], &path);
        assert!(out.status.success(), "{dialect}: {}", String::from_utf8_lossy(&out.stderr));
        let text = String::from_utf8(out.stdout).unwrap();
        assert_eq!(report_value(&text, "end"), "X2.0000 Y1.0000 Z0.0000 (line 8)", "{dialect}");
    }
}

/// Issue 34 item 7: `plan --json` prints one JSON object with the text report's values.
#[test]
fn plan_json_is_one_object_with_the_reports_values() {
    let path = program("json.nc", "G90 G20\nG1 X1 F10\nM30\n");
    let text = plan(&["--accel", "10"], &path);
    let out = plan(&["--accel", "10", "--json"], &path);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let text = String::from_utf8(text.stdout).expect("utf-8");
    assert_eq!(format!("{:.3} s", v["cycle_time_s"].as_f64().expect("cycle")), report_value(&text, "cycle time"));
    assert_eq!(v["setpoints"].to_string(), report_value(&text, "setpoints"));
    assert_eq!(v["events"].to_string(), report_value(&text, "events"));
    assert_eq!((v["end"]["x"].as_f64(), v["end"]["line"].as_u64()), (Some(1.0), Some(3)));
    assert_eq!(
        (v["unit"].as_str(), v["path_accel"].as_f64(), v["period_ms"].as_f64()),
        (Some("in"), Some(10.0), Some(1.0))
    );
    assert!((v["axis_max_speed"].as_f64().expect("speed") - 500.0 / 25.4).abs() < 1e-12, "{v}");
}

/// Issue 34 item 7: the settings line reads numbers as messages do (`vision_math::show::number`),
/// not a float's every digit.
#[test]
fn plan_prints_its_settings_with_the_message_number_formatter() {
    let path = program("settings.nc", "G90 G20\nG1 X1 F10\n");
    let out = plan(&["--accel", "10"], &path);
    let text = String::from_utf8(out.stdout).expect("utf-8");
    let first = text.lines().next().expect("settings line");
    assert!(
        first.ends_with(": 1 ms setpoints, path acceleration 10 in/s², axes 19.68503937 in/s and 10 in/s²"),
        "{first}"
    );
}

/// Issue 34 item 7: `trace`, `plan` and `run` read a program alike without `--dialect`: all
/// default to Mach4 (a comment ends at its first `)`, where seed 002's would nest), and
/// `--help` lists the dialects and the default.
#[test]
fn every_subcommand_defaults_to_the_mach4_dialect_and_lists_the_dialects() {
    let path = program("nested-comment.nc", "G90 G20\nG1 F10 Y0 (outer (inner) X1\nM30\n");
    let trace = bin().arg("trace").arg(&path).output().expect("trace");
    assert!(trace.status.success(), "{}", String::from_utf8_lossy(&trace.stderr));
    assert!(String::from_utf8_lossy(&trace.stdout).contains("X1.0000"), "X1 is a word after the comment");
    let planned = plan(&["--accel", "10"], &path);
    assert!(planned.status.success(), "{}", String::from_utf8_lossy(&planned.stderr));
    assert_eq!(report_value(&String::from_utf8_lossy(&planned.stdout), "end"), "X1.0000 Y0.0000 Z0.0000 (line 3)");
    let run = bin().arg("run").arg(&path).output().expect("run");
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let seed = bin().args(["trace", "--dialect", "machinemotion"]).arg(&path).output().expect("trace");
    assert!(!seed.status.success(), "seed 002's comments nest: the comment is never closed");
    for sub in ["trace", "plan", "run"] {
        let help = bin().args([sub, "--help"]).output().expect("help");
        let help = String::from_utf8_lossy(&help.stdout);
        assert!(help.contains("[possible values: mach4, linuxcnc, machinemotion, grbl]"), "{sub}: {help}");
        assert!(help.contains("mach4") && help.contains("the manual's controller"), "{sub}: {help}");
    }
}
