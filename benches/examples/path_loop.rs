//! Plans a program once and prints its cycle time, setpoint count, wall time and real-time
//! factor — for callgrind (instructions per setpoint) and `/usr/bin/time -v` (peak memory):
//! `cargo run --release -p vision-benches --features bench --example path_loop -- spiral-g64 1000000`
//! (`spiral-g64`, `spiral-g61`: the dense polyline with that many segments; `gcode`: the
//! G-code benchmark's program with that many lines).
use std::time::Instant;

use vision_benches::gcode_program;
use vision_benches::path::{router, spiral, spiral_start};
use vision_gcode::{Interpreter, InterpreterConfig};
use vision_path::{GcodeItems, PathMode, Setpoints};

fn main() {
    let what = std::env::args().nth(1).unwrap_or_else(|| "spiral-g64".into());
    let n: usize = std::env::args().nth(2).and_then(|s| s.parse().ok()).unwrap_or(1_000_000);
    let t = Instant::now();
    let summary = match what.as_str() {
        "gcode" => {
            let text = gcode_program(n, false);
            let items = GcodeItems::new(Interpreter::new(InterpreterConfig::default()), text.as_str());
            let config = router(items.start_position());
            Setpoints::new(&config, items).and_then(Setpoints::run_to_end)
        }
        _ => {
            let mode =
                if what == "spiral-g61" { PathMode::ExactStop } else { PathMode::Blend { tolerance: Some(0.0005) } };
            Setpoints::from_items(&router(spiral_start()), spiral(n, 0.005, 300.0, mode))
                .and_then(Setpoints::run_to_end)
        }
    }
    .expect("the program runs");
    let wall = t.elapsed().as_secs_f64();
    println!(
        "{what} {n}: cycle time {:.1} s, {} setpoints, {} events, wall {wall:.3} s, {:.0} ns/setpoint, {:.0}x real time",
        summary.cycle_time,
        summary.setpoints,
        summary.events,
        wall * 1e9 / summary.setpoints as f64,
        summary.cycle_time / wall
    );
}
