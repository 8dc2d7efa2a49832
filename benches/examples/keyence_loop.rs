//! Triggers in a loop against the emulated camera, for wall-clock figures outside criterion and
//! for instruction counts under callgrind: `keyence_loop driver|raw|session [iterations]`.
//!
//! `driver` runs `KeyenceDriver::measure`, `raw` a bare `TcpStream` write/read of the same
//! bytes, `session` the driver's protocol work alone against an in-memory camera.
use std::hint::black_box;
use std::net::TcpStream;
use std::time::{Duration, Instant};

use vision_benches::keyence::{camera, raw_trigger, InMemoryCamera};
use vision_driver_keyence::{Exchange, Limits};
use vision_driver_keyence::{KeyenceConfig, KeyenceDriver};

fn main() {
    let mode = std::env::args().nth(1).unwrap_or_else(|| "driver".into());
    let iters: u32 = std::env::args().nth(2).and_then(|s| s.parse().ok()).unwrap_or(10_000);
    let em = camera();
    let t = Instant::now();
    match mode.as_str() {
        "driver" => {
            let mut d = KeyenceDriver::new(KeyenceConfig::new("127.0.0.1", em.addr().port())).expect("config");
            for _ in 0..iters {
                black_box(d.measure().expect("reading"));
            }
        }
        "raw" => {
            let mut s = TcpStream::connect(em.addr()).expect("connect");
            s.set_nodelay(true).expect("nodelay");
            let mut buf = [0u8; 512];
            for _ in 0..iters {
                black_box(raw_trigger(&mut s, &mut buf).expect("reply"));
            }
        }
        "session" => {
            let mut s = Exchange::new(InMemoryCamera::default(), Limits::default(), Duration::from_secs(3));
            for _ in 0..iters {
                black_box(s.trigger().expect("reading"));
            }
        }
        other => panic!("unknown mode {other:?}: driver, raw or session"),
    }
    let us = t.elapsed().as_secs_f64() * 1e6 / f64::from(iters);
    println!("{mode}: {us:.2} µs per trigger over {iters}");
}
