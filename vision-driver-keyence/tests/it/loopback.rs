//! The driver against the emulator over real loopback TCP: every output format, every `ER`
//! code, every fault. Each failure must come back typed within timeout + 20 % (see
//! `common::SLACK`), and the next trigger must be answered correctly.
#![expect(clippy::float_cmp, reason = "tests compare exact values")]

use crate::common;

use std::time::{Duration, Instant};

use common::{assert_within, counting, driver, start, T};
use vision_core::{CameraDriver, DriverErrorKind, DriverRegistry, Judgment, Reading, VisionError};
use vision_driver_keyence::emulator::{
    Delimiter, Emulator, Fault, JudgmentStyle, ListSource, Mode, NumberStyle, OutputFormat, Series, Shot,
};
use vision_driver_keyence::{register, JobCommand, KeyenceConfig, KeyenceDriver, KeyenceError, Program};

fn mark() -> Reading {
    Reading {
        judgment: Judgment::Ok,
        count: Some(1),
        x_px: 812.125,
        y_px: -903.5,
        width_px: 40.25,
        height_px: 39.75,
        angle_deg: -12.5,
        score: 97.25,
    }
}

#[test]
fn every_output_format_number_style_judgment_and_delimiter() {
    for format in [OutputFormat::Xy, OutputFormat::JudgmentXy, OutputFormat::Full] {
        for numbers in [NumberStyle::Plain, NumberStyle::FixedWidth] {
            for judgment in [JudgmentStyle::Digit, JudgmentStyle::Word] {
                for delimiter in [Delimiter::Cr, Delimiter::CrLf, Delimiter::Lf] {
                    let ng = Reading { judgment: Judgment::Ng, count: Some(0), ..mark() };
                    let em = start(
                        Emulator::builder()
                            .source(ListSource::readings([mark(), ng]))
                            .format(format)
                            .numbers(numbers)
                            .judgment(judgment)
                            .delimiter(delimiter),
                    );
                    let mut d = driver(&em, T);
                    let what = format!("{format:?} {numbers:?} {judgment:?} {delimiter:?}");
                    for _ in 0..2 {
                        let r = d.measure().unwrap_or_else(|e| panic!("{what}: {e}"));
                        assert_eq!((r.x_px, r.y_px), (mark().x_px, mark().y_px), "{what}");
                        match format {
                            OutputFormat::Xy => assert_eq!((r.judgment, r.count), (Judgment::Unknown, None)),
                            OutputFormat::JudgmentXy => assert_eq!(r.judgment, Judgment::Ok, "{what}"),
                            OutputFormat::Full => assert_eq!(r, mark(), "{what}"),
                        }
                        let r = d.measure().unwrap_or_else(|e| panic!("{what}: {e}"));
                        if format != OutputFormat::Xy {
                            assert_eq!(r.judgment, Judgment::Ng, "{what}");
                            assert!(!r.found());
                        }
                    }
                    assert_eq!(em.stats().connections, 1, "{what}: one connection reused");
                    assert_eq!(em.stats().triggers, 4);
                }
            }
        }
    }
}

#[test]
fn verbatim_lines_from_the_manual() {
    let lines = [
        ("150.0,75.5", Judgment::Unknown, None, 150.0, 75.5),
        ("1,150.0,75.5", Judgment::Ok, None, 150.0, 75.5),
        ("OK,150.0,75.5", Judgment::Ok, None, 150.0, 75.5),
        ("NG,150.0,75.5", Judgment::Ng, None, 150.0, 75.5),
        ("0,150.0,75.5", Judgment::Ng, None, 150.0, 75.5),
        ("1,0,0,0,0,0,0,0", Judgment::Ok, Some(0), 0.0, 0.0),
        ("+0000000888.123000,-0000000012.500000", Judgment::Unknown, None, 888.123, -12.5),
    ];
    let em = start(
        Emulator::builder()
            .source(ListSource::cycling(lines.iter().map(|(l, ..)| Shot::Line((*l).to_string())).collect())),
    );
    let mut d = driver(&em, T);
    for (line, judgment, count, x, y) in lines {
        let r = d.measure().unwrap_or_else(|e| panic!("{line}: {e}"));
        assert_eq!((r.judgment, r.count, r.x_px, r.y_px), (judgment, count, x, y), "{line}");
    }
}

