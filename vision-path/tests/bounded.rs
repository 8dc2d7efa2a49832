//! Bounded by design (issue 26): a G-code loop streams into the planner a line at a time. A
//! global allocator in this test binary tracks the peak of live bytes (`vision-testalloc`), one
//! test at a time.

use vision_gcode::{Dialect, Interpreter, InterpreterConfig, MAX_REPEATS};
use vision_path::{GcodeItems, Item};

#[global_allocator]
static GLOBAL: vision_testalloc::PeakAlloc = vision_testalloc::PeakAlloc;

#[test]
fn a_loop_streams_its_items_a_line_at_a_time() {
    let text = format!("G20 G90 F100\no100 repeat [{MAX_REPEATS}]\nG1 X1\nG1 X0\no100 endrepeat\nM2\n");
    let interp = Interpreter::new(InterpreterConfig { dialect: Dialect::LinuxCnc, ..InterpreterConfig::default() });
    let mut moves = 0u32;
    let mut last = None;
    let ((), extra) = vision_testalloc::peak_during(|| {
        for item in GcodeItems::new(interp, text.as_str()) {
            match item.expect("runs") {
                Item::Move(s) => {
                    moves += 1;
                    last = Some(s.line);
                }
                Item::End { line } => assert_eq!(line, 6),
                other => panic!("unexpected {other:?}"),
            }
        }
    });
    assert_eq!(moves, 2 * MAX_REPEATS);
    assert_eq!(last, Some(4), "lines count in the whole text");
    // Queued whole, the 200 000 items took tens of megabytes.
    assert!(extra < 1_000_000, "a loop of {moves} moves took {extra} bytes");
}

#[test]
fn a_canned_cycle_of_many_holes_reaches_the_planner_a_hole_at_a_time() {
    let text =
        format!("G20 G90 F10\nG0 Z1\nG91 G81 X0.001 Y0 Z-0.1 R0.1 L{MAX_REPEATS}\nG80\nG90 G2 X100 Y0 I1 J0\nM2\n");
    let interp = Interpreter::new(InterpreterConfig { dialect: Dialect::LinuxCnc, ..InterpreterConfig::default() });
    let (lines, extra) = vision_testalloc::peak_during(|| {
        let mut lines = Vec::new();
        for item in GcodeItems::new(interp, text.as_str()) {
            let line = item.expect("runs").line();
            if lines.last().is_none_or(|(l, _)| *l != line) {
                lines.push((line, 0));
            }
            if let Some((_, n)) = lines.last_mut() {
                *n += 1;
            }
        }
        lines
    });
    // The G0, the rise and 3 moves per hole, the arc, the end.
    assert_eq!(lines, [(2, 1), (3, 1 + 3 * MAX_REPEATS as usize), (5, 1), (6, 1)]);
    // Queued whole, the cycle's 300 000 items took tens of megabytes.
    assert!(extra < 1_000_000, "a cycle line took {extra} bytes");
}
