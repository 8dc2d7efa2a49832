//! The emulated controller, driven byte by byte without sockets, against Grbl's protocol.

use vision_grbl::emulator::{EmulatorConfig, Flavour, Machine};

fn machine(flavour: Flavour) -> Machine {
    let config = EmulatorConfig {
        flavour,
        settings: vec![(110, 6000.0), (111, 6000.0), (120, 500.0), (121, 500.0)],
        ..Default::default()
    };
    let mut m = Machine::new(config);
    m.take_output();
    m
}

/// Sends `bytes`, runs `seconds` of simulated time, returns what came back.
fn exchange(m: &mut Machine, bytes: &[u8], seconds: f64) -> String {
    m.receive(bytes);
    m.advance(seconds);
    String::from_utf8(m.take_output()).expect("utf8")
}

fn answer(m: &mut Machine, line: &str) -> String {
    exchange(m, format!("{line}\n").as_bytes(), 5.0).trim_end().to_string()
}

#[test]
fn each_refusal_has_grbls_error_number() {
    let mut m = machine(Flavour::Grbl);
    for (line, expected) in [
        ("G68 X0 Y0 R10", "error:20"),
        ("G51 X1", "error:20"),
        ("G52 X1", "error:20"),
        ("G81 X1 Y1 Z-1 R1 F100", "error:20"),
        ("M6", "error:20"),
        ("M100", "error:20"),
        // M280 is stored in a byte (24) with the rest as a fraction: not an integer.
        ("M280", "error:23"),
        ("M256", "error:23"),
        ("G1 X1", "error:22"),
        ("G2 X10 Y0 I5.1 J0 F6000", "error:33"),
        ("G1 X1 X2 F100", "error:25"),
        ("G10 L2 P1 R5 X0", "error:20"),
        ("G53 G2 X1 I1 F100", "error:30"),
        ("G0 G1 X1", "error:24"),
        ("G17 G18", "error:21"),
        ("1", "error:1"),
        ("GX", "error:2"),
        ("G4", "error:28"),
    ] {
        assert_eq!(answer(&mut m, line), expected, "{line}");
    }
    // Just within the arc tolerance: start radius 5, end radius 5.004.
    assert_eq!(answer(&mut m, "G2 X10.004 Y0 I5 J0 F6000"), "ok");
    // 0.006 mm off on a 10 mm radius: more than 0.005 mm but within 0.1 %.
    assert_eq!(answer(&mut m, "G90 G0 X0 Y0"), "ok");
    assert_eq!(answer(&mut m, "G2 X20.006 Y0 I10 J0 F6000"), "ok");
    assert_eq!(answer(&mut m, "G0 X0 Y0"), "ok");
    assert_eq!(answer(&mut m, "G2 X20.011 Y0 I10 J0 F6000"), "error:33");
}

#[test]
fn a_line_past_80_characters_is_error_11_and_the_accepted_codes_answer_ok() {
    let mut m = machine(Flavour::Grbl);
    let long = format!("G1 X1 F100 ({})", "c".repeat(60));
    assert_eq!(answer(&mut m, &long), "ok", "comments do not count");
    assert_eq!(answer(&mut m, &format!("G1X{}", "1".repeat(80))), "error:11");
    for line in [
        "G21 G90 G17 G54",
        "G92 X0 Y0",
        "G10 L20 P1 X0",
        "G10 L2 P2 X5",
        "G91 G0 X1",
        "G90 G53 G0 X0",
        "M3 S1000",
        "M8",
        "M7",
        "M9",
        "M5",
        "T1",
        "G4 P0.01",
        "G18",
        "G19",
        "G17",
        "G20",
        "G21",
        "G55",
        "G54",
    ] {
        assert_eq!(answer(&mut m, line), "ok", "{line}");
    }
    assert!(exchange(&mut m, b"M2\n", 2.0).contains("[MSG:Pgm End]\r\nok"));
}