#[test]
fn every_er_code_is_typed_fast_and_keeps_the_connection() {
    let (source, _) = counting();
    let em = start(Emulator::builder().source(source));
    let mut d = driver(&em, T);
    for code in 1..=7u8 {
        em.inject(Fault::Reject(code));
        let t0 = Instant::now();
        let e = d.measure().expect_err("rejected");
        assert_within(t0, T, "ER");
        let want = format!("{code:02}");
        assert_eq!(e.code(), Some(want.as_str()), "{e}");
        let user = VisionError::from(vision_core::DriverError::from(e)).to_string();
        assert!(user.contains(&format!("ER,TRG,{want}")), "{user}");
        let r = d.measure().expect("next trigger");
        assert_eq!(r.x_px, em.stats().triggers as f64);
    }
    assert_eq!(em.stats().connections, 1, "a refusal is a complete reply: the connection stays");
}

#[test]
fn setup_mode_refuses_trg_with_06() {
    let em = start(Emulator::builder().mode(Mode::Setup));
    let mut d = driver(&em, T);
    let e = d.measure().expect_err("setup");
    assert_eq!(e.code(), Some("06"));
    assert_eq!(vision_core::DriverError::from(e).kind(), DriverErrorKind::Rejected);
    em.set_mode(Mode::Run);
    assert_eq!(d.measure().expect("run").x_px, 888.0);
}

#[test]
fn firmware_version_and_program() {
    let em = start(Emulator::builder());
    let mut d = driver(&em, T);
    assert_eq!(d.test_connection().expect("FVR"), "1.00.0000 mach-vision VS emulator");
    assert_eq!(d.program().expect("PR"), Program { device: 1, job: 0 });
}

#[test]
fn job_switch_on_a_vs_uses_pl_and_keeps_the_device() {
    let settings =
        vision_driver_keyence::emulator::EmulatorSettings { program: (2, 3), max_job: 40, ..Default::default() };
    let em = start(Emulator::builder().settings(settings));
    let mut d = driver(&em, T);
    d.select_job(17).expect("PL");
    assert_eq!(d.job_command(), Some(JobCommand::Pl));
    assert_eq!(em.program(), Program { device: 2, job: 17 });
    let e = d.load_job(41).expect_err("no job 41");
    assert_eq!(e.code(), Some("03"));
    assert!(e.to_string().contains("does not exist"), "{e}");
    // What the operator reads: the driver's advice for this command, through the core.
    let user = VisionError::Driver(vision_core::DriverError::from(e)).to_string();
    assert!(user.contains("ER,PL,03") && user.contains("does not exist on the camera"), "{user}");
    let sent = em.stats().commands;
    assert_eq!(d.load_job(1000), Err(KeyenceError::InvalidJob { job: 1000 }));
    assert_eq!(em.stats().commands, sent, "refused before anything was sent");
    em.set_mode(Mode::Setup);
    assert_eq!(d.load_job(5).expect_err("setup").code(), Some("06"));
    let e = d.measure().expect_err("setup");
    let user = VisionError::Driver(vision_core::DriverError::from(e)).to_string();
    assert!(user.contains("ER,TRG,06"), "{user}");
    assert_eq!(user.matches("switch the camera to Run mode").count(), 1, "advice once: {user}");
}

#[test]
fn job_switch_falls_back_to_pw_and_remembers_it() {
    let em = start(Emulator::builder().series(Series::CvX));
    let mut d = driver(&em, T);
    d.load_job(9).expect("PL refused with 01, then PW");
    assert_eq!(d.job_command(), Some(JobCommand::Pw));
    assert_eq!(em.program().job, 9);
    let before = em.stats().commands;
    d.load_job(10).expect("PW directly");
    assert_eq!(em.stats().commands - before, 2, "PR then PW, no PL");
}

