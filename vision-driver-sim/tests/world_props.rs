//! World files are a parser of user input: any mutation of a valid world is either refused with
//! a typed error or gives a world whose every number is within its documented range.

use proptest::prelude::*;
use vision_driver_sim::{World, DEFAULT_WORLD_TOML};

/// Every number token of the built-in world, as byte ranges.
fn number_spans() -> Vec<(usize, usize)> {
    let text = DEFAULT_WORLD_TOML.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < text.len() {
        // Skip comments: their numbers are prose.
        if text[i] == b'#' {
            while i < text.len() && text[i] != b'\n' {
                i += 1;
            }
            continue;
        }
        let starts = text[i].is_ascii_digit() || (text[i] == b'-' && text.get(i + 1).is_some_and(u8::is_ascii_digit));
        if starts && (i == 0 || !text[i - 1].is_ascii_alphanumeric() && text[i - 1] != b'_') {
            let s = i;
            i += 1;
            while i < text.len() && (text[i].is_ascii_digit() || b".eE+-".contains(&text[i])) {
                i += 1;
            }
            spans.push((s, i));
        } else {
            i += 1;
        }
    }
    spans
}

fn replacement() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<f64>().prop_map(|v| format!("{v:e}")),
        prop::sample::select(vec![
            "1e300",
            "-1e300",
            "1e-300",
            "0",
            "-0.0",
            "nan",
            "inf",
            "-inf",
            "1e308",
            "99999999999"
        ])
        .prop_map(String::from),
        (-1e7..1e7f64).prop_map(|v| format!("{v}")),
        Just("[1, 2, 3, 4]".to_string()),
        Just("\"junk\"".to_string()),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn mutated_worlds_are_refused_or_within_range(edits in prop::collection::vec((any::<prop::sample::Index>(), replacement()), 1..4)) {
        let spans = number_spans();
        let mut picked: Vec<(usize, usize, String)> =
            edits.into_iter().map(|(i, r)| { let (s, e) = spans[i.index(spans.len())]; (s, e, r) }).collect();
        picked.sort_by_key(|p| std::cmp::Reverse(p.0));
        picked.dedup_by_key(|p| p.0);
        let mut text = DEFAULT_WORLD_TOML.to_string();
        for (s, e, r) in picked {
            text.replace_range(s..e, &r);
        }
        match World::from_toml(&text) {
            Err(e) => prop_assert!(!e.to_string().is_empty()),
            Ok(w) => {
                prop_assert!(w.validate().is_ok());
                let c = &w.camera;
                let lengths = c.offset.iter().chain(&w.machine.start).chain(&w.machine.work_offset);
                for v in lengths {
                    prop_assert!(v.is_finite() && v.abs() <= vision_driver_sim::world::MAX_LENGTH, "{v}");
                }
                prop_assert!(c.units_per_pixel > 0.0 && c.units_per_pixel <= 10.0);
                prop_assert!(c.rotation_deg.abs() <= vision_driver_sim::world::MAX_ANGLE_DEG);
            }
        }
    }
}

#[test]
fn the_number_scanner_finds_the_worlds_numbers() {
    let spans = number_spans();
    assert!(spans.len() > 20, "{}", spans.len());
    assert!(spans.iter().any(|&(s, e)| &DEFAULT_WORLD_TOML[s..e] == "-3.25"));
}