#[test]
fn the_receive_buffer_holds_128_bytes_and_loses_the_rest() {
    let mut m = machine(Flavour::Grbl);
    // A dwell keeps the controller from reading; 200 bytes of comment-free moves follow.
    m.receive(b"G4 P10\n");
    m.advance(0.01);
    let block: Vec<u8> = b"G1 X1 F100\n".repeat(20);
    m.receive(&block);
    m.receive(b"?");
    m.advance(0.0);
    let out = String::from_utf8(m.take_output()).expect("utf8");
    assert!(out.contains("<Idle|"), "{out}");
    // The line end that found the buffer full is lost too.
    m.receive(b"\n");
    m.advance(30.0);
    let mut out = String::from_utf8(m.take_output()).expect("utf8");
    // Exactly 128 bytes were kept: 11 lines of 11 bytes and 7 bytes of the 12th.
    out.push_str(&exchange(&mut m, b"\n", 1.0));
    let oks = out.matches("ok").count();
    let errors: Vec<&str> = out.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(oks, 1 + 11, "{out}");
    assert_eq!(errors, ["error:2"], "the 12th line, cut to `G1 X1 F`, has no number after F");
}

#[test]
fn status_reports_carry_wco_every_tenth_report_idle_and_after_a_change() {
    let mut m = machine(Flavour::Grbl);
    let reports: Vec<String> = (0..12).map(|_| exchange(&mut m, b"?", 0.0)).collect();
    assert_eq!(reports[0], "<Idle|MPos:0.000,0.000,0.000|FS:0,0|WCO:0.000,0.000,0.000>\r\n");
    assert_eq!(reports[1], "<Idle|MPos:0.000,0.000,0.000|FS:0,0|Ov:100,100,100>\r\n");
    let with_wco: Vec<usize> = reports.iter().enumerate().filter(|(_, r)| r.contains("WCO")).map(|(i, _)| i).collect();
    assert_eq!(with_wco, [0, 10]);
    assert_eq!(answer(&mut m, "G10 L20 P1 X-5"), "ok");
    assert!(exchange(&mut m, b"?", 0.0).contains("|WCO:5.000,0.000,0.000"));
    assert!(!exchange(&mut m, b"?", 0.0).contains("WCO"));
}

#[test]
fn dollar_commands_report_like_grbl() {
    let mut m = machine(Flavour::Grbl);
    assert_eq!(answer(&mut m, "$G"), "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\nok");
    assert_eq!(answer(&mut m, "$I"), "[VER:1.1h.20190830:]\r\n[OPT:VM,15,128]\r\nok");
    assert!(answer(&mut m, "$#").starts_with("[G54:0.000,0.000,0.000]\r\n[G55:"));
    assert_eq!(answer(&mut m, "$X"), "ok");
    assert_eq!(answer(&mut m, "$H"), "error:5", "homing is disabled by default ($22=0)");
    assert_eq!(answer(&mut m, "$22=1"), "ok");
    assert_eq!(answer(&mut m, "$H"), "ok");
}

#[test]
fn feed_hold_stops_on_the_path_and_resume_finishes() {
    let mut m = machine(Flavour::Grbl);
    assert_eq!(exchange(&mut m, b"G1 X50 F3000\n", 0.3).trim_end(), "ok");
    assert!(exchange(&mut m, b"?", 0.0).starts_with("<Run|"));
    let held = exchange(&mut m, b"!", 0.5);
    assert!(held.is_empty());
    let report = exchange(&mut m, b"?", 0.0);
    assert!(report.starts_with("<Hold:0|"), "{report}");
    exchange(&mut m, b"", 1.0);
    let later = exchange(&mut m, b"?", 0.0);
    assert_eq!(report.split('|').nth(1), later.split('|').nth(1), "no motion while held");
    exchange(&mut m, b"~", 5.0);
    assert!(exchange(&mut m, b"?", 0.0).starts_with("<Idle|MPos:50.000,0.000,0.000"));
}

#[test]
fn a_reset_in_motion_raises_alarm_3_and_locks_gcode() {
    let mut m = machine(Flavour::Grbl);
    exchange(&mut m, b"G1 X50 F3000\n", 0.2);
    let out = exchange(&mut m, &[0x18], 0.0);
    assert_eq!(out, "ALARM:3\r\n\r\nGrbl 1.1h ['$' for help]\r\n[MSG:'$H'|'$X' to unlock]\r\n");
    assert_eq!(answer(&mut m, "G0 X0"), "error:9");
    assert_eq!(answer(&mut m, "$X"), "[MSG:Caution: Unlocked]\r\nok");
    // At rest a reset only greets.
    assert_eq!(exchange(&mut m, &[0x18], 0.0), "\r\nGrbl 1.1h ['$' for help]\r\n");
}

