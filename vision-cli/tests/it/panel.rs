//! `mach-vision panel`: refused off loopback without a token (exit 2), and on loopback the mark
//! it reports is the one `mach-vision locate` finds on the frame it serves. `run --panel`:
//! each capture and the fit are published while the run goes on. (The page itself is
//! tested in Chromium by `scripts/browser-test`.)

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
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

/// A 1776×1776 PNG (the simulated camera's size, the one the profile is calibrated at), white,
/// with a dark 60 px dot at the centre.
fn centred_dot() -> Vec<u8> {
    let image = image::GrayImage::from_fn(1776, 1776, |x, y| {
        let inside = (f64::from(x) + 0.5 - 888.0).hypot(f64::from(y) + 0.5 - 888.0) < 30.0;
        image::Luma([if inside { 20 } else { 230 }])
    });
    let mut png = Vec::new();
    image.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png).expect("encoded");
    png
}

/// A calibrated profile for the camera driver in `dir`: the quick calibration on the simulated
/// camera, then the camera driver's settings (60 px dots, no flushed frames).
fn camera_profile(dir: &Path) -> PathBuf {
    let profile = dir.join("profile.toml");
    let program = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/programs/03-quick-diameter-cal.nc");
    let out = Command::new(env!("CARGO_BIN_EXE_mach-vision"))
        .args(["run", "--quiet", "--clock", "0", "--profile"])
        .arg(&profile)
        .arg(program)
        .output()
        .expect("run");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&profile)
        .expect("profile")
        .replace("VisionCal_Driver = \"Sim\"", "VisionCal_Driver = \"Camera\"")
        .replace("VisionCameraMarkDiameterPx = 0.0", "VisionCameraMarkDiameterPx = 60.0")
        .replace("VisionCameraFlushFrames = 2", "VisionCameraFlushFrames = 0");
    std::fs::write(&profile, text).expect("written");
    profile
}

/// Serves `png` to every request on `listener`, once `go` says so.
fn serve_snapshots(listener: TcpListener, png: Vec<u8>, go: mpsc::Receiver<()>) {
    std::thread::spawn(move || {
        let _ = go.recv_timeout(Duration::from_secs(60));
        for stream in listener.incoming() {
            let Ok(mut stream) = stream else { return };
            let mut head = Vec::new();
            let mut byte = [0u8; 1];
            while !head.ends_with(b"\r\n\r\n") && stream.read(&mut byte).is_ok_and(|n| n == 1) {
                head.push(byte[0]);
            }
            let reply = format!(
                "HTTP/1.1 200 OK\r\nContent-Type: image/png\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
                png.len()
            );
            let _ = stream.write_all(reply.as_bytes()).and_then(|()| stream.write_all(&png));
        }
    });
}

/// `run --panel` on a camera whose frames the test serves, holding the first until the test
/// reads the panel's event stream, so that no view is missed: each capture is published with
/// its frame and mark, the fit with its G-code and picture, and the panel ends with the run.
#[test]
fn a_run_publishes_its_captures_and_its_fit_and_exits_with_its_panel() {
    let dir = std::env::temp_dir().join(format!("mv-panel-run-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let profile = camera_profile(&dir);
    let listener = TcpListener::bind("127.0.0.1:0").expect("bound");
    let source = format!("http://{}/snapshot", listener.local_addr().expect("addr"));
    let (go, wait) = mpsc::channel();
    serve_snapshots(listener, centred_dot(), wait);
    let program = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/programs/04-rectangle-fit.nc");
    let mut child = Command::new(env!("CARGO_BIN_EXE_mach-vision"))
        .args(["run", "--quiet", "--clock", "0", "--panel", "127.0.0.1:0", "--camera", "camera", "--source", &source])
        .arg("--profile")
        .arg(&profile)
        .arg(program)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let mut stderr = BufReader::new(child.stderr.take().expect("stderr"));
    let mut line = String::new();
    while !line.contains("panel at ") {
        line.clear();
        assert!(stderr.read_line(&mut line).expect("stderr") > 0, "no panel address");
    }
    let addr = line.split("http://").nth(1).and_then(|r| r.split('/').next()).expect("address").to_string();
    let mut events = TcpStream::connect(&addr).expect("connect");
    events.set_read_timeout(Some(Duration::from_secs(60))).expect("timeout");
    events.write_all(b"GET /events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n").expect("sent");
    go.send(()).expect("the snapshot server waits");
    let views: Vec<serde_json::Value> = BufReader::new(events)
        .lines()
        .map_while(Result::ok)
        .filter_map(|l| l.strip_prefix("data: ").and_then(|d| serde_json::from_str(d).ok()))
        .collect();
    let mut rest = String::new();
    let _ = stderr.read_to_string(&mut rest);
    assert!(child.wait().expect("exit").success(), "{rest}");
    let capture = views.iter().find(|v| v["found"] == true && v["width"] == 1776).expect("a capture with its frame");
    assert!((capture["mark"]["x"].as_f64().expect("x") - 887.5).abs() < 0.5, "{capture}");
    let last = views.last().expect("views");
    let fit = &last["fit"];
    assert_eq!(fit["line"], 20, "{fit}");
    assert_eq!(fit["svg"], true, "{fit}");
    assert!(fit["gcode"].as_array().is_some_and(|g| !g.is_empty()), "{fit}");
    assert!(fit["bound99"].as_f64().is_some(), "{fit}");
    assert_eq!(last["found"], true, "the last capture stays beside the fit");
    let names: Vec<&str> = last["params"].as_array().expect("params").iter().filter_map(|p| p[0].as_str()).collect();
    assert!(names.contains(&"VisionCal_K11") && names.contains(&"VisionCameraMarkDiameterPx"), "{names:?}");
    assert!(last["telemetry"].as_array().is_some_and(|t| !t.is_empty()), "{last}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn run_s_panel_is_refused_off_loopback_without_a_token_and_a_token_needs_it() {
    for (args, says) in [
        (&["run", "--panel", "0.0.0.0:0", "-"][..], "--token"),
        (&["run", "--panel-token", "abc", "-"], "--panel-token needs --panel"),
    ] {
        let out = bounded(args, 1024, 30).unwrap_or_else(|| panic!("{args:?} did not exit"));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
    }
}
