//! The response and status parsers on arbitrary bytes: typed errors, never a panic.

use proptest::prelude::*;
use vision_grbl::response::{parse_line, parse_status, Response};

proptest! {
    #[test]
    fn parse_line_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
        let _ = parse_line(&bytes);
    }

    #[test]
    fn parse_status_never_panics_and_keeps_numbers_finite(s in "<[A-Za-z:0-9|.,-]{0,80}>?") {
        if let Ok(status) = parse_status(&s) {
            for axes in [status.mpos, status.wpos, status.wco].into_iter().flatten() {
                prop_assert!(axes.iter().all(|v| v.is_finite()));
            }
        }
    }

    #[test]
    fn reports_round_trip(x in -1000.0f64..1000.0, y in -1000.0f64..1000.0) {
        let line = format!("<Run|MPos:{x:.3},{y:.3},0.000|FS:500,0>");
        let Ok(Response::Status(s)) = parse_line(line.as_bytes()) else { panic!("{line}") };
        let m = s.mpos.expect("mpos");
        prop_assert!((m[0] - x).abs() < 0.001 && (m[1] - y).abs() < 0.001);
    }
}
