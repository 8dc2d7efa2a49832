#![expect(missing_docs, reason = "criterion_group!/criterion_main! generate undocumented items.")]
//! vision-driver-keyence: one `TRG` round trip through the driver against the emulator, next to
//! a raw `TcpStream` writing the same `TRG\r` and reading the same two reply lines from the same
//! emulator; and the driver's protocol work alone (framing + parsing, in memory).

use std::hint::black_box;
use std::net::TcpStream;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use vision_benches::keyence::{camera, raw_trigger, InMemoryCamera, FULL_LINE};
use vision_driver_keyence::{parse_data_line, Exchange, Limits};
use vision_driver_keyence::{KeyenceConfig, KeyenceDriver};

fn round_trip(c: &mut Criterion) {
    let em = camera();
    let mut group = c.benchmark_group("keyence/trg_round_trip");
    let mut driver = KeyenceDriver::new(KeyenceConfig::new("127.0.0.1", em.addr().port())).expect("config");
    driver.measure().expect("warm-up");
    group.bench_function("driver", |b| {
        b.iter(|| {
            black_box(driver.measure().expect("reading"));
        })
    });
    driver.disconnect();
    std::thread::sleep(Duration::from_millis(50));

    let mut raw = TcpStream::connect(em.addr()).expect("connect");
    raw.set_nodelay(true).expect("nodelay");
    let mut buf = [0u8; 512];
    raw_trigger(&mut raw, &mut buf).expect("warm-up");
    group.bench_function("raw_tcp", |b| {
        b.iter(|| {
            black_box(raw_trigger(&mut raw, &mut buf).expect("reply"));
        })
    });
    group.finish();
}

fn protocol(c: &mut Criterion) {
    let mut group = c.benchmark_group("keyence/protocol");
    let mut session = Exchange::new(InMemoryCamera::default(), Limits::default(), Duration::from_secs(3));
    group.bench_function("session_trigger_in_memory", |b| {
        b.iter(|| {
            black_box(session.trigger().expect("reading"));
        });
    });
    group.bench_function("parse_full_line", |b| {
        b.iter(|| {
            black_box(parse_data_line(black_box(FULL_LINE)).expect("the full line parses"));
        })
    });
    group.finish();
}

criterion_group!(benches, round_trip, protocol);
criterion_main!(benches);
