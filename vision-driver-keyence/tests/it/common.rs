//! Shared helpers for the loopback tests.
#![expect(unreachable_pub, reason = "helpers shared by the test modules, public to them")]

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use vision_core::Reading;
use vision_driver_keyence::emulator::{EmulatorBuilder, EmulatorHandle, FnSource, Shot};
use vision_driver_keyence::{KeyenceConfig, KeyenceDriver};

/// The driver timeout the tests use.
///
/// Chosen with [`SLACK`] so that [`assert_within`]'s bound, `1.2·T + SLACK` = 850 ms, stays
/// below `2·T` = 1000 ms: a driver that waited two timeouts (a doubled deadline, a retry on a
/// fresh connection, a connect timeout and a reply timeout in sequence) fails the bound. With
/// T = 300 ms the bound was 610 ms > 2·T and could not catch that. Larger T would widen the
/// margin but lengthen every fault test (the slowest waits about 3·T).
pub const T: Duration = Duration::from_millis(500);

/// Absolute margin on top of "timeout + 20 %" for a loaded 2-core CI machine: thread wake-ups
/// and scheduling there can take tens of milliseconds. The property tested is that no failure
/// waits more than one timeout; this margin only absorbs scheduler noise, and must stay below
/// `0.8·T` so the bound stays below two timeouts (checked in [`assert_within`]).
pub const SLACK: Duration = Duration::from_millis(250);

/// Panics unless `start` is at most timeout + 20 % (+ [`SLACK`]) ago, a bound that must itself
/// be below two timeouts (else a doubled wait would pass).
pub fn assert_within(start: Instant, timeout: Duration, what: &str) {
    let took = start.elapsed();
    let bound = timeout.mul_f64(1.2) + SLACK;
    assert!(bound < timeout * 2, "{what}: the bound {bound:?} cannot tell one timeout {timeout:?} from two");
    assert!(took <= bound, "{what} took {took:?}, more than {bound:?}");
}

/// A driver for the emulator at `em` with timeout `t`.
pub fn driver(em: &EmulatorHandle, t: Duration) -> KeyenceDriver {
    KeyenceDriver::new(KeyenceConfig::new("127.0.0.1", em.addr().port()).with_timeout(t)).expect("config")
}

/// A source whose n-th trigger (from 1) reports a mark at (n, 2n) px, and its counter.
pub fn counting() -> (FnSource<impl FnMut() -> Shot + Send>, Arc<AtomicU32>) {
    let n = Arc::new(AtomicU32::new(0));
    let c = Arc::clone(&n);
    let source = FnSource(move || {
        let k = c.fetch_add(1, Ordering::SeqCst) + 1;
        Shot::Reading(Reading { count: Some(1), ..Reading::position(f64::from(k), 2.0 * f64::from(k)) })
    });
    (source, n)
}

/// Starts `builder` on a free loopback port.
pub fn start(builder: EmulatorBuilder) -> EmulatorHandle {
    builder.bind("127.0.0.1:0").expect("bind 127.0.0.1:0")
}
