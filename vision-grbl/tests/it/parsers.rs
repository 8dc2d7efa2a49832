//! The response and status parsers on arbitrary bytes: typed errors, never a panic.

use proptest::prelude::*;
use vision_grbl::response::{parse_line, parse_status, Response};
use vision_grbl::state::{parse_offsets, parse_parser_state, parse_settings};

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

    #[test]
    fn offsets_never_panic_and_keep_numbers_finite(
        lines in proptest::collection::vec("\\[?(G5[3-9]|G28|G30|G92|TLO|PRB)?:?[-0-9.,eEinfNa]{0,30}\\]?", 0..14),
    ) {
        if let Ok(o) = parse_offsets(&lines) {
            let all = o.work.iter().flatten().chain(&o.g28).chain(&o.g30).chain(&o.g92).chain([&o.tlo]);
            for v in all {
                prop_assert!(v.is_finite());
            }
        }
    }

    #[test]
    fn parser_state_never_panics_and_keeps_numbers_finite(s in "\\[?GC:([GMTFS][-0-9.eEinfNa]{0,6} ?){0,14}\\]?") {
        if let Ok(p) = parse_parser_state(&[s]) {
            prop_assert!(p.feed.is_finite() && p.spindle.is_finite());
            prop_assert!((1..=6).contains(&p.work_system) && (17..=19).contains(&p.plane));
        }
    }

    #[test]
    fn settings_never_panic_and_keep_numbers_finite(lines in proptest::collection::vec("\\$?[0-9a-z]{0,6}=?[-0-9.eEinfNa ()]{0,12}", 0..10)) {
        if let Ok(settings) = parse_settings(&lines) {
            prop_assert!(settings.iter().all(|(_, v)| v.is_finite()));
        }
    }

    #[test]
    fn any_text_is_refused_or_read_never_a_panic(lines in proptest::collection::vec(".{0,40}", 0..8)) {
        let _ = parse_offsets(&lines);
        let _ = parse_parser_state(&lines);
        let _ = parse_settings(&lines);
    }
}
