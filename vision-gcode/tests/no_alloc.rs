//! Parsing and interpreting ordinary lines (moves, arcs, comments, parameters, expressions,
//! modal codes, 17-digit literals) allocates nothing once the buffers have grown: a counting
//! global allocator in this test binary checks it.
//!
//! Only the test's own thread is counted: the test harness's main thread may still be doing its
//! bookkeeping for the spawned test (it did, on a loaded machine), and that is not ours.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

use vision_gcode::{Event, Interpreter, InterpreterConfig};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    /// Set on the thread whose allocations are counted (const-initialised, no destructor: reading
    /// it never allocates).
    static COUNTED: Cell<bool> = const { Cell::new(false) };
}

fn count() {
    if COUNTED.try_with(Cell::get).unwrap_or(false) {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
    }
}

// SAFETY: forwards every call to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

const BODY: &str = "\
N10 G1 X1.2345 Y-2.5 Z-0.1 F30 (cut)
G2 X3.2345 Y-2.5 I1 J0 ; half circle
G3 X1.2345 Y-2.5 R1.0
#1 = [#1 + 0.5] #2 = [SIN[30] * #1 MOD 7]
G1 X#2 Y[#1 / 4] Z-[0.05 * 2]
G91 G0 X0.1
G90 G61
G64 P0.001 G17 G20
G4 P0.01
G54 G52 X0.1 Y0.1
G68 X1 Y1 R5
G51 X1.001 Y1.001
G0 X1 Y1
G0 X0.30000000000000004 Y1.0000 0000 0000 0002 (17 digits, as Rust prints an f64)
G0 X1 Y1
G2 X2 Y2 I0.5 J0.5
G51 X1.001 Y0.999
G0 X2 Y2
G3 X1 Y1 I-0.5 J-0.5 (a polyline)
G69 G50 G52 X0 Y0
(only a comment)

";

#[test]
fn ordinary_lines_allocate_nothing() {
    COUNTED.with(|c| c.set(true));
    let mut interp = Interpreter::new(InterpreterConfig::default());
    let mut events = 0usize;
    let mut sink = |_: &Event| events += 1;
    // Warm up: buffers grow to their working size.
    interp.run(BODY, None, &mut sink).expect("runs");
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    for _ in 0..100 {
        interp.run(BODY, None, &mut sink).expect("runs");
    }
    let during = ALLOCATIONS.load(Ordering::Relaxed) - before;
    assert_eq!(during, 0, "{during} allocations over 100 runs of the program");

    assert!(events > 0);
}
