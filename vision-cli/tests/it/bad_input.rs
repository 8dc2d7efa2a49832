//! Hostile input through the built binary (issue 17, items 14–15): what a person reads is one
//! escaped line of bounded size, whatever the input quotes.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mach-vision"))
}

fn scratch(name: &str, text: &[u8]) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bad_input");
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write");
    path
}

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/programs").join(name)
}

fn arg(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// The one error line: exit 2, a single line, short, no raw control character.
fn one_short_line(out: &Output, names: &str) -> String {
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    let err = String::from_utf8(out.stderr.clone()).expect("utf-8");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.len() < 4096, "{} bytes on standard error", err.len());
    assert!(!err.trim_end().chars().any(char::is_control), "{err:?}");
    assert!(err.contains(names), "{err}");
    err
}

#[test]
fn huge_quoted_input_is_cut_in_messages() {
    let huge = "a!".repeat(5_000_000);
    // A profile under the size cap quoting a long value: cut in the message.
    let long = "a!".repeat(200_000);
    let profile = scratch("long.toml", format!("[vision]\nVisionIP = \"{long}\"\n").as_bytes());
    let out =
        bin().args(["run", "--profile", arg(&profile)]).arg(example("04-rectangle-fit.nc")).output().expect("run");
    let err = one_short_line(&out, "VisionIP");
    assert!(err.contains("characters cut") && err.contains("must be an IP address"), "{err}");
    // Past the cap (1 MiB): refused unread.
    let profile = scratch("huge.toml", format!("[vision]\nVisionIP = \"{huge}\"\n").as_bytes());
    let out =
        bin().args(["run", "--profile", arg(&profile)]).arg(example("04-rectangle-fit.nc")).output().expect("run");
    let err = one_short_line(&out, "huge.toml");
    assert!(err.contains("is 10000023 bytes; a profile is at most 1048576 bytes"), "{err}");

    let world = scratch("huge-world.toml", format!("unit = \"{huge}\"\n").as_bytes());
    let out = bin().args(["run", "--world", arg(&world)]).arg(example("04-rectangle-fit.nc")).output().expect("run");
    one_short_line(&out, "unit");

    let mut child =
        bin().arg("fit").stdin(Stdio::piped()).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().expect("fit");
    let json = format!("{{\"commanded\": \"{}\"}}", "x".repeat(10_000_000));
    child.stdin.take().expect("stdin").write_all(json.as_bytes()).expect("write");
    one_short_line(&child.wait_with_output().expect("fit"), "fit JSON");
}

#[test]
fn control_characters_in_a_program_are_shown_escaped() {
    let program = scratch("escapes.nc", b"G20\nM281 (hi \x1b[31mred\x0b)\nG1 X1 \x0b F10\n");
    let out = bin().arg("trace").arg(&program).output().expect("trace");
    assert_eq!(out.status.code(), Some(1));
    let text = String::from_utf8(out.stdout).expect("utf-8");
    assert!(text.contains("M281 (hi \\u{1b}[31mred\\u{b})"), "{text}");
    assert!(!text.chars().any(|c| c.is_control() && c != '\n'), "{text:?}");
    let err = String::from_utf8(out.stderr).expect("utf-8");
    assert_eq!(err.lines().count(), 1, "the vertical tab does not split the line: {err:?}");
    assert!(err.contains("line 3") && err.contains("\\u{b}"), "{err}");
}

#[test]
fn command_line_camera_choices_are_not_written_into_the_profile() {
    let file =
        "[vision]\nVisionEnabled = true\nVisionDriver = \"Keyence\"\nVisionIP = \"10.1.2.3\"\nVisionPort = 8600\n\
                VisionCameraToolNumber = 98\n";
    for camera in [&["--camera", "sim"][..], &["--camera", "keyence"][..]] {
        let profile = scratch(&format!("kept-{}.toml", camera[1]), file.as_bytes());
        let out = bin()
            .args(["run", "--profile", arg(&profile)])
            .args(camera)
            .arg(example("01-calibrate-sheet.nc"))
            .output()
            .expect("run");
        assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
        let saved = std::fs::read_to_string(&profile).expect("saved");
        assert!(saved.contains("VisionCal_K11") && !saved.contains("VisionCal_K11 = 0.0\n"), "M283 saved: {saved}");
        for kept in ["VisionDriver = \"Keyence\"", "VisionIP = \"10.1.2.3\"", "VisionPort = 8600"] {
            assert!(saved.contains(kept), "{camera:?}: {kept} missing from {saved}");
        }
        let keyence = saved.find("[keyence]").expect("the driver's settings in its own table");
        assert!(saved.find("VisionIP") > Some(keyence), "{saved}");
    }
}

#[test]
fn a_profile_that_cannot_be_saved_is_refused_before_any_motion() {
    let profile = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bad_input/no-such-folder/vision.toml");
    let out =
        bin().args(["run", "--profile", arg(&profile)]).arg(example("01-calibrate-sheet.nc")).output().expect("run");
    let err = one_short_line(&out, "create the folder");
    assert!(!err.contains("intact"), "{err}");
    assert!(out.stdout.is_empty(), "nothing ran");
}

#[test]
fn a_pound_block_past_9999_is_bad_input_at_load_not_a_failed_m280() {
    let profile = scratch("pound.toml", b"[vision]\nVisionEnabled = true\nVisionPoundVarBase = 9980\n");
    let out =
        bin().args(["run", "--profile", arg(&profile)]).arg(example("04-rectangle-fit.nc")).output().expect("run");
    let err = one_short_line(&out, "VisionPoundVarBase");
    assert!(err.contains("#9980..#10019") && err.contains("from 100 to 9960"), "{err}");
    assert!(out.stdout.is_empty(), "nothing ran");
}

/// Issue 17 item 16: a program of very many Vision M-codes keeps a bounded report.
#[test]
fn the_run_report_keeps_a_bounded_number_of_steps_and_counts_the_rest() {
    let program = format!("G90 G20\nT98 M6\n{}M30\n", "M281\n".repeat(25_000));
    let path = scratch("many-m281.nc", program.as_bytes());
    let out = bin().args(["run", "--json", arg(&path)]).output().expect("run");
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let p = &report["programs"][0];
    assert_eq!(p["steps"].as_array().map(Vec::len), Some(10_000));
    assert_eq!(p["steps_not_listed"], 15_000);
    let out = bin().args(["run", arg(&path)]).output().expect("run");
    let text = String::from_utf8(out.stdout).expect("utf-8");
    assert!(
        text.contains("15000 more Vision M-codes ran but are not listed (the report keeps the first 10000)"),
        "{}",
        &text[text.len().saturating_sub(500)..]
    );
}

#[test]
fn camera_takes_any_registered_name_in_any_case_and_lists_them_for_an_unknown_one() {
    let out = bin().args(["run", "--camera", "SIM"]).arg(example("04-rectangle-fit.nc")).output().expect("run");
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).expect("utf-8");
    assert!(text.starts_with("mach-vision run: world built-in, camera: simulated camera\n"), "{text}");
    let out = bin().args(["run", "--camera", "basler\u{7}"]).arg(example("04-rectangle-fit.nc")).output().expect("run");
    let err = one_short_line(&out, "--camera basler\\u{7}: no such camera");
    assert!(err.contains("the cameras are sim, simimage, keyence, camera (any case)"), "{err}");
    let out = bin().args(["run", "--camera", "sim", "--ip", "10.0.0.1"]).arg(example("04-rectangle-fit.nc")).output();
    one_short_line(&out.expect("run"), "--ip needs --camera keyence");
}
