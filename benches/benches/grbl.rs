#![expect(missing_docs, reason = "criterion_group!/criterion_main! generate undocumented items.")]
//! vision-grbl: 10 000 short segments (1 mm at 2000 mm/min) pushed one at a time by the sender
//! (`Sender::push`, then `Sender::finish`, as `mach-vision send` streams a program while it
//! interprets it) to the Grbl emulator over loopback TCP, the emulator timing the motion (at
//! 50× real time so one stream takes about 6 s). Measured: the sending thread's CPU time per
//! line (`iter_custom` returns it in place of wall time); printed after each stream: the lines,
//! how often the planner ran dry (status reports with `Bf:` showing every block free, or
//! `Idle`, while lines were still to come), the longest wait for buffer room, and the wall time.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};
use vision_grbl::emulator::{Emulator, EmulatorConfig};
use vision_grbl::stream::{Sender, SenderOptions};

const SEGMENTS: usize = 10_000;

fn thread_cpu() -> Duration {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes one timespec we own.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    if rc != 0 {
        return Duration::ZERO;
    }
    Duration::new(u64::try_from(ts.tv_sec).unwrap_or(0), u32::try_from(ts.tv_nsec).unwrap_or(0))
}

fn program() -> Vec<String> {
    let mut lines = vec!["G21 G90 G1 F2000".to_string()];
    lines.extend((1..=SEGMENTS).map(|i| format!("X{i} Y{}", if i % 2 == 0 { "0.05" } else { "0" })));
    lines
}

fn stream_10k(c: &mut Criterion) {
    let config = EmulatorConfig {
        time_scale: 50.0,
        // $10=3: MPos and Bf; rates and accelerations of a small hobby machine.
        settings: vec![(10, 3.0), (110, 5000.0), (111, 5000.0), (120, 200.0), (121, 200.0)],
        ..EmulatorConfig::default()
    };
    let grbl = Emulator::bind("127.0.0.1:0", config).expect("bind");
    let lines = program();
    let mut group = c.benchmark_group("grbl/stream_10k_segments");
    group.sample_size(10).measurement_time(Duration::from_secs(60)).warm_up_time(Duration::from_secs(1));
    group.bench_function("sender_cpu", |b| {
        b.iter_custom(|iters| {
            let mut cpu = Duration::ZERO;
            for _ in 0..iters {
                let mut sender =
                    Sender::connect(&format!("tcp://{}", grbl.addr()), &SenderOptions::default()).expect("connect");
                let wall = Instant::now();
                let before = thread_cpu();
                for line in &lines {
                    sender.push(black_box(line)).expect("push");
                }
                let report = black_box(sender.finish().expect("finish"));
                cpu += thread_cpu().saturating_sub(before);
                sender.wait_idle(Duration::from_secs(120)).expect("idle");
                eprintln!(
                    "grbl: {} lines, {} bytes, planner ran dry {} times, longest wait {:?}, wall {:?}",
                    report.lines_sent,
                    report.bytes_sent,
                    report.planner_dry,
                    report.longest_wait,
                    wall.elapsed()
                );
            }
            cpu
        });
    });
    group.finish();
}

/// The rest of the sender's work per line: the host's interpreter running a 10 000-segment
/// program (1 mm at 2000 mm/min, a mm machine, Grbl's dialect) and `vision_grbl::emit` writing
/// each event as a Grbl line, with no I/O. Criterion's time is for the whole program.
fn interpret_and_emit_10k(c: &mut Criterion) {
    use vision_gcode::{Dialect, Event, Interpreter, InterpreterConfig, Xyz};
    use vision_grbl::emit::{Emitter, Frame};
    use vision_math::LengthUnit;

    let mut text = String::from("G21 G90 G54\nG1 F2000\n");
    for i in 1..=SEGMENTS {
        text.push_str(&format!("X{i} Y{}\n", if i % 2 == 0 { "0.05" } else { "0" }));
    }
    text.push_str("M30\n");
    let frame = Frame { mm_per_unit: 1.0, wco: [0.0; 3], work_system: 1 };
    c.bench_function("grbl/interpret_and_emit_10k_segments", |b| {
        b.iter(|| {
            let mut config = InterpreterConfig::new(LengthUnit::Millimetre);
            config.dialect = Dialect::Grbl;
            let mut interp = Interpreter::new(config);
            let mut emitter = Emitter::new(frame, Xyz::ZERO).expect("emitter");
            let mut bytes = 0usize;
            let mut sink = |e: &Event| {
                for line in emitter.event(e).expect("emit") {
                    bytes += line.len() + 1;
                }
            };
            interp.run(black_box(&text), None, &mut sink).expect("runs");
            black_box(bytes)
        });
    });
}

criterion_group!(benches, stream_10k, interpret_and_emit_10k);
criterion_main!(benches);