/// Once a feed hold has stopped the machine, a reset keeps its position (the hold's step
/// control is cleared when it completes): no `ALARM:3`, on Grbl as on grblHAL.
#[test]
fn a_reset_in_a_completed_feed_hold_keeps_the_position() {
    for (flavour, welcome) in
        [(Flavour::Grbl, "Grbl 1.1h ['$' for help]"), (Flavour::GrblHal, "GrblHAL 1.1f ['$' or '$HELP' for help]")]
    {
        let mut m = machine(flavour);
        exchange(&mut m, b"G1 X50 F3000\n", 0.2);
        assert_eq!(exchange(&mut m, b"!", 0.0), "");
        let braking = exchange(&mut m, b"?", 0.0);
        assert!(braking.starts_with("<Hold:1|"), "{braking}");
        exchange(&mut m, b"", 1.0);
        let held = exchange(&mut m, b"?", 0.0);
        assert!(held.starts_with("<Hold:0|"), "{held}");
        assert_eq!(exchange(&mut m, &[0x18], 0.0), format!("\r\n{welcome}\r\n"), "{flavour:?}");
        let after = exchange(&mut m, b"?", 0.0);
        assert!(after.starts_with("<Idle|"), "{after}");
        assert_eq!(held.split('|').nth(1), after.split('|').nth(1), "the position is kept");
        assert_eq!(answer(&mut m, "G0 X0"), "ok", "not locked");
        // Still braking: the position is lost.
        exchange(&mut m, b"G1 X50 F3000\n", 0.2);
        exchange(&mut m, b"!", 0.0);
        assert!(exchange(&mut m, &[0x18], 0.0).starts_with("ALARM:3\r\n"), "{flavour:?}");
    }
}

/// grblHAL's line buffer holds 256 characters, comments and inner spaces included (leading
/// spaces are dropped); the 257th is `error:11`. Grbl's holds 79 without them.
#[test]
fn grblhal_takes_lines_up_to_256_characters_comments_and_spaces_included() {
    let mut m = machine(Flavour::GrblHal);
    for (line, expected) in [
        (format!("G21{}", " ".repeat(253)), "ok"),
        (format!("G21{}", " ".repeat(254)), "error:11"),
        (format!("G21({})", "c".repeat(251)), "ok"),
        (format!("G21({})", "c".repeat(252)), "error:11"),
        (format!("   G21{}", " ".repeat(253)), "ok"),
        (format!("G0 X{}", "0".repeat(80)), "ok"),
    ] {
        assert_eq!(answer(&mut m, &line), expected, "{} characters", line.len());
        assert_eq!(answer(&mut m, ""), "ok", "unlatched");
    }
    let mut g = machine(Flavour::Grbl);
    assert_eq!(answer(&mut g, &format!("G0 X{}", "0".repeat(80))), "error:11");
}

#[test]
fn grblhal_latches_errors_until_a_dollar_line_and_accepts_g51() {
    let mut m = machine(Flavour::GrblHal);
    assert_eq!(answer(&mut m, "$I"), "[VER:1.1f.20260817:]\r\n[OPT:VNML,100,1024,3,0]\r\n[FIRMWARE:grblHAL]\r\nok");
    assert_eq!(answer(&mut m, "G51 P2"), "ok");
    assert_eq!(answer(&mut m, "G50"), "ok");
    assert_eq!(answer(&mut m, "M280"), "error:20");
    assert_eq!(answer(&mut m, "G0 X1"), "error:20", "latched");
    assert_eq!(answer(&mut m, "G0 X1"), "error:20", "still latched");
    assert_eq!(answer(&mut m, "$G").lines().last(), Some("ok"));
    assert_eq!(answer(&mut m, "G0 X1"), "ok");
    for line in ["G68 X0 Y0 R1", "G52 X1", "G10 L2 P1 R1 X0"] {
        assert_eq!(answer(&mut m, line), "error:20", "{line}");
        assert_eq!(answer(&mut m, ""), "ok");
    }
    // CRLF is one line end on grblHAL, two on Grbl.
    assert_eq!(exchange(&mut m, b"G0 X0\r\n", 1.0), "ok\r\n");
    let mut g = machine(Flavour::Grbl);
    assert_eq!(exchange(&mut g, b"G0 X0\r\n", 1.0), "ok\r\nok\r\n");
}

