//! Bounded by design (issue 26): a G-code loop streams into the planner a line at a time. A
//! global allocator in this test binary tracks the peak of live bytes; the tests take a lock so
//! that one test's allocations do not show in another's peak.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use vision_gcode::{Dialect, Interpreter, InterpreterConfig, MAX_REPEATS};
use vision_path::{GcodeItems, Item};

struct Peak;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

// SAFETY: forwards every call to the system allocator unchanged; only tracks sizes.
unsafe impl GlobalAlloc for Peak {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let live = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
        PEAK.fetch_max(live, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Peak = Peak;

#[test]
fn a_loop_streams_its_items_a_line_at_a_time() {
    let text = format!("G20 G90 F100\no100 repeat [{MAX_REPEATS}]\nG1 X1\nG1 X0\no100 endrepeat\nM2\n");
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    let interp = Interpreter::new(InterpreterConfig { dialect: Dialect::LinuxCnc, ..InterpreterConfig::default() });
    let before = LIVE.load(Ordering::Relaxed);
    PEAK.store(before, Ordering::Relaxed);
    let mut moves = 0u32;
    let mut last = None;
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
    let extra = PEAK.load(Ordering::Relaxed) - before;
    assert_eq!(moves, 2 * MAX_REPEATS);
    assert_eq!(last, Some(4), "lines count in the whole text");
    // Queued whole, the 200 000 items took tens of megabytes.
    assert!(extra < 1_000_000, "a loop of {moves} moves took {extra} bytes");
}

#[test]
fn a_canned_cycle_of_many_holes_reaches_the_planner_a_hole_at_a_time() {
    let text =
        format!("G20 G90 F10\nG0 Z1\nG91 G81 X0.001 Y0 Z-0.1 R0.1 L{MAX_REPEATS}\nG80\nG90 G2 X100 Y0 I1 J0\nM2\n");
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    let interp = Interpreter::new(InterpreterConfig { dialect: Dialect::LinuxCnc, ..InterpreterConfig::default() });
    let before = LIVE.load(Ordering::Relaxed);
    PEAK.store(before, Ordering::Relaxed);
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
    let extra = PEAK.load(Ordering::Relaxed) - before;
    // The G0, the rise and 3 moves per hole, the arc, the end.
    assert_eq!(lines, [(2, 1), (3, 1 + 3 * MAX_REPEATS as usize), (5, 1), (6, 1)]);
    // Queued whole, the cycle's 300 000 items took tens of megabytes.
    assert!(extra < 1_000_000, "a cycle line took {extra} bytes");
}
