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
    let profile = scratch("huge.toml", format!("[vision]\nVisionIP = \"{huge}\"\n").as_bytes());
    let out =
        bin().args(["run", "--profile", arg(&profile)]).arg(example("04-rectangle-fit.nc")).output().expect("run");
    let err = one_short_line(&out, "VisionIP");
    assert!(err.contains("characters cut") && err.contains("must be an IP address"), "{err}");

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
