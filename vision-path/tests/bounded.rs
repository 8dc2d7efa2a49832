//! Bounded by design (issue 26): a G-code loop streams into the planner a line at a time. A
//! global allocator in this test binary tracks the peak of live bytes.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use vision_gcode::{Dialect, Interpreter, InterpreterConfig, MAX_REPEATS};
use vision_path::{GcodeItems, Item};

struct Peak;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

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
