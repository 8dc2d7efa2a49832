//! `mach-vision panel`: refused off loopback without a token (exit 2), and on loopback the mark
//! it reports is the one `mach-vision locate` finds on the frame it serves. (The page itself is
//! tested in Chromium by `scripts/browser-test`.)

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::bounded;

#[test]
fn off_loopback_without_a_token_and_other_cameras_are_refused_with_exit_2() {
    for (args, says) in [
        (&["panel", "--listen", "0.0.0.0:0"][..], "--token"),
        (&["panel", "--listen", "[::]:0"], "--token"),
        (&["panel", "--listen", "0.0.0.0:0", "--token", "a b"], "--token"),
        (&["panel", "--listen", "127.0.0.1:0", "--camera", "sim"], "simimage"),
        (&["panel", "--listen", "127.0.0.1:0", "--camera", "nope"], "no such camera"),
        (&["panel", "--listen", "127.0.0.1:0", "--source", "x.png"], "--source is for --camera camera"),
        (&["panel", "--listen", "localhost"], "invalid"),
    ] {
        let out = bounded(args, 1024, 30).unwrap_or_else(|| panic!("{args:?} did not exit"));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
    }
}

/// A panel process, killed when dropped.
pub(crate) struct Running(pub(crate) Child, pub(crate) String);

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

pub(crate) fn panel(args: &[&str]) -> Running {
    let child = Command::new(env!("CARGO_BIN_EXE_mach-vision"))
        .arg("panel")
        .args(["--listen", "127.0.0.1:0"])
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn");
    let mut running = Running(child, String::new());
    let mut line = String::new();
    let stdout = running.0.stdout.take().expect("stdout");
    BufReader::new(stdout).read_line(&mut line).expect("the first line");
    let addr = line.split("http://").nth(1).and_then(|r| r.split('/').next());
    running.1 = addr.unwrap_or_else(|| panic!("no address in {line:?}")).to_string();
    running
}

pub(crate) fn get(addr: &str, path: &str) -> (u16, Vec<u8>) {
    let mut s = TcpStream::connect(addr).expect("connect");
    s.set_read_timeout(Some(Duration::from_secs(20))).expect("timeout");
    s.write_all(format!("GET {path} HTTP/1.1\r\n\r\n").as_bytes()).expect("send");
    let mut answer = Vec::new();
    s.read_to_end(&mut answer).expect("answer");
    let status = String::from_utf8_lossy(&answer[9..12]).parse().expect("status");
    let body = answer.windows(4).position(|w| w == b"\r\n\r\n").map_or(Vec::new(), |i| answer[i + 4..].to_vec());
    (status, body)
}

/// The panel's first look, as `/state.json` gives it.
fn first_look(addr: &str) -> serde_json::Value {
    let start = Instant::now();
    loop {
        let state: serde_json::Value = serde_json::from_slice(&get(addr, "/state.json").1).expect("JSON");
        if state["seq"].as_u64() > Some(0) {
            return state;
        }
        assert!(start.elapsed() < Duration::from_secs(60), "no look in a minute");
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// A panel on a file camera: a 200×160 frame with a 40 px dot at `at` (or none) and a profile
/// that gives the dot's diameter, in a scratch folder of their own.
fn file_camera(name: &str, at: Option<(f64, f64)>) -> (PathBuf, Running) {
    let dir = std::env::temp_dir().join(format!("mv-panel-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let (png, profile) = (dir.join("frame.png"), dir.join("profile.toml"));
    frame(&png, at);
    std::fs::write(&profile, "[vision]\n[camera]\nVisionCameraMarkDiameterPx = 40.0\n").expect("profile");
    let source = png.to_str().expect("utf-8");
    let running = panel(&["--camera", "camera", "--source", source, "--profile", profile.to_str().expect("utf-8")]);
    (dir, running)
}

/// A 200×160 frame, white, with a dark 40 px dot centred at native pixel `at`, when given.
pub(crate) fn frame(path: &Path, at: Option<(f64, f64)>) {
    let image = image::GrayImage::from_fn(200, 160, |x, y| {
        let inside = at.is_some_and(|(cx, cy)| (f64::from(x) + 0.5 - cx).hypot(f64::from(y) + 0.5 - cy) < 20.0);
        image::Luma([if inside { 20 } else { 230 }])
    });
    image.save(path).expect("saved");
}

#[test]
fn a_file_camera_s_mark_is_the_one_locate_finds_on_the_served_frame() {
    let (dir, running) = file_camera("found", Some((110.0, 70.0)));
    let state = first_look(&running.1);
    assert_eq!(state["found"], true, "{state}");
    let seq = state["seq"].as_u64().expect("seq");
    let (status, served) = get(&running.1, &format!("/frame.png?seq={seq}"));
    assert_eq!(status, 200);
    let copy = dir.join("served.png");
    std::fs::write(&copy, served).expect("written");
    let out = Command::new(env!("CARGO_BIN_EXE_mach-vision"))
        .args(["locate", "--json", "--diameter", "40"])
        .arg(&copy)
        .output()
        .expect("locate");
    let found: serde_json::Value = serde_json::from_slice(&out.stdout).expect("locate's JSON");
    for key in ["x", "y", "diameter"] {
        let (panel, locate) = (state["mark"][key].as_f64(), found[key].as_f64());
        let (panel, locate) = (panel.expect("panel"), locate.expect("locate"));
        assert!((panel - locate).abs() < 0.5, "{key}: panel {panel}, locate {locate}");
    }
    assert!((found["x"].as_f64().expect("x") - 109.5).abs() < 0.3, "{found}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn no_mark_shows_the_frame_and_the_finder_s_reason() {
    let (dir, running) = file_camera("none", None);
    let state = first_look(&running.1);
    assert_eq!(state["found"], false, "{state}");
    assert!(state["why_ng"].as_str().is_some_and(|w| w.contains("no")), "{state}");
    assert_eq!(state["width"], 200, "the frame is shown without a mark");
    let seq = state["seq"].as_u64().expect("seq");
    assert_eq!(get(&running.1, &format!("/frame.png?seq={seq}")).0, 200);
    let _ = std::fs::remove_dir_all(&dir);
}
