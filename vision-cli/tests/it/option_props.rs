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
