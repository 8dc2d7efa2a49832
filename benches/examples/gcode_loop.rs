//! Parses (`parse`), interprets (`run`) or parses with the `gcode` crate (`gcode-crate`) a
//! generated program once, or only generates it (`generate`, the baseline to subtract from
//! instruction counts), for callgrind and quick timings:
//! `cargo run --release -p vision-benches --features bench --example gcode_loop -- run 1000000`.
use std::hint::black_box;
use std::time::Instant;

use vision_benches::gcode_program;
use vision_gcode::parse::Parser;
use vision_gcode::{Event, Interpreter, InterpreterConfig};

fn main() {
    let what = std::env::args().nth(1).unwrap_or_else(|| "run".into());
    let lines: usize = std::env::args().nth(2).and_then(|s| s.parse().ok()).unwrap_or(1_000_000);
    let text = gcode_program(lines, what == "gcode-crate" || what == "generate-literal");
    let t = Instant::now();
    let count: u64 = match what.as_str() {
        "generate" | "generate-literal" => text.len() as u64,
        "parse" => {
            let mut parser = Parser::new();
            let mut words = 0u64;
            for (i, line) in text.lines().enumerate() {
                let n = u32::try_from(i + 1).unwrap_or(u32::MAX);
                words += parser.parse_line(black_box(line), n).map_or(0, |b| b.words().len() as u64);
            }
            words
        }
        "gcode-crate" => gcode::full_parse_with_callbacks(black_box(&text), gcode::Nop)
            .map(|l| l.gcodes().iter().map(|g| g.arguments().len() as u64).sum::<u64>())
            .sum(),
        _ => {
            let mut interp = Interpreter::new(InterpreterConfig::default());
            let mut events = 0u64;
            interp
                .run(black_box(&text), None, &mut |e: &Event| {
                    events += 1;
                    black_box(e);
                })
                .expect("runs");
            events
        }
    };
    let s = t.elapsed().as_secs_f64();
    let rate = lines as f64 / s / 1e6;
    println!("{what}: {lines} lines in {:.1} ms = {rate:.2} M lines/s ({count} words/events)", s * 1e3);
}
