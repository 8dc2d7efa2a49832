//! Streaming one line at a time (`Sender::push`, `Sender::finish`) and reading the controller's
//! state back, against the emulator on loopback and a scripted controller.

use std::io::{Read, Write};
use std::net::TcpListener;
use std::time::{Duration, Instant};

use vision_grbl::emulator::{Emulator, EmulatorConfig};
use vision_grbl::response::MachineState;
use vision_grbl::stream::{Sender, SenderOptions, StreamError};

const FAST: [(u16, f64); 6] = [(110, 6000.0), (111, 6000.0), (112, 6000.0), (120, 500.0), (121, 500.0), (122, 500.0)];

fn emulator(time_scale: f64, extra: &[(u16, f64)]) -> Emulator {
    let mut settings = FAST.to_vec();
    settings.extend_from_slice(extra);
    Emulator::bind("127.0.0.1:0", EmulatorConfig { time_scale, settings, ..Default::default() }).expect("bind")
}

fn connect(e: &Emulator, timeout: Duration) -> Sender {
    let options = SenderOptions { timeout, ..Default::default() };
    Sender::connect(&format!("tcp://{}", e.addr()), &options).expect("connect")
}

#[test]
fn pushes_short_moves_one_by_one_and_finishes_with_the_totals() {
    // At 20x the 15 planned segments cover about 20 ms of real time.
    let grbl = emulator(20.0, &[(10, 3.0)]);
    let mut s = connect(&grbl, Duration::from_secs(10));
    s.push("G21 G90 G1 F2000").expect("push");
    for i in 1..=300 {
        s.push(&format!("X{i} Y{}", if i % 2 == 0 { "0.1" } else { "0" })).expect("push");
    }
    assert_eq!(s.lines_pushed(), 301);
    let first = s.finish().expect("finish");
    assert_eq!(first.lines_sent, 301);
    assert!(first.longest_wait > Duration::ZERO, "the buffer filled");
    assert!(first.status_reports > 0 && first.planner_dry <= 2, "{first:?}");
    assert_eq!(s.wait_idle(Duration::from_secs(30)).expect("idle").mpos, Some([300.0, 0.1, 0.0]));
    // A deliberate stop (a camera capture) between finish and the next push: the poll that
    // push sends first sees Idle before the line is answered, and that is not running dry.
    std::thread::sleep(Duration::from_millis(250));
    s.push("G0 Y5").expect("push");
    let total = s.finish().expect("finish");
    assert_eq!((total.lines_sent, total.bytes_sent), (302, first.bytes_sent + 6), "totals since connect");
    assert!(total.status_reports > first.status_reports, "{total:?}");
    assert_eq!(total.planner_dry, first.planner_dry, "{total:?}");
    assert_eq!(s.wait_idle(Duration::from_secs(10)).expect("idle").mpos, Some([300.0, 5.0, 0.0]));
}

#[test]
fn an_error_stops_pushing_for_good_until_unlatched() {
    let grbl = emulator(20.0, &[]);
    let mut s = connect(&grbl, Duration::from_secs(10));
    s.push("G21 G90").expect("push");
    s.finish().expect("finish");
    let lines: Vec<String> = (1..=10)
        .map(|i| format!("G1 X{i} F3000"))
        .chain(["G68 X0 Y0 R5".to_string()])
        .chain((11..=20).map(|i| format!("G1 X{i}")))
        .collect();
    let mut refusal = None;
    let mut refused_after = 0;
    for line in &lines {
        match s.push(line) {
            Ok(()) => assert!(refusal.is_none(), "{line} was sent after the error"),
            Err(StreamError::Stopped { at }) => {
                assert_eq!(at, 11);
                refused_after += 1;
            }
            Err(e) => refusal = Some(e),
        }
    }
    let refusal = match refusal {
        Some(e) => e,
        None => s.finish().expect_err("G68"),
    };
    let StreamError::Firmware { index, code, in_flight, ref text } = refusal else { panic!("{refusal}") };
    assert_eq!((index, code, text.as_str()), (11, 20, "G68 X0 Y0 R5"), "indexes count since connect");
    assert!(matches!(s.finish(), Err(StreamError::Stopped { at: 11 })));
    assert!(matches!(s.push("G0 X0"), Err(StreamError::Stopped { at: 11 })));
    // Grbl ran the lines already in its buffer behind G68 and nothing else.
    let status = s.wait_idle(Duration::from_secs(10)).expect("idle");
    assert_eq!(status.mpos.map(|p| p[0]), Some(10.0 + f64::from(u8::try_from(in_flight).expect("few"))));
    assert_eq!(s.lines_pushed(), 12 + in_flight, "{refused_after} refused");
    s.unlatch().expect("unlatch");
    s.push("G0 X0").expect("pushing starts again");
    s.finish().expect("finish");
    assert_eq!(s.wait_idle(Duration::from_secs(10)).expect("idle").mpos, Some([0.0; 3]));
}