#[test]
fn a_loading_job_answers_05_then_recovers() {
    let load = Duration::from_millis(150);
    let em = start(Emulator::builder().load_time(load));
    let mut d = driver(&em, T);
    d.load_job(4).expect("PL");
    assert_eq!(d.measure().expect_err("loading").code(), Some("05"));
    std::thread::sleep(load);
    d.measure().expect("loaded");
}

#[test]
fn a_configured_memory_device_skips_pr() {
    let em = start(Emulator::builder());
    let config = KeyenceConfig { memory_device: Some(2), ..KeyenceConfig::new("127.0.0.1", em.addr().port()) };
    let mut d = KeyenceDriver::new(config.with_timeout(T)).expect("config");
    d.load_job(6).expect("PL,2,006");
    assert_eq!(em.program(), Program { device: 2, job: 6 });
    assert_eq!(em.stats().commands, 1);
}

/// Runs one fault: the failing call's error, then checks the next trigger is the camera's next
/// result and that the failing call sent `TRG` exactly once.
fn fault(fault: Fault, timeout: Duration) -> Result<Reading, KeyenceError> {
    let (source, _) = counting();
    let em = start(Emulator::builder().source(source));
    let mut d = driver(&em, timeout);
    assert_eq!(d.measure().expect("warm-up").x_px, 1.0);
    em.inject(fault.clone());
    let t0 = Instant::now();
    let result = d.measure();
    assert_within(t0, timeout, &format!("{fault:?}"));
    assert_eq!(em.stats().triggers, 2, "{fault:?}: TRG sent exactly once");
    let next = d.measure().unwrap_or_else(|e| panic!("{fault:?}: next trigger failed: {e}"));
    assert_eq!((next.x_px, next.y_px), (3.0, 6.0), "{fault:?}: the next trigger gets the next result");
    assert!(em.pending_faults().is_empty());
    result
}

