//! A hostile or broken peer cannot grow the driver's memory: whatever bytes arrive, and however
//! many, one exchange allocates at most a fixed amount. Measured with a counting allocator, so
//! this binary holds a single test.

use std::io::{self, Read, Write};
use std::time::Duration;

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use vision_driver_keyence::{Exchange, Limits};

#[global_allocator]
static GLOBAL: vision_testalloc::PeakAlloc = vision_testalloc::PeakAlloc;

/// Most bytes one session (its buffer included) may hold at once during an exchange.
const BOUND: usize = 4 * 1024;

/// A peer that accepts every write and answers with `pattern` forever (or `bytes` once).
struct Peer<'a> {
    bytes: &'a [u8],
    pattern: Option<&'a [u8]>,
    at: usize,
    served: usize,
}

impl Read for Peer<'_> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = match self.pattern {
            Some(p) => {
                for b in buf.iter_mut() {
                    *b = p[self.at % p.len()];
                    self.at += 1;
                }
                buf.len()
            }
            None => {
                let n = buf.len().min(self.bytes.len() - self.at).min(97);
                buf[..n].copy_from_slice(&self.bytes[self.at..self.at + n]);
                self.at += n;
                n
            }
        };
        self.served += n;
        Ok(n)
    }
}

impl Write for Peer<'_> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// Peak bytes allocated (above what was live before) while a session runs one `TRG` against
/// `peer`, and the bytes the peer served.
fn peak_during(peer: Peer<'_>) -> (usize, usize, bool) {
    let ((served, ok), peak) = vision_testalloc::peak_during(|| {
        let mut s = Exchange::new(peer, Limits::default(), Duration::from_secs(3));
        let ok = s.trigger().is_ok();
        (s.get_ref().served, ok)
    });
    (peak, served, ok)
}

#[test]
fn one_exchange_allocates_a_bounded_amount_whatever_the_peer_sends() {
    // Endless peers: the exchange must end, and memory must not follow the bytes.
    for pattern in [&b"x"[..], b"\r", b"\n\r", b"1,2\r", b"TRG\r", b"ER,PL,01\r", b"TRG\r\xff"] {
        let (peak, served, ok) = peak_during(Peer { bytes: &[], pattern: Some(pattern), at: 0, served: 0 });
        assert!(!ok);
        assert!(peak <= BOUND, "{pattern:?}: {peak} bytes");
        assert!(served <= 16 * 1024, "{pattern:?}: read {served} bytes");
    }
    // Arbitrary replies.
    let mut runner = TestRunner::new(Config { cases: 200, ..Config::default() });
    let strategy = proptest::collection::vec(
        prop_oneof![Just(b'\r'), Just(b'\n'), Just(b','), b'0'..=b'9', any::<u8>()],
        0..3_000,
    );
    runner
        .run(&strategy, |reply| {
            let mut bytes = b"TRG\r".to_vec();
            bytes.extend(&reply);
            let (peak, _, _) = peak_during(Peer { bytes: &bytes, pattern: None, at: 0, served: 0 });
            prop_assert!(peak <= BOUND, "{} bytes", peak);
            Ok(())
        })
        .expect("bounded");
}