#[test]
fn grblhal_drills_with_g81_and_g82_where_grbl_refuses_them() {
    let mut m = machine(Flavour::GrblHal);
    assert_eq!(answer(&mut m, "G0 Z5"), "ok");
    assert_eq!(answer(&mut m, "G81 X10 Y10 Z-2 F600"), "error:28", "no R");
    assert_eq!(answer(&mut m, ""), "ok");
    assert_eq!(answer(&mut m, "G98 G81 X10 Y10 Z-2 R1 F600"), "ok");
    assert!(exchange(&mut m, b"?", 0.0).contains("MPos:10.000,10.000,5.000"), "back at the starting Z");
    assert_eq!(answer(&mut m, "G99 X20"), "ok", "R and Z are kept");
    assert!(exchange(&mut m, b"?", 0.0).contains("MPos:20.000,10.000,1.000"), "G99 stays at R");
    assert_eq!(answer(&mut m, "G82 X30 P0.2"), "ok");
    assert_eq!(answer(&mut m, "G80"), "ok");
    let mut g = machine(Flavour::Grbl);
    assert_eq!(answer(&mut g, "G81 X10 Y10 Z-2 R1 F600"), "error:20");
    assert_eq!(answer(&mut g, "G98"), "error:20");
}

#[test]
fn m0_holds_until_resume_and_a_busy_machine_reports_wco_every_thirtieth_time() {
    let mut m = machine(Flavour::Grbl);
    assert_eq!(exchange(&mut m, b"G1 X5 F3000\nM0\nG1 X10\n", 2.0), "ok\r\nok\r\nok\r\n");
    assert!(exchange(&mut m, b"?", 1.0).starts_with("<Hold:0|MPos:5.000,"));
    exchange(&mut m, b"~", 2.0);
    assert!(exchange(&mut m, b"?", 0.0).starts_with("<Idle|MPos:10.000,"));
    exchange(&mut m, b"G1 X500 F100\n", 0.1);
    let reports: Vec<String> = (0..100).map(|_| exchange(&mut m, b"?", 0.01)).collect();
    assert!(reports.iter().all(|r| r.starts_with("<Run|")));
    let with_wco: Vec<usize> = reports.iter().enumerate().filter(|(_, r)| r.contains("WCO")).map(|(i, _)| i).collect();
    let gaps: Vec<usize> = with_wco.windows(2).map(|w| w[1] - w[0]).collect();
    assert!(gaps.len() >= 2 && gaps.iter().all(|&g| g == 30), "{with_wco:?}");
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
    /// Any bytes, G-code-like or not, get answers and never a panic or a non-finite position.
    #[test]
    fn arbitrary_input_never_panics(
        chunks in proptest::collection::vec("[GMXYZIJKRFPSTLN$?!~0-9 .\\-\\n;()=#]{0,40}", 1..30),
        hal in proptest::bool::ANY,
    ) {
        let mut m = machine(if hal { Flavour::GrblHal } else { Flavour::Grbl });
        for chunk in &chunks {
            m.receive(chunk.as_bytes());
            m.advance(0.05);
        }
        m.receive(&[0x18, b'?']);
        m.advance(0.0);
        let out = String::from_utf8(m.take_output()).expect("ascii");
        proptest::prop_assert!(out.contains("<"));
        proptest::prop_assert!(m.machine_position().iter().all(|v| v.is_finite()));
    }
}