#[test]
fn fault_delay_past_the_timeout() {
    match fault(Fault::Delay(T * 3), T) {
        Err(KeyenceError::Timeout { waiting_for, echoed: false, .. }) => assert_eq!(waiting_for, "the TRG echo"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn fault_delay_within_the_timeout_is_just_slow() {
    assert_eq!(fault(Fault::Delay(T / 3), T).expect("slow").x_px, 2.0);
}

#[test]
fn fault_late_reply_never_answers_the_next_command() {
    match fault(Fault::LateReply(T + Duration::from_millis(100)), T) {
        Err(KeyenceError::Timeout { .. }) => {}
        other => panic!("{other:?}"),
    }
}

#[test]
fn fault_dropped_connection() {
    let r = fault(Fault::Close, T);
    assert!(matches!(r, Err(KeyenceError::Closed { .. })), "{r:?}");
    match fault(Fault::CloseAfterEcho, T) {
        Err(KeyenceError::Closed { waiting_for, .. }) => assert!(waiting_for.starts_with("the data line")),
        other => panic!("{other:?}"),
    }
}

#[test]
fn fault_garbage_line() {
    match fault(Fault::Garbage(b"\x07#?!,,x".to_vec()), T) {
        Err(KeyenceError::Malformed { line, .. }) => assert_eq!(line, "\\x07#?!,,x"),
        other => panic!("{other:?}"),
    }
    match fault(Fault::Garbage(b"1,nan,5".to_vec()), T) {
        Err(e @ KeyenceError::Malformed { .. }) => assert_eq!(e.kind(), DriverErrorKind::Malformed),
        other => panic!("{other:?}"),
    }
}

#[test]
fn fault_byte_by_byte_one_segment_and_stray_lf_still_read() {
    for f in [Fault::ByteByByte, Fault::OneSegment, Fault::StrayLf] {
        let r = fault(f.clone(), T).unwrap_or_else(|e| panic!("{f:?}: {e}"));
        assert_eq!((r.x_px, r.y_px), (2.0, 4.0), "{f:?}");
    }
}

#[test]
fn fault_silence_after_the_echo_names_the_data_output() {
    match fault(Fault::Silence, T) {
        Err(e @ KeyenceError::Timeout { echoed: true, .. }) => {
            assert!(e.fix().contains("Data Output"), "{e}");
            // What the operator reads: the camera answered, it is not unreachable.
            let user = VisionError::from(vision_core::DriverError::from(e)).to_string();
            assert!(user.starts_with("timeout: the camera echoed TRG but sent no data within"), "{user}");
            assert!(user.contains("the camera answered but sent no data"), "{user}");
            assert!(!user.contains("unreachable") && !user.contains("wrong IP"), "{user}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_bare_ng_is_an_ng_reading_not_a_malformed_reply() {
    let em =
        start(Emulator::builder().source(ListSource::cycling(vec![Shot::Line("0".into()), Shot::Line("NG".into())])));
    let mut d = driver(&em, T);
    for _ in 0..2 {
        let r = d.measure().expect("an NG reading");
        assert_eq!(r.judgment, Judgment::Ng);
        assert!(!r.found());
    }
}

#[test]
fn a_robot_pose_output_is_named_as_such() {
    let em = start(Emulator::builder().source(ListSource::cycling(vec![Shot::Line("1,10.5,20.5,30,0,0,90".into())])));
    let e = driver(&em, T).measure().expect_err("a robot pose");
    assert_eq!(e.kind(), DriverErrorKind::Malformed);
    let user = VisionError::from(vision_core::DriverError::from(e)).to_string();
    assert!(user.contains("the Data Output looks set to a robot pose"), "{user}");
    assert!(user.contains("the mark in image pixels: x,y or judgment,x,y or judgment,count,x,y"), "{user}");
}

#[test]
fn several_marks_are_used_with_a_warning() {
    let two = Reading { count: Some(2), ..mark() };
    let em = start(Emulator::builder().source(ListSource::readings([two])));
    let mut d = driver(&em, T);
    let r = d.measure().expect("a reading");
    assert_eq!(r, two);
    let warning = d.reading_warning(&r).expect("a warning");
    assert!(warning.contains("found 2 marks") && warning.contains("x 812.125 y -903.500 px"), "{warning}");
}

#[test]
fn fault_dribbling_peer_cannot_stretch_the_timeout() {
    // One byte every 40 % of the timeout: each read is quick, the reply never completes.
    match fault(Fault::Dribble(T.mul_f64(0.4)), T) {
        Err(KeyenceError::Timeout { .. }) => {}
        other => panic!("{other:?}"),
    }
}

#[test]
fn fault_hostile_lengths_hit_the_bounds() {
    assert!(matches!(fault(Fault::LongLine(5000), T), Err(KeyenceError::LineTooLong { limit: 512, .. })));
    assert!(matches!(fault(Fault::ManyLines(12), T), Err(KeyenceError::TooManyLines { limit: 8, .. })));
}

#[test]
fn stale_lines_before_the_echo_are_not_taken_as_the_answer() {
    // Fewer stale lines than the bound: the driver skips them and reads its own answer.
    assert_eq!(fault(Fault::ManyLines(3), T).expect("skipped").x_px, 2.0);
}

#[test]
fn a_camera_that_drops_the_idle_link_costs_a_reconnect_not_an_error() {
    let (source, _) = counting();
    let em = start(Emulator::builder().source(source));
    let mut d = driver(&em, T);
    d.measure().expect("first");
    em.disconnect_client();
    std::thread::sleep(Duration::from_millis(50));
    assert_eq!(d.measure().expect("reconnected").x_px, 2.0);
    assert_eq!(em.stats().triggers, 2, "no TRG was sent twice");
    assert_eq!(em.stats().connections, 2);
}

#[test]
fn a_second_client_is_turned_away() {
    let em = start(Emulator::builder());
    let mut first = driver(&em, T);
    first.measure().expect("first client");
    let mut second = driver(&em, T);
    let t0 = Instant::now();
    let e = second.measure().expect_err("camera taken");
    assert_within(t0, T, "second client");
    assert_eq!(e.kind(), DriverErrorKind::Refused, "{e}");
    assert_eq!(em.stats().rejected, 1);
    first.measure().expect("first client still served");
    drop(first);
    std::thread::sleep(Duration::from_millis(50));
    second.measure().expect("the camera is free again");
}

#[test]
fn clients_queued_behind_a_held_camera_all_hear_it_is_taken() {
    let em = start(Emulator::builder());
    let mut holder = driver(&em, T);
    holder.measure().expect("the first client holds the camera");
    // Several clients at once: each must learn the camera closed the connection, within its
    // timeout, not one grace per client ahead of it (which timed most of them out).
    let clients: Vec<_> = (0..8)
        .map(|_| {
            let mut d = driver(&em, T);
            std::thread::spawn(move || {
                let t0 = Instant::now();
                let e = d.measure().expect_err("camera taken");
                (t0.elapsed(), e)
            })
        })
        .collect();
    for c in clients {
        let (took, e) = c.join().expect("client thread");
        assert!(matches!(e, KeyenceError::Closed { .. }), "after {took:?}: {e}");
        assert!(took < T, "took {took:?}: {e}");
        let user = VisionError::from(vision_core::DriverError::from(e)).to_string();
        assert!(user.contains("camera closed the connection"), "{user}");
        assert!(user.contains("another client probably holds the camera's only command socket"), "{user}");
    }
    assert_eq!(em.stats().rejected, 8);
    holder.measure().expect("the first client is still served");
}

#[test]
fn nothing_listening_is_refused_at_once() {
    let port = {
        let l = std::net::TcpListener::bind("127.0.0.1:0").expect("bind");
        l.local_addr().expect("addr").port()
    };
    let mut d = KeyenceDriver::new(KeyenceConfig::new("127.0.0.1", port).with_timeout(T)).expect("config");
    let t0 = Instant::now();
    let e = d.measure().expect_err("refused");
    assert_within(t0, T, "refused");
    assert!(matches!(e, KeyenceError::Refused { .. }), "{e}");
    let user = VisionError::from(vision_core::DriverError::from(e.clone())).to_string();
    assert_eq!(user, e.to_string(), "the driver's words, as they are");
    assert!(
        user.starts_with("connection refused: camera at 127.0.0.1:") && user.contains("refused the connection"),
        "{user}"
    );
}

#[test]
fn a_camera_that_never_accepts_times_out_on_connect() {
    // A listener with a backlog of one that never accepts: once its queue is full, the kernel
    // drops further connection requests, so connecting hangs like an unreachable camera.
    let socket = socket2::Socket::new(socket2::Domain::IPV4, socket2::Type::STREAM, None).expect("socket");
    socket.bind(&"127.0.0.1:0".parse::<std::net::SocketAddr>().expect("addr").into()).expect("bind");
    socket.listen(0).expect("listen");
    let addr = socket.local_addr().expect("addr").as_socket().expect("inet");
    let fillers: Vec<_> =
        (0..4).filter_map(|_| std::net::TcpStream::connect_timeout(&addr, Duration::from_millis(50)).ok()).collect();
    let mut d = KeyenceDriver::new(KeyenceConfig::new("127.0.0.1", addr.port()).with_timeout(T)).expect("config");
    let t0 = Instant::now();
    let e = d.measure().expect_err("no accept");
    assert_within(t0, T, "connect");
    assert_eq!(e.kind(), DriverErrorKind::Timeout, "{e}");
    drop(fillers);
}

#[test]
fn the_registry_builds_it_from_the_parameters() {
    let em = start(Emulator::builder());
    let mut registry = DriverRegistry::new();
    register(&mut registry);
    assert!(registry.contains("keyence"));
    let mut params = registry.params();
    params.set("VisionIP", "127.0.0.1").expect("ip");
    params.set("VisionPort", i64::from(em.addr().port())).expect("port");
    params.set("VisionTimeout", T.as_secs_f64()).expect("timeout");
    let mut d = registry.create("Keyence", &params).expect("created without connecting");
    assert_eq!(d.name(), "Keyence");
    assert!(d.capabilities().select_job);
    assert_eq!(d.timeout(), T);
    assert_eq!(d.trigger().expect("reading").x_px, 888.0);
}

#[test]
fn unresolvable_host_is_a_clear_error() {
    let mut d = KeyenceDriver::new(KeyenceConfig::new("no-such-camera.invalid", 8500).with_timeout(T)).expect("cfg");
    let e = d.measure().expect_err("does not resolve");
    assert!(matches!(e, KeyenceError::Resolve { .. } | KeyenceError::ConnectTimeout { .. }), "{e}");
    assert!(!d.is_connected());
}

/// A loopback server that is no Keyence camera: it sends `greeting` on connect (an SSH
/// server's banner), or `reply` once it has read a command (a web server's 400), then closes.
fn foreign_device(greeting: &'static [u8], reply: &'static [u8]) -> u16 {
    use std::io::{Read, Write};
    let listener = std::net::TcpListener::bind("127.0.0.1:0").expect("port");
    let port = listener.local_addr().expect("addr").port();
    std::thread::spawn(move || {
        for stream in listener.incoming().take(4) {
            let Ok(mut s) = stream else { continue };
            let _ = s.write_all(greeting);
            let mut buf = [0u8; 64];
            let _ = s.set_read_timeout(Some(Duration::from_millis(200)));
            let _ = s.read(&mut buf);
            let _ = s.write_all(reply);
        }
    });
    port
}

/// Issue 33: a device that answers on the camera's port but does not speak the protocol (a web
/// server, an SSH server) is named as such, with what it answered (escaped, bounded), not given
/// advice about the camera's Data Output tool.
#[test]
fn a_device_that_does_not_speak_the_protocol_is_named_with_what_it_answered() {
    let cases: [(&[u8], &[u8], &str); 3] = [
        (
            b"",
            b"HTTP/1.1 400 Bad Request\r\nContent-Type: text/html\r\nContent-Length: 11\r\nConnection: close\r\n\r\nBad Request",
            // The first FIRST_BYTES_SHOWN (64) bytes, and a mark that more came.
            "to TRG it answered \"HTTP/1.1 400 Bad Request\\x0d\\x0aContent-Type: text/html\\x0d\\x0aContent-Lengt…\"",
        ),
        (b"SSH-2.0-OpenSSH_9.2p1 Debian-2\r\n", b"", "to TRG it answered \"SSH-2.0-OpenSSH_9.2p1 Debian-2\\x0d\\x0a\""),
        (b"\x00\xff\xfe binary\n", b"", "to TRG it answered \"\\x00\\xff\\xfe binary\\x0a\""),
    ];
    for (greeting, reply, answered) in cases {
        let port = foreign_device(greeting, reply);
        let mut d = KeyenceDriver::new(KeyenceConfig::new("127.0.0.1", port).with_timeout(T)).expect("config");
        let e = d.measure().expect_err("no camera");
        let user = VisionError::Driver(e.clone().into()).to_string();
        assert!(matches!(e, KeyenceError::NotKeyence { .. }), "{e:?}");
        assert_eq!(e.kind(), DriverErrorKind::Malformed);
        assert!(
            user.starts_with(&format!(
                "Malformed response: the device at 127.0.0.1:{port} does not speak the Keyence Non-Procedural protocol"
            )),
            "{user}"
        );
        assert!(user.contains(answered), "{user}");
        assert!(user.contains("check VisionIP and VisionPort"), "{user}");
        assert!(!user.contains("Data Output"), "{user}");
        assert!(user.len() < 600, "{user}");
    }
}
