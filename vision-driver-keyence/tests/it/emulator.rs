//! The emulator on its own, over raw loopback sockets: what a VS camera answers, byte for byte.

use crate::common;

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

use common::{start, SLACK};
use vision_core::{CameraDriver, Capabilities, DriverError, DriverErrorKind, Reading};
use vision_driver_keyence::emulator::{DriverSource, Emulator, EmulatorHandle, Mode, Shot};

/// A raw client: writes bytes, reads CR-terminated lines.
struct Raw {
    s: TcpStream,
    buf: Vec<u8>,
}

impl Raw {
    fn connect(em: &EmulatorHandle) -> Raw {
        let s = TcpStream::connect(em.addr()).expect("connect");
        s.set_read_timeout(Some(Duration::from_secs(2))).expect("timeout");
        Raw { s, buf: Vec::new() }
    }

    fn send(&mut self, bytes: &[u8]) {
        self.s.write_all(bytes).expect("write");
    }

    fn line(&mut self) -> String {
        loop {
            if let Some(p) = self.buf.iter().position(|&b| b == b'\r') {
                let line: Vec<u8> = self.buf.drain(..=p).collect();
                return String::from_utf8_lossy(&line[..p]).into_owned();
            }
            let mut chunk = [0u8; 256];
            let n = self.s.read(&mut chunk).expect("read");
            assert!(n > 0, "closed while waiting for a line");
            self.buf.extend_from_slice(&chunk[..n]);
        }
    }

    fn ask(&mut self, command: &str) -> String {
        self.send(format!("{command}\r").as_bytes());
        self.line()
    }
}

#[test]
fn every_error_code_a_vs_gives() {
    let em = start(Emulator::builder().load_time(Duration::from_millis(200)));
    let mut c = Raw::connect(&em);
    assert_eq!(c.ask("HELLO"), "ER,HELLO,01");
    assert_eq!(c.ask("PW,1,5"), "ER,PW,01");
    assert_eq!(c.ask("TRG,1"), "ER,TRG,02");
    assert_eq!(c.ask("PL,1"), "ER,PL,02");
    assert_eq!(c.ask("PL,1,1000"), "ER,PL,03");
    assert_eq!(c.ask("PL,9,1"), "ER,PL,03");
    assert_eq!(c.ask("PL,1,five"), "ER,PL,04");
    assert_eq!(c.ask("PL,1,5"), "PL");
    assert_eq!(c.ask("TRG"), "ER,TRG,05");
    assert_eq!(c.ask("PR"), "ER,PR,05");
    assert_eq!(c.ask("MOR"), "MOR,1");
    std::thread::sleep(Duration::from_millis(200));
    assert_eq!(c.ask("PR"), "PR,1,005");
    assert_eq!(c.ask("SET"), "SET");
    assert_eq!(c.ask("MOR"), "MOR,0");
    assert_eq!(c.ask("TRG"), "ER,TRG,06");
    assert_eq!(c.ask("PL,1,6"), "ER,PL,06");
    assert_eq!(c.ask("RUN"), "RUN");
    assert_eq!(em.mode(), Mode::Run);
    assert_eq!(c.ask("TRG"), "TRG");
    assert_eq!(c.line(), "1,1,888.000,888.000,0.000,0.000,0.000,0.000");
    assert!(c.ask("FVR").starts_with("FVR,"));
}

#[test]
fn an_unfinished_command_gets_07_after_the_command_timeout() {
    let timeout = Duration::from_millis(150);
    let em = start(Emulator::builder().command_timeout(timeout));
    let mut c = Raw::connect(&em);
    let t0 = Instant::now();
    c.send(b"TR");
    assert_eq!(c.line(), "ER,TR,07");
    let took = t0.elapsed();
    assert!(took >= timeout && took <= timeout + SLACK, "{took:?}");
    // The fragment was discarded: the next command stands on its own.
    assert_eq!(c.ask("TRG"), "TRG");
    c.line();
}

#[test]
fn overlong_commands_get_02_and_are_discarded_whole() {
    let em = start(Emulator::builder());
    let mut c = Raw::connect(&em);
    let mut long = b"PL,1,".to_vec();
    long.extend(std::iter::repeat_n(b'0', 2000));
    long.push(b'\r');
    c.send(&long);
    assert_eq!(c.line(), "ER,PL,02");
    assert_eq!(c.ask("PR"), "PR,1,000");
}