#[test]
fn the_planner_holds_15_blocks_and_the_16th_line_waits_for_room() {
    let mut m = machine(Flavour::Grbl);
    assert_eq!(answer(&mut m, "$10=3"), "ok");
    assert_eq!(answer(&mut m, "G91 G1 F60"), "ok");
    // 20 slow moves of 1 mm (80 bytes): 15 are planned and answered, the 16th waits in the parser.
    let out = exchange(&mut m, &b"X1\n".repeat(20), 0.01);
    assert_eq!(out.matches("ok").count(), 15, "{out}");
    assert!(exchange(&mut m, b"?", 0.0).contains("|Bf:0,"));
    // The first block done (1 s at 60 mm/min), one more line is answered.
    assert_eq!(exchange(&mut m, b"", 1.2).matches("ok").count(), 1);
}

#[test]
fn grblhal_keeps_1023_of_its_1024_bytes_of_receive_buffer() {
    let mut m = machine(Flavour::GrblHal);
    assert_eq!(answer(&mut m, "$10=3"), "ok");
    let idle = exchange(&mut m, b"?", 0.0);
    assert!(idle.contains("|Bf:100,1023|"), "one slot of the ring stays free: {idle}");
    m.receive(b"G4 P10\n");
    m.advance(0.01);
    // 100 lines of 11 bytes arrive while the dwell keeps the controller from reading.
    m.receive(&b"G1 X1 F100\n".repeat(100));
    m.receive(b"?");
    m.advance(0.0);
    let report = String::from_utf8(m.take_output()).expect("utf8");
    assert!(report.contains("<Idle|") && report.contains("|Bf:100,0|"), "{report}");
    m.advance(30.0);
    let out = String::from_utf8(m.take_output()).expect("utf8");
    // 1023 bytes: 93 whole lines, nothing of the 94th.
    assert_eq!(out.matches("ok").count(), 1 + 93, "{out}");
    assert_eq!(exchange(&mut m, b"\n", 1.0), "ok\r\n", "an empty line");
}

#[test]
#[expect(clippy::float_cmp, reason = "positions are whole steps, exactly representable here")]
fn configured_work_offsets_and_start_position_are_there_at_power_up() {
    let config = EmulatorConfig {
        work_offsets: [[1.0, 2.0, 3.0], [-10.0, 0.5, 0.0], [0.0; 3], [0.0; 3], [0.0; 3], [7.0, 8.0, 9.0]],
        start: [-5.0, -6.0, -7.0],
        ..Default::default()
    };
    let mut m = Machine::new(config);
    m.take_output();
    assert_eq!(m.machine_position(), [-5.0, -6.0, -7.0]);
    assert_eq!(exchange(&mut m, b"?", 0.0), "<Idle|MPos:-5.000,-6.000,-7.000|FS:0,0|WCO:1.000,2.000,3.000>\r\n");
    let params = answer(&mut m, "$#");
    assert!(
        params.starts_with("[G54:1.000,2.000,3.000]\r\n[G55:-10.000,0.500,0.000]\r\n[G56:0.000,0.000,0.000]\r\n"),
        "{params}"
    );
    assert!(params.contains("[G59:7.000,8.000,9.000]\r\n"), "{params}");
    assert_eq!(answer(&mut m, "G55"), "ok");
    assert!(exchange(&mut m, b"?", 0.0).ends_with("|WCO:-10.000,0.500,0.000>\r\n"));
    assert_eq!(answer(&mut m, "$10=0"), "ok");
    assert!(exchange(&mut m, b"?", 0.0).starts_with("<Idle|WPos:5.000,-6.500,-7.000|"));
    assert_eq!(answer(&mut m, "G59 G0 X0 Y0 Z0"), "ok");
    assert_eq!(m.machine_position(), [7.0, 8.0, 9.0]);
    // A reset keeps the stored offsets and the position, and selects G54 again.
    m.receive(&[0x18]);
    m.take_output();
    assert!(answer(&mut m, "$G").starts_with("[GC:G0 G54 "));
    assert!(exchange(&mut m, b"?", 0.0).starts_with("<Idle|WPos:6.000,6.000,6.000|"));
    let bad = EmulatorConfig { work_offsets: [[f64::NAN; 3]; 6], start: [f64::INFINITY; 3], ..Default::default() };
    assert_eq!(Machine::new(bad).machine_position(), [0.0; 3], "non-finite values read as 0");
}
