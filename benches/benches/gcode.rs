#![expect(missing_docs, reason = "criterion_group!/criterion_main! generate undocumented items.")]
//! vision-gcode: parse, and parse + interpret, of a generated 1 M-line program (G1/G2/G3,
//! comments, parameters and expressions); and the public `gcode` crate parsing the same program
//! without its parameter lines, for comparison; and a control-flow program (an o-word
//! subroutine called in a `while` loop).

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
        #[expect(clippy::cast_possible_truncation, reason = "Line numbers fit in u32 for any benchmark input.")]
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

/// Iterations of the control-flow program's loop.
const CALLS: usize = 100_000;

/// A subroutine called in a loop: per iteration a `while` test, a call with two arguments, one
/// straight move and one arc in the subroutine, its `endsub`, an assignment and the `endwhile`
/// — 7 lines run, 2 moves.
fn flow_program(calls: usize) -> String {
    format!(
        "G20 G90 G17 F40\n\
         o<step> sub\n\
         G1 X[#1 * 0.0001] Y#2\n\
         G2 X[#1 * 0.0001 + 0.1] Y#2 I0.05 J0\n\
         o<step> endsub\n\
         #<i> = 0\n\
         o1 while [#<i> LT {calls}]\n\
         o<step> call [#<i>] [[#<i> MOD 7] * 0.01]\n\
         #<i> = [#<i> + 1]\n\
         o1 endwhile\n\
         M2\n"
    )
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

    let flow = flow_program(CALLS);
    let mut group = c.benchmark_group("gcode/control-flow");
    group.sample_size(10).measurement_time(Duration::from_secs(8)).throughput(Throughput::Elements(CALLS as u64));
    group.bench_function("subroutine-call-in-a-while-loop", |b| b.iter(|| interpret(black_box(&flow))));
    group.finish();
}

criterion_group!(gcode_benches, benches);
criterion_main!(gcode_benches);