#[test]
fn commands_may_end_in_cr_lf_or_crlf_and_arrive_together() {
    let em = start(Emulator::builder());
    let mut c = Raw::connect(&em);
    c.send(b"MOR\r\nPR\nFVR\r\r\n");
    assert_eq!(c.line(), "MOR,1");
    assert_eq!(c.line(), "PR,1,000");
    assert!(c.line().starts_with("FVR,"));
    assert_eq!(em.stats().commands, 3, "empty lines are not commands");
}

#[test]
fn a_driver_plugs_in_as_the_result_source() {
    struct Fake(u32);
    impl CameraDriver for Fake {
        fn name(&self) -> &str {
            "Fake"
        }
        fn capabilities(&self) -> Capabilities {
            Capabilities { select_job: true, grab_image: false }
        }
        fn trigger(&mut self) -> Result<Reading, DriverError> {
            Ok(Reading::position(f64::from(self.0), 1.5))
        }
        fn select_job(&mut self, job: u32) -> Result<(), DriverError> {
            if job == 13 {
                return Err(DriverError::new(DriverErrorKind::InvalidArgument, "no job 13"));
            }
            self.0 = job;
            Ok(())
        }
        fn test_connection(&mut self) -> Result<String, DriverError> {
            Ok("fake".into())
        }
    }
    let em = start(Emulator::builder().source(DriverSource(Box::new(Fake(0)))));
    let mut c = Raw::connect(&em);
    assert_eq!(c.ask("PL,1,7"), "PL");
    assert_eq!(c.ask("TRG"), "TRG");
    assert_eq!(c.line(), "1,1,7.000,1.500,0.000,0.000,0.000,0.000");
    assert_eq!(c.ask("PL,1,13"), "ER,PL,03");
    assert_eq!(em.program().job, 7);
}

#[test]
fn a_rejected_shot_replaces_the_echo() {
    let em = start(
        Emulator::builder()
            .source(vision_driver_keyence::emulator::ListSource::exhausting(vec![Shot::Reject(7), Shot::Silent])),
    );
    let mut c = Raw::connect(&em);
    assert_eq!(c.ask("TRG"), "ER,TRG,07");
    assert_eq!(c.ask("TRG"), "TRG");
    assert_eq!(c.ask("TRG"), "ER,TRG,05", "an exhausted list answers 05");
}

#[test]
fn a_second_raw_client_is_reset() {
    let em = start(Emulator::builder());
    let mut first = Raw::connect(&em);
    assert_eq!(first.ask("MOR"), "MOR,1");
    let mut second = TcpStream::connect(em.addr()).expect("the OS accepts");
    second.set_read_timeout(Some(Duration::from_secs(2))).expect("timeout");
    let mut b = [0u8; 8];
    match second.read(&mut b) {
        Ok(0) | Err(_) => {}
        Ok(n) => panic!("the second client got {n} bytes"),
    }
    assert_eq!(em.stats().rejected, 1);
    assert_eq!(first.ask("MOR"), "MOR,1");
}

#[test]
fn shutdown_stops_serving() {
    let em = start(Emulator::builder());
    let addr = em.addr();
    let mut c = Raw::connect(&em);
    assert_eq!(c.ask("MOR"), "MOR,1");
    em.shutdown();
    let mut b = [0u8; 8];
    assert!(matches!(c.s.read(&mut b), Ok(0) | Err(_)), "the client is cut off");
    assert!(TcpStream::connect_timeout(&addr, Duration::from_millis(200)).is_err(), "nothing listens");
}

#[test]
fn settings_are_checked_at_bind() {
    let mut s = vision_driver_keyence::emulator::EmulatorSettings { version: "bad\u{7f}".into(), ..Default::default() };
    assert!(Emulator::builder().settings(s.clone()).bind("127.0.0.1:0").is_err());
    s.version = "ok".into();
    s.program = (3, 0);
    assert!(Emulator::builder().settings(s).bind("127.0.0.1:0").is_err());
}
