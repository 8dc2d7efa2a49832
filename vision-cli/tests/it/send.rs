//! `mach-vision send`: Grbl's examples streamed to the Grbl emulator — over loopback TCP (an
//! emulator this process starts) and over a pseudo-terminal (`mach-vision emulate grbl --pty`)
//! — with the simulated camera looking where the controller reports the machine, and the
//! truth reported. Then what can go wrong while streaming: a refused line, a lost connection,
//! Ctrl-C.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::Duration;

use serde_json::Value;
use vision_driver_sim::World;
use vision_grbl::emulator::{Emulator, EmulatorConfig};

/// Simulated seconds per real second: the examples' moves take a moment, the 5 Hz status polls
/// before each capture the rest.
const TIME_SCALE: f64 = 50.0;

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../hosts/grbl/examples").join(name)
}

/// A scratch folder of this test process.
fn scratch(name: &str) -> PathBuf {
    crate::common::scratch("send", name)
}

/// The built-in world's machine as a Grbl controller (what `emulate grbl` serves): G54 and the
/// power-up position in mm.
fn world_config() -> EmulatorConfig {
    let world = World::default_world();
    let mm = 25.4;
    assert_eq!(world.length_unit(), vision_math::LengthUnit::Inch, "the built-in world is in inches");
    let mut work_offsets = [[0.0; 3]; 6];
    work_offsets[0] = world.machine.work_offset.map(|v| v * mm);
    EmulatorConfig {
        time_scale: TIME_SCALE,
        work_offsets,
        start: world.machine.start.map(|v| v * mm),
        ..EmulatorConfig::default()
    }
}

fn send(port: &str, program: &Path, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mach-vision"))
        .args(["send", "--json", "--port", port])
        .args(extra)
        .arg(program)
        .stdin(Stdio::null())
        .output()
        .expect("spawn")
}

fn report(out: &Output) -> Value {
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "not JSON ({e}): {}\nstderr: {}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        )
    })
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The step of `kind` in the report's first program.
fn step(report: &Value, kind: &str) -> Value {
    report["programs"][0]["steps"].as_array().expect("steps").iter().find(|s| s["type"] == kind).cloned().expect(kind)
}

/// Streams example `name` to a fresh emulator on loopback TCP; the report.
fn send_example(name: &str) -> Value {
    let grbl = Emulator::bind("127.0.0.1:0", world_config()).expect("emulator");
    let out = send(&format!("tcp://{}", grbl.addr()), &example(name), &[]);
    assert!(out.status.success(), "{name}: {}", stderr(&out));
    let report = report(&out);
    let streaming = &report["streaming"];
    assert_eq!(streaming["firmware"], "Grbl", "{streaming}");
    assert!(streaming["lines_sent"].as_u64().is_some_and(|n| n > 10), "{streaming}");
    assert_eq!(streaming["rx_buffer"], 128, "{streaming}");
    report
}

/// Example 4 streamed: the host applies the whole chain to the moves it sends, and the cut lands
/// on the true part within 0.0005 in.
#[test]
fn example_4_streams_and_lands_on_the_true_part() {
    let report = send_example("04-rectangle-fit.nc");
    let fit = step(&report, "fit");
    assert_eq!(fit["applied_by"], "host", "{fit}");
    let landed = fit["cut_error"]["max"].as_f64().expect("the truth");
    assert!(landed < 0.0005, "example 4 lands {landed} in from the true part");
    assert!(report["programs"][0]["outcome"].as_str().is_some_and(|o| o.starts_with("ended by M30")), "{report}");
}

/// Example 5 (a similarity) and example 1 (the sheet walk, whose every capture waits for the
/// controller to stop) streamed.
#[test]
fn examples_1_and_5_stream_with_the_truth() {
    let fit = step(&send_example("05-similarity-fit.nc"), "fit");
    assert!(fit["cut_error"]["max"].as_f64().expect("the truth") < 0.002, "{fit}");
    let report = send_example("01-calibrate-sheet.nc");
    let truth = &report["programs"][0]["calibration_truth"];
    assert!(truth["offset_error"].as_f64().expect("the truth") < 0.001, "{truth}");
}