#[test]
fn lines_with_real_time_bytes_or_too_long_are_refused_unsent() {
    let grbl = emulator(20.0, &[]);
    let mut s = connect(&grbl, Duration::from_secs(10));
    s.push("G21").expect("push");
    for (line, byte) in [("G0 X1 (why?)", b'?'), ("G0 X1 (\u{d8} 6)", 0xc3), ("G0 X1\nG0 X2", b'\n'), ("G0 X1!", b'!')]
    {
        match s.push(line) {
            Err(StreamError::RealTimeByte { index: 1, byte: b }) => assert_eq!(b, byte, "{line}"),
            other => panic!("{line}: {other:?}"),
        }
    }
    let long = format!("G0 X1 ({})", "c".repeat(130));
    assert!(matches!(s.push(&long), Err(StreamError::LineTooLong { index: 1, len: 139, limit: 128 })));
    assert_eq!(s.lines_pushed(), 1);
    assert_eq!(s.finish().expect("finish").lines_sent, 1);
    assert_eq!(s.wait_idle(Duration::from_secs(10)).expect("idle").mpos, Some([0.0; 3]));
}

#[test]
fn a_lost_connection_mid_push_names_the_line_reached_and_stops() {
    let grbl = emulator(20.0, &[]);
    let mut s = connect(&grbl, Duration::from_secs(10));
    let dropper = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(300));
        grbl.disconnect();
        grbl
    });
    let mut lost = None;
    for i in 1..=200 {
        if let Err(e) = s.push(&format!("G1 X{i} F600")) {
            lost = Some(e);
            break;
        }
    }
    let lost = match lost {
        Some(e) => e,
        None => s.finish().expect_err("lost"),
    };
    let _grbl = dropper.join().expect("join");
    let StreamError::ConnectionLost { reached: Some(reached), .. } = lost else { panic!("{lost:?}") };
    assert!(reached < 199, "{reached}");
    assert!(matches!(s.push("G0 X0"), Err(StreamError::Stopped { at }) if at == reached + 1));
}

#[test]
fn feed_hold_freezes_the_machine_and_push_waits_past_the_timeout_until_resume() {
    let grbl = emulator(20.0, &[]);
    // A short timeout: the hold below lasts several times longer.
    let mut s = connect(&grbl, Duration::from_millis(500));
    // 40 mm at 300 mm/min: 0.4 s at 20x to put the hold in.
    s.push("G21 G91 G1 F300").expect("push");
    for _ in 0..40 {
        s.push("X1").expect("push");
    }
    let control = s.control();
    control.feed_hold().expect("hold");
    std::thread::sleep(Duration::from_millis(100));
    let held = s.status().expect("status");
    assert_eq!(held.state, Some(MachineState::Hold));
    let x = held.mpos.expect("mpos")[0];
    assert!(x < 40.0, "{x}");
    let until = Instant::now() + Duration::from_millis(300);
    while Instant::now() < until {
        let later = s.status().expect("status");
        assert_eq!((later.state, later.mpos), (Some(MachineState::Hold), held.mpos), "frozen while held");
    }
    let resumer = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(1500));
        control.resume().expect("resume");
    });
    // The buffer is full: these pushes wait the whole hold, three times the timeout.
    let start = Instant::now();
    for _ in 0..40 {
        s.push("X1").expect("push waits while held");
    }
    let report = s.finish().expect("finish");
    assert!(start.elapsed() > Duration::from_millis(1000), "{:?}", start.elapsed());
    resumer.join().expect("join");
    assert_eq!(report.lines_sent, 81);
    assert_eq!(s.wait_idle(Duration::from_secs(10)).expect("idle").mpos, Some([80.0, 0.0, 0.0]));
}

#[test]
fn offsets_parser_state_and_settings_read_the_emulator() {
    let config = EmulatorConfig {
        time_scale: 20.0,
        settings: FAST.to_vec(),
        work_offsets: [[1.0, 2.0, 3.0], [-10.0, 0.5, 0.0], [0.0; 3], [0.0; 3], [0.0; 3], [7.0, 8.0, -9.0]],
        start: [-5.0, -6.0, -7.0],
        ..Default::default()
    };
    let grbl = Emulator::bind("127.0.0.1:0", config).expect("bind");
    let mut s = connect(&grbl, Duration::from_millis(500));
    assert_eq!(s.status().expect("status").mpos, Some([-5.0, -6.0, -7.0]));
    // A move of 2 s, four times the timeout: `$#` waits for it to end (Grbl answers error:8
    // to `$#` while moving).
    s.push("G21 G90 G1 X35 F1200").expect("push");
    s.push("G92 Z1").expect("push");
    let o = s.offsets().expect("offsets");
    assert_eq!(s.last_status().and_then(|st| st.mpos).map(|p| p[0]), Some(36.0), "X35 in G54");
    assert_eq!(o.work, [[1.0, 2.0, 3.0], [-10.0, 0.5, 0.0], [0.0; 3], [0.0; 3], [0.0; 3], [7.0, 8.0, -9.0]]);
    assert_eq!((o.g28, o.g30, o.g92, o.tlo), ([0.0; 3], [0.0; 3], [0.0, 0.0, -11.0], 0.0));
    s.push("G55 G91 G18 T3 F250 M3 S1000").expect("push");
    let p = s.parser_state().expect("$G");
    assert_eq!((p.work_system, p.incremental, p.plane, p.tool, p.feed, p.spindle), (2, true, 18, 3, 250.0, 1000.0));
    assert!(!p.inches);
    s.push("G20").expect("push");
    assert!(s.parser_state().expect("$G").inches);
    let settings = s.settings().expect("$$");
    assert!(settings.contains(&(13, 0.0)) && settings.contains(&(110, 6000.0)), "{settings:?}");
    assert_eq!(settings.first(), Some(&(0, 10.0)));
}

