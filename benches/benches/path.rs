#![expect(missing_docs, reason = "criterion_group!/criterion_main! generate undocumented items.")]
//! vision-path: setpoint generation at a 1 ms period — the planner alone on a 1 M-segment
//! dense polyline (G64 and G61), and the interpreter + planner on the G-code benchmark's
//! generated program. Throughput is in setpoints: one setpoint is 1 ms of machine time, so
//! `setpoints/s ÷ 1000` is the real-time factor.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use vision_benches::gcode_program;
use vision_benches::path::{router, spiral, spiral_start};
use vision_gcode::{Interpreter, InterpreterConfig};
use vision_path::{GcodeItems, PathMode, Setpoints, Summary};

const SEGMENTS: usize = 1_000_000;
const GCODE_LINES: usize = 2_000;

fn spiral_run(mode: PathMode) -> Summary {
    Setpoints::from_items(&router(spiral_start()), spiral(SEGMENTS, 0.005, 300.0, mode))
        .expect("valid configuration")
        .run_to_end()
        .expect("the spiral runs")
}

fn gcode_run(text: &str) -> Summary {
    let items = GcodeItems::new(Interpreter::new(InterpreterConfig::default()), text);
    let config = router(items.start_position());
    Setpoints::new(&config, items).expect("valid configuration").run_to_end().expect("the program runs")
}

fn benches(c: &mut Criterion) {
    let mut group = c.benchmark_group("path/1ms");
    group.sample_size(10).measurement_time(Duration::from_secs(15));
    for (name, mode) in [
        ("spiral-1M-segments-G64-P0.0005", PathMode::Blend { tolerance: Some(0.0005) }),
        ("spiral-1M-segments-G61", PathMode::ExactStop),
    ] {
        let setpoints = spiral_run(mode).setpoints;
        group.throughput(Throughput::Elements(setpoints));
        group.bench_function(name, |b| b.iter(|| spiral_run(black_box(mode))));
    }
    let text = gcode_program(GCODE_LINES, false);
    group.throughput(Throughput::Elements(gcode_run(&text).setpoints));
    group.bench_function("gcode-2k-lines-interpret+plan", |b| b.iter(|| gcode_run(black_box(&text))));
    group.finish();
}

criterion_group!(path_benches, benches);
criterion_main!(path_benches);