/// The CAM job: tool changes, a drilling cycle and a subprogram expanded by the host, under the
/// host's alignment.
#[test]
fn the_cam_job_streams_expanded_and_aligned() {
    let report = send_example("08-cam-job.nc");
    let program = &report["programs"][0];
    assert!(program["outcome"].as_str().is_some_and(|o| o.starts_with("ended by M30")), "{program}");
    assert!(program["moves"].as_u64().is_some_and(|n| n > 100), "{program}");
}

/// A child `mach-vision emulate grbl --pty`, and the pseudo-terminal's path it printed.
#[cfg(unix)]
fn pty_emulator() -> (Child, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_mach-vision"))
        .args(["emulate", "grbl", "--pty", "--time-scale", "50"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn");
    let mut line = String::new();
    BufReader::new(child.stdout.take().expect("stdout")).read_line(&mut line).expect("the emulator's line");
    let path = line.split_whitespace().find(|w| w.starts_with("/dev/")).map(|w| w.trim_end_matches(';').to_string());
    (child, path.unwrap_or_else(|| panic!("no pty in {line:?}")))
}

/// Over a pseudo-terminal, as over a USB serial port: example 4 lands as over TCP.
#[cfg(unix)]
#[test]
fn example_4_streams_over_a_pseudo_terminal() {
    let (mut child, path) = pty_emulator();
    let out = send(&path, &example("04-rectangle-fit.nc"), &[]);
    let _ = child.kill();
    let _ = child.wait();
    assert!(out.status.success(), "{}", stderr(&out));
    let fit = step(&report(&out), "fit");
    assert!(fit["cut_error"]["max"].as_f64().expect("the truth") < 0.0005, "{fit}");
}

/// A program of `moves` 1 mm moves at `feed` mm/min, with `middle` after the first half.
fn moves_program(dir: &Path, moves: usize, feed: f64, middle: &str) -> PathBuf {
    let mut text = String::from("G21 G90 G54\nG0 X0 Y0\n");
    for i in 0..moves {
        if i == moves / 2 {
            text.push_str(middle);
            text.push('\n');
        }
        text.push_str(&format!("G1 X{} F{feed}\n", (i + 1) % 2));
    }
    text.push_str("M30\n");
    let path = dir.join("moves.nc");
    std::fs::write(&path, text).expect("write");
    path
}

/// A firmware built without mist coolant refuses M7 mid-stream: the run stops at that line,
/// names it and the firmware's error, and sends nothing more.
#[test]
fn a_line_the_firmware_refuses_stops_the_stream_at_that_line() {
    let dir = scratch("refused");
    let program = moves_program(&dir, 200, 3000.0, "M7");
    let grbl = Emulator::bind("127.0.0.1:0", EmulatorConfig { m7: false, ..world_config() }).expect("emulator");
    let out = send(&format!("tcp://{}", grbl.addr()), &program, &[]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("`M7` (program line 103)") && err.contains("error:20"), "{err}");
    let report = report(&out);
    assert_eq!(report["programs"][0]["outcome"], "failed at line 103", "{report}");
    // The preamble, G0, 100 moves and M7; then what fitted the 128-byte buffer behind it
    // before its error came back (moves of 3 bytes: `X1`), and nothing after.
    let sent = report["streaming"]["lines_sent"].as_u64().expect("lines sent");
    assert!((103..=103 + 128 / 3).contains(&sent), "{sent} lines sent: {err}");
    assert!(err.contains("a feed hold and a soft reset discarded the"), "{err}");
}

/// `send` started on a job of 400 moves at 600 mm/min (40 s) on a controller timing them in
/// real time, to be stopped while it runs; the controller, and the child.
fn slow_job(name: &str) -> (Emulator, Child) {
    let program = moves_program(&scratch(name), 400, 600.0, "");
    let grbl = Emulator::bind("127.0.0.1:0", EmulatorConfig { time_scale: 1.0, ..world_config() }).expect("emulator");
    let child = Command::new(env!("CARGO_BIN_EXE_mach-vision"))
        .args(["send", "--json", "--port", &format!("tcp://{}", grbl.addr())])
        .arg(&program)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    (grbl, child)
}

/// The cable pulled mid-job: the run stops with the line the controller reached.
#[test]
fn a_lost_connection_stops_the_run_with_the_line_reached() {
    let (grbl, child) = slow_job("lost");
    std::thread::sleep(Duration::from_millis(1500));
    grbl.disconnect();
    let out = child.wait_with_output().expect("output");
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("connection") && err.contains("lost") && err.contains("after line"), "{err}");
    let outcome = report(&out)["programs"][0]["outcome"].as_str().unwrap_or_default().to_string();
    assert!(outcome.starts_with("failed at line"), "{outcome}");
}

/// Ctrl-C with no terminal to ask on: the first holds the feed, the second soft-resets and the
/// run stops, saying the operator did it.
#[cfg(unix)]
#[test]
fn ctrl_c_holds_then_a_second_resets() {
    let (_grbl, child) = slow_job("ctrlc");
    let pid = child.id().to_string();
    let interrupt = || {
        let status = Command::new("kill").args(["-INT", &pid]).status().expect("kill");
        assert!(status.success());
    };
    std::thread::sleep(Duration::from_millis(1500));
    interrupt();
    std::thread::sleep(Duration::from_millis(800));
    interrupt();
    let out = child.wait_with_output().expect("output");
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("feed hold") && err.contains("soft reset"), "{err}");
    assert!(err.contains("operator"), "{err}");
}