#[test]
fn a_dollar_line_goes_out_in_alarm_as_grbl_takes_it() {
    // Homing enabled: the controller powers up locked in Alarm, and `$H` is what unlocks it.
    let config =
        EmulatorConfig { time_scale: 20.0, settings: vec![(22, 1.0)], start: [5.0, 5.0, 5.0], ..Default::default() };
    let grbl = Emulator::bind("127.0.0.1:0", config).expect("bind");
    let mut s = connect(&grbl, Duration::from_secs(10));
    assert_eq!(s.status().expect("status").state, Some(MachineState::Alarm));
    s.push("$H").expect("push");
    s.finish().expect("finish");
    assert_eq!(s.wait_idle(Duration::from_secs(10)).expect("idle").mpos, Some([0.0; 3]));
}

/// A controller that answers `$I` and, if `idle`, status polls, and nothing else; it hangs up
/// after 5 s.
fn scripted(idle: bool) -> std::net::SocketAddr {
    let listener = TcpListener::bind("127.0.0.1:0").expect("bind");
    let addr = listener.local_addr().expect("addr");
    std::thread::spawn(move || {
        let Ok((mut socket, _)) = listener.accept() else { return };
        socket.set_read_timeout(Some(Duration::from_millis(50))).expect("timeout");
        let end = Instant::now() + Duration::from_secs(5);
        let mut line = Vec::new();
        let mut buf = [0u8; 256];
        while Instant::now() < end {
            let n = match socket.read(&mut buf) {
                Ok(0) => return,
                Ok(n) => n,
                Err(_) => continue,
            };
            for &b in &buf[..n] {
                let answer: &[u8] = match b {
                    b'?' if idle => b"<Idle|MPos:0.000,0.000,0.000|FS:0,0>\r\n",
                    b'\n' if line == b"$I" => b"[VER:1.1h.20190830:]\r\n[OPT:V,15,128]\r\nok\r\n",
                    _ => b"",
                };
                if b == b'\n' {
                    line.clear();
                } else if b != b'?' {
                    line.push(b);
                }
                let _ = socket.write_all(answer);
            }
        }
    });
    addr
}

#[test]
fn a_silent_controller_or_one_idle_without_answering_times_out() {
    for idle in [false, true] {
        let options = SenderOptions { timeout: Duration::from_millis(300), ..Default::default() };
        let mut s = Sender::connect(&format!("tcp://{}", scripted(idle)), &options).expect("connect");
        s.push("G0 X1").expect("push");
        let start = Instant::now();
        assert!(matches!(s.finish(), Err(StreamError::Timeout(_))), "idle: {idle}");
        assert!(start.elapsed() < Duration::from_secs(3), "idle: {idle}");
    }
}

#[test]
fn a_reset_or_an_alarm_stops_pushing() {
    let grbl = emulator(1.0, &[]);
    let mut s = connect(&grbl, Duration::from_secs(10));
    let control = s.control();
    // A reset during a dwell: no alarm (nothing moves), but the queued line is gone.
    s.push("G4 P0.5").expect("push");
    s.push("G0 X1").expect("push");
    control.soft_reset().expect("reset");
    match s.finish() {
        Err(StreamError::ConnectionLost { reason, reached: None }) => assert!(reason.contains("reset"), "{reason}"),
        other => panic!("{other:?}"),
    }
    assert!(matches!(s.push("G0 X2"), Err(StreamError::Stopped { at: 0 })));
    s.unlatch().expect("unlatch");
    // A reset in motion: ALARM:3, read by the next push, which sends nothing.
    s.push("G1 X50 F3000").expect("push");
    s.finish().expect("finish");
    control.soft_reset().expect("reset");
    std::thread::sleep(Duration::from_millis(100));
    assert!(matches!(s.push("G0 X0"), Err(StreamError::Alarm { code: 3, reached: Some(2) })));
    assert!(matches!(s.push("G0 X0"), Err(StreamError::Stopped { at: 3 })));
    assert_eq!(s.lines_pushed(), 3);
}
