#![allow(missing_docs)] // criterion_group!/criterion_main! generate undocumented items.
//! vision-gcode: parse, and parse + interpret, of a generated 1 M-line program (G1/G2/G3,
//! comments, parameters and expressions); and the public `gcode` crate parsing the same program
//! without its parameter lines, for comparison.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use vision_benches::gcode_program;
use vision_gcode::parse::Parser;
use vision_gcode::{Event, Interpreter, InterpreterConfig};

const LINES: usize = 1_000_000;

fn parse_all(parser: &mut Parser, text: &str) -> usize {
    let mut words = 0;
    for (i, line) in text.lines().enumerate() {
        // Line numbers fit in u32 for any benchmark input.
        #[allow(clippy::cast_possible_truncation)]
        if let Ok(block) = parser.parse_line(line, i as u32 + 1) {
            words += block.words().len();
        }
    }
    words
}

fn interpret(text: &str) -> u64 {
    let mut interp = Interpreter::new(InterpreterConfig::default());
    let mut events = 0u64;
    interp
        .run(text, None, &mut |e: &Event| {
            events += 1;
            black_box(e);
        })
        .expect("the generated program runs");
    events
}

fn benches(c: &mut Criterion) {
    let full = gcode_program(LINES, false);
    let literal = gcode_program(LINES, true);
    let mut group = c.benchmark_group("gcode/1M-lines");
    group.sample_size(10).measurement_time(Duration::from_secs(8)).throughput(Throughput::Elements(LINES as u64));
    let mut parser = Parser::new();
    group.bench_function("parse", |b| b.iter(|| parse_all(&mut parser, black_box(&full))));
    group.bench_function("parse-literal-only", |b| b.iter(|| parse_all(&mut parser, black_box(&literal))));
    group.bench_function("parse+interpret", |b| b.iter(|| interpret(black_box(&full))));
    group.bench_function("gcode-crate-parse-literal-only", |b| {
        b.iter(|| {
            gcode::full_parse_with_callbacks(black_box(&literal), gcode::Nop)
                .map(|line| line.gcodes().iter().map(|g| g.arguments().len()).sum::<usize>())
                .sum::<usize>()
        });
    });
    group.finish();
}

criterion_group!(gcode_benches, benches);
criterion_main!(gcode_benches);