/// A controller in alarm is refused before anything is sent, with what to do.
#[test]
fn a_controller_in_alarm_is_refused_with_the_way_out() {
    let dir = scratch("alarm");
    let program = moves_program(&dir, 4, 600.0, "");
    // Homing enabled: Grbl powers up locked in alarm until homed or unlocked.
    let config = EmulatorConfig { settings: vec![(22, 1.0)], ..world_config() };
    let grbl = Emulator::bind("127.0.0.1:0", config).expect("emulator");
    let out = send(&format!("tcp://{}", grbl.addr()), &program, &[]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("alarm") && err.contains("$H") && err.contains("$X"), "{err}");
}

/// M0 waits for an operator: with no terminal to ask on, the job stops there, saying so.
#[test]
fn a_program_stop_without_a_terminal_stops_the_job_there() {
    let dir = scratch("m0");
    let program = moves_program(&dir, 10, 3000.0, "M0");
    let grbl = Emulator::bind("127.0.0.1:0", world_config()).expect("emulator");
    let out = send(&format!("tcp://{}", grbl.addr()), &program, &[]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("M0 at line 8") && err.contains("no terminal"), "{err}");
    assert_eq!(report(&out)["programs"][0]["outcome"], "failed at line 8");
}

/// A controller set to report work positions (`$10=0`: `WPos`, no `MPos`): the machine position
/// is `WPos` + `WCO`, and the job lands as with `MPos`.
#[test]
fn work_position_reports_are_read_with_the_work_offset() {
    // Powered up half a millimetre below the world's start: a Z the program leaves alone until
    // its captures are done, so a start read wrongly would show as a refused capture.
    let mut config = EmulatorConfig { settings: vec![(10, 0.0)], ..world_config() };
    config.start[2] = -0.5;
    let grbl = Emulator::bind("127.0.0.1:0", config).expect("emulator");
    let out = send(&format!("tcp://{}", grbl.addr()), &example("04-rectangle-fit.nc"), &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    let fit = step(&report(&out), "fit");
    assert!(fit["cut_error"]["max"].as_f64().expect("the truth") < 0.0005, "{fit}");
}
