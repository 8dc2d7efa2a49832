//! The sender against the emulator on loopback (each test starts its own, on a free port).

use std::time::Duration;

use vision_grbl::emulator::{Emulator, EmulatorConfig, Flavour};
use vision_grbl::response::MachineState;
use vision_grbl::stream::{needs_idle, needs_sync, Sender, SenderOptions, StreamError};

fn emulator(flavour: Flavour) -> Emulator {
    let config = EmulatorConfig {
        flavour,
        time_scale: 20.0,
        settings: vec![(110, 6000.0), (111, 6000.0), (112, 6000.0), (120, 500.0), (121, 500.0), (122, 500.0)],
        ..Default::default()
    };
    Emulator::bind("127.0.0.1:0", config).expect("bind")
}

fn connect(e: &Emulator) -> Sender {
    let options = SenderOptions { timeout: Duration::from_secs(10), ..Default::default() };
    Sender::connect(&format!("tcp://{}", e.addr()), &options).expect("connect")
}

#[test]
fn learns_the_buffer_from_dollar_i() {
    let grbl = emulator(Flavour::Grbl);
    let s = connect(&grbl);
    assert_eq!((s.rx_buffer(), s.planner_blocks(), s.is_grblhal()), (128, Some(15), false));
    let hal = emulator(Flavour::GrblHal);
    let s = connect(&hal);
    assert_eq!((s.rx_buffer(), s.planner_blocks(), s.is_grblhal()), (1023, Some(100), true), "one slot kept free");
}

#[test]
fn lines_that_write_eeprom_or_settings_go_alone() {
    for line in ["$110=500", "G10 L2 P1 X0", "g54", "G28.1", "G30.1", "G0 G55 X1"] {
        assert!(needs_sync(line), "{line}");
    }
    for line in ["G1 X1", "G92 X0", "(G54) G0 X1", "G0 X1 ; G10", "G540"] {
        assert!(!needs_sync(line), "{line}");
    }
}

#[test]
fn a_setting_waits_for_the_machine_to_stop() {
    let grbl = emulator(Flavour::Grbl);
    let mut s = connect(&grbl);
    assert!(needs_idle("$10=3") && needs_idle("$#") && !needs_idle("$G") && !needs_idle("G1 X1"));
    // Grbl answers error:8 to a setting while moving; the sender waits for Idle instead.
    let report = s.stream(&["G1 X30 F3000", "$10=3", "G1 X0"]).expect("stream");
    assert_eq!(report.planner_dry, 0, "a stop for a setting is not the planner running dry");
    let status = s.wait_idle(Duration::from_secs(10)).expect("idle");
    assert!(status.buffer.is_some(), "$10=3 took: reports carry Bf");
    assert_eq!(status.mpos, Some([0.0; 3]));
}

#[test]
fn an_error_mid_stream_stops_names_the_line_and_sends_nothing_after() {
    let grbl = emulator(Flavour::Grbl);
    let mut s = connect(&grbl);
    let lines = ["G21 G90", "G1 X1 F3000", "G68 X0 Y0 R5", "G1 X2", "G1 X3"];
    match s.stream(&lines) {
        Err(StreamError::Firmware { index, code, text, in_flight }) => {
            assert_eq!((index, code, text.as_str()), (2, 20, "G68 X0 Y0 R5"));
            assert_eq!(in_flight, 2, "character counting had the next two lines in the buffer");
        }
        other => panic!("{other:?}"),
    }
    // Grbl classic ran the two lines behind the error; nothing beyond them was sent.
    let status = s.wait_idle(Duration::from_secs(10)).expect("idle");
    assert_eq!(status.mpos, Some([3.0, 0.0, 0.0]));
    let lines: Vec<String> = (0..40)
        .map(|i| format!("G1 X{} F3000", i % 5))
        .chain(["M280".to_string()])
        .chain((0..5).map(|i| format!("G1 Y{i}")))
        .collect();
    let err = s.stream(&lines).expect_err("M280");
    assert!(matches!(err, StreamError::Firmware { index: 40, code: 23, .. }), "{err}");
    assert!(err.to_string().starts_with("line 41 (\"M280\"): the controller answered error:23"), "{err}");
}

#[test]
fn grblhal_answers_the_lines_behind_an_error_with_the_same_error_until_unlatched() {
    let hal = emulator(Flavour::GrblHal);
    let mut s = connect(&hal);
    let err = s.stream(&["G1 X1 F3000", "G68 X0 Y0 R1", "G1 X2", "G1 X3"]).expect_err("G68");
    assert!(matches!(err, StreamError::Firmware { index: 1, code: 20, in_flight: 2, .. }), "{err}");
    let status = s.wait_idle(Duration::from_secs(10)).expect("idle");
    assert_eq!(status.mpos, Some([1.0, 0.0, 0.0]), "the latched lines did not move");
    assert!(matches!(s.stream(&["G1 X5"]), Err(StreamError::Firmware { code: 20, .. })));
    s.unlatch().expect("unlatch");
    s.stream(&["G1 X5"]).expect("runs again");
}

