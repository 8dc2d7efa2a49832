//! The CLI's numeric options (plan's limits, the camera's timeout and port) and the fit JSON
//! are parsers of user input: any number (or non-number) gives exit 0, 1 or 2 with at most one
//! line on standard error, never a panic (exit 101) or a non-finite number in the output.

use std::io::Write as _;
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

use proptest::prelude::*;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mach-vision"))
}

fn program() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/path/seed002-example.nc")
}

/// Exit 0, 1 or 2; bad input is one line (or clap's usage error); no NaN or infinity printed.
fn well_behaved(out: &Output, what: &str) -> Result<(), TestCaseError> {
    let code = out.status.code();
    prop_assert!(matches!(code, Some(0..=2)), "{what}: exit {code:?}: {}", String::from_utf8_lossy(&out.stderr));
    let err = String::from_utf8_lossy(&out.stderr);
    // Clap's own usage errors ("error: invalid value …" and a hint) are the one exception.
    prop_assert!(err.trim_end().lines().count() <= 1 || err.starts_with("error: invalid value"), "{what}: {err}");
    let stdout = String::from_utf8_lossy(&out.stdout).to_ascii_lowercase();
    prop_assert!(!stdout.contains("nan") && !stdout.contains("inf"), "{what}: {stdout}");
    Ok(())
}

/// A number-ish option value: ordinary, huge, tiny, negative, non-finite or not a number.
fn number() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<f64>().prop_map(|v| format!("{v:e}")),
        (-1e4..1e4f64).prop_map(|v| v.to_string()),
        prop::sample::select(vec!["0", "-0", "1e308", "1e-308", "NaN", "inf", "-inf", "", "x", "1,5", "0x10"])
            .prop_map(str::to_string),
    ]
}

fn point() -> impl Strategy<Value = String> {
    prop_oneof![
        (number(), number()).prop_map(|(x, y)| format!("[{x}, {y}]")),
        (-10.0..10.0f64, -10.0..10.0f64).prop_map(|(x, y)| format!("[{x}, {y}]")),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn plan_numeric_options_are_used_or_refused(
        option in prop::sample::select(vec!["--accel", "--period", "--max-speed", "--axis-accel", "--default-feed"]),
        value in number(),
    ) {
        let mut cmd = bin();
        cmd.arg("plan");
        if option != "--accel" {
            cmd.args(["--accel", "1000"]);
        }
        let out = cmd.arg(format!("{option}={value}")).arg(program()).output().expect("plan");
        well_behaved(&out, &format!("{option}={value}"))?;
    }

    #[test]
    fn camera_numeric_options_are_used_or_refused(
        option in prop::sample::select(vec!["--timeout", "--port"]),
        value in number(),
    ) {
        // Loopback port 9 has no listener: a valid option ends in a refused connection at
        // once (exit 1), an invalid one is bad input (exit 2).
        let mut cmd = bin();
        cmd.args(["trigger", "--ip", "127.0.0.1"]);
        if option != "--port" {
            cmd.args(["--port", "9"]);
        }
        let out = cmd.arg(format!("{option}={value}")).output().expect("trigger");
        well_behaved(&out, &format!("trigger {option}={value}"))?;
        let out = bin()
            .args(["run", "--camera", "keyence", "--ip", "127.0.0.1", &format!("--port={value}")])
            .arg(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/programs/04-rectangle-fit.nc"))
            .output()
            .expect("run");
        well_behaved(&out, &format!("run --port={value}"))?;
    }

    #[test]
    fn fit_json_of_any_numbers_is_fitted_or_refused(
        commanded in prop::collection::vec(point(), 0..6),
        observed in prop::collection::vec(point(), 0..6),
    ) {
        let json = format!("{{\"commanded\": [{}], \"observed\": [{}]}}", commanded.join(","), observed.join(","));
        let mut child = bin()
            .args(["fit", "--json"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("fit");
        child.stdin.take().expect("stdin").write_all(json.as_bytes()).expect("write");
        let out = child.wait_with_output().expect("fit");
        well_behaved(&out, &json)?;
        prop_assert!(out.status.code() != Some(1), "fit has no exit 1: {json}");
    }
}

/// Issue 34 item 7: a negative number given to a numeric option (`--accel -5`) is the option's
/// value and gets the option's range message (exit 2), never clap's "unexpected argument".
#[test]
fn negative_numbers_reach_every_numeric_options_range_check() {
    let p = program();
    let p = p.to_str().expect("utf-8");
    let cases: [(&[&str], &str); 14] = [
        (&["plan", "--accel", "-5", p], "max path acceleration (units/s²) = -5 is invalid"),
        (&["plan", "--accel", "1", "--period", "-1", p], "setpoint period (s) = -0.001 is invalid"),
        (&["plan", "--accel", "1", "--max-speed", "-1", p], "axis max speed (units/s) = -1 is invalid"),
        (&["plan", "--accel", "1", "--axis-accel", "-1", p], "axis max acceleration (units/s²) = -1 is invalid"),
        (&["plan", "--accel", "1", "--default-feed", "-1", p], "--default-feed -1 is invalid"),
        (&["locate", "--diameter", "-3", p], "--diameter -3: not a positive number"),
        (&["locate", "--diameter", "10", "--tolerance", "-3", p], "--tolerance -3: not a percentage"),
        (&["trigger", "--ip", "127.0.0.1", "--timeout", "-1"], "--timeout -1 must be more than 0 s"),
        (&["trigger", "--ip", "127.0.0.1", "--port", "-1"], "-1 is not in 0..=65535"),
        (&["emulate", "--port", "-1"], "-1 is not in 0..=65535"),
        (&["run", "--port", "-1", p], "-1 is not in 0..=65535"),
        (&["run", "--clock", "-1", p], "-1 is before 1970-01-01 00:00 UTC"),
        (&["sheet", "-1"], "no calibration sheet -1"),
        (&["sheet", "-1", "--format", "svg"], "no calibration sheet -1"),
    ];
    for (args, message) in cases {
        let out = bin().args(args).stdin(Stdio::null()).output().expect("spawn");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(!err.contains("unexpected argument") && err.contains(message), "{args:?}: {err}");
    }
}