#[test]
fn a_lost_connection_ends_with_the_line_reached() {
    let grbl = emulator(Flavour::Grbl);
    let mut s = connect(&grbl);
    let lines: Vec<String> = (1..=200).map(|i| format!("G1 X{i} F600")).collect();
    let dropper = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(400));
        grbl.disconnect();
        grbl
    });
    let err = s.stream(&lines).expect_err("lost");
    let _grbl = dropper.join().expect("join");
    match err {
        StreamError::ConnectionLost { reached, .. } => {
            let reached = reached.expect("some lines were answered");
            assert!(reached < 199, "{reached}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn feed_hold_and_resume_from_another_thread() {
    let grbl = emulator(Flavour::Grbl);
    let mut s = connect(&grbl);
    // 10 s of motion at 20x: half a second to hold it in, even on a loaded machine.
    s.stream(&["G1 X100 F600"]).expect("stream");
    let control = s.control();
    std::thread::sleep(Duration::from_millis(20));
    control.feed_hold().expect("hold");
    std::thread::sleep(Duration::from_millis(50));
    let held = s.status().expect("status");
    assert_eq!(held.state, Some(MachineState::Hold));
    std::thread::sleep(Duration::from_millis(100));
    let later = s.status().expect("status");
    assert_eq!(held.mpos, later.mpos);
    assert!(held.mpos.expect("mpos")[0] < 100.0);
    control.resume().expect("resume");
    let done = s.wait_idle(Duration::from_secs(20)).expect("idle");
    assert_eq!(done.mpos, Some([100.0, 0.0, 0.0]));
    // A soft reset in motion: ALARM:3.
    s.stream(&["G1 X0 F3000"]).expect("stream");
    control.soft_reset().expect("reset");
    assert!(matches!(s.wait_idle(Duration::from_secs(5)), Err(StreamError::Alarm { .. })));
}

#[test]
fn streams_1000_short_segments_with_the_planner_fed() {
    let config = EmulatorConfig {
        time_scale: 20.0,
        settings: vec![(10, 3.0), (110, 6000.0), (111, 6000.0), (120, 500.0), (121, 500.0)],
        ..Default::default()
    };
    let grbl = Emulator::bind("127.0.0.1:0", config).expect("bind");
    let mut s = connect(&grbl);
    // 1000 segments of 1 mm at 2000 mm/min on a zig-zag that keeps moving forward.
    let mut lines = vec!["G21 G90 G1 F2000".to_string()];
    lines.extend((1..=1000).map(|i| format!("X{} Y{}", i, if i % 2 == 0 { "0.1" } else { "0" })));
    let report = s.stream(&lines).expect("stream");
    assert_eq!(report.lines_sent, 1001);
    assert_eq!(report.bytes_sent, lines.iter().map(|l| l.len() + 1).sum::<usize>());
    assert!(report.longest_wait > Duration::ZERO, "the buffer filled");
    let status = s.wait_idle(Duration::from_secs(30)).expect("idle");
    assert_eq!(status.mpos.map(|p| p[0]), Some(1000.0));
    // Lines ahead cover about 35 ms of real time here: a scheduler stall longer than that on a
    // busy machine can drain the planner once or twice; a sender that cannot keep up drains it
    // on most of the 1000 segments.
    assert!(report.planner_dry <= 2, "{report:?}");
}

#[cfg(unix)]
#[test]
fn streams_over_a_pseudo_terminal() {
    use vision_grbl::emulator::PtyEmulator;
    let config = EmulatorConfig { time_scale: 20.0, ..Default::default() };
    let pty = PtyEmulator::open(config).expect("pty");
    let port = pty.path().to_str().expect("utf-8").to_string();
    let mut s = Sender::connect(&port, &SenderOptions::default()).expect("connect");
    assert_eq!(s.rx_buffer(), 128);
    s.stream(&["G21 G91", "G1 X1 F500", "G1 Y1"]).expect("stream");
    let status = s.wait_idle(Duration::from_secs(10)).expect("idle");
    assert_eq!(status.mpos, Some([1.0, 1.0, 0.0]));
    let refused = Sender::connect(&port, &SenderOptions { baud: Some(12345), ..Default::default() });
    assert!(matches!(refused, Err(StreamError::Open { .. })), "an unknown baud rate is refused");
}

#[test]
fn a_dwell_mid_stream_counts_as_the_planner_running_dry() {
    let config = EmulatorConfig { time_scale: 20.0, settings: vec![(10, 3.0)], ..Default::default() };
    let grbl = Emulator::bind("127.0.0.1:0", config).expect("bind");
    let mut s = connect(&grbl);
    // 8 s of dwell at 20x: 400 ms, two polls at least see an empty planner with a line to come.
    let report = s.stream(&["G1 X1 F500", "G4 P8", "G1 X2"]).expect("stream");
    assert_eq!(report.planner_dry, 1, "{report:?}");
    assert!(report.status_reports >= 2, "{report:?}");
}

/// A sender that goes leaves the controller free for the next one (the emulator serves one
/// client at a time, as a serial port does): its socket is shut down, though its reader
/// thread still holds a clone.
#[test]
fn a_dropped_sender_frees_the_controller_for_the_next() {
    let grbl = emulator(Flavour::Grbl);
    for _ in 0..3 {
        let options = SenderOptions { timeout: Duration::from_secs(2), ..Default::default() };
        let mut sender = Sender::connect(&format!("tcp://{}", grbl.addr()), &options).expect("connects again");
        sender.stream(&["G1 X1 F6000"]).expect("streams");
    }
}
