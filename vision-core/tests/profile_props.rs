//! The profile is a parser of user input: any value for any key, and arbitrary text, is either
//! refused with a message naming the key (or the parse error) or gives parameters that save and
//! load back unchanged.

use proptest::prelude::*;
use vision_core::profile::{from_toml, to_toml};
use vision_core::Params;

/// The persisted names (configuration and calibration), from the default profile's text.
fn persisted_names() -> Vec<String> {
    let text = to_toml(&Params::default()).expect("defaults save");
    text.lines().filter_map(|l| l.split_once(" = ").map(|(name, _)| name.to_string())).collect()
}

/// A TOML value of any kind, including hostile ones.
fn toml_value() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<i64>().prop_map(|v| v.to_string()),
        any::<f64>().prop_filter("TOML float", |v| v.is_finite()).prop_map(|v| format!("{v:e}")),
        prop::sample::select(vec![
            "inf",
            "-inf",
            "nan",
            "0",
            "-1",
            "1e300",
            "1e-300",
            "true",
            "false",
            "\"\"",
            "\"yes\"",
            "\"8500\"",
            "\"mm\"",
            "\"in\"",
            "[1, 2]",
            "{ a = 1 }",
            "\"\\u0000\"",
            "9223372036854775807",
            "0.5",
            "2024-01-02T03:04:05Z",
            "2024-01-02",
            "03:04:05",
        ])
        .prop_map(str::to_string),
        "\\PC{0,40}".prop_map(|s| format!("{s:?}")),
    ]
}

fn round_trips(p: &Params) -> Result<(), TestCaseError> {
    let text = to_toml(p).map_err(TestCaseError::fail)?;
    let back = from_toml(&text).map_err(|e| TestCaseError::fail(format!("saved profile refused: {e}\n{text}")))?;
    prop_assert_eq!(&back, p);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn any_value_for_any_key_is_refused_naming_it_or_round_trips(
        entries in prop::collection::vec((prop::sample::select(persisted_names()), toml_value()), 1..4),
    ) {
        // Later entries of one key would be a TOML error (duplicate key): keep the first.
        let mut seen = std::collections::BTreeSet::new();
        let entries: Vec<_> = entries.into_iter().filter(|(k, _)| seen.insert(k.clone())).collect();
        let text = entries.iter().fold("[vision]\n".to_string(), |t, (k, v)| format!("{t}{k} = {v}\n"));
        match from_toml(&text) {
            Ok(p) => round_trips(&p)?,
            Err(e) => prop_assert!(
                e.starts_with("cannot parse") || entries.iter().any(|(k, _)| e.contains(k.as_str()))
                    || e.contains("VisionCal_K11..K22"),
                "{text}: {e}"
            ),
        }
    }

    #[test]
    fn arbitrary_text_never_panics_and_what_loads_round_trips(text in "\\PC{0,200}") {
        for text in [text.clone(), format!("[vision]\n{text}")] {
            match from_toml(&text) {
                Ok(p) => round_trips(&p)?,
                // One line, naming no private name of the TOML library.
                Err(e) => prop_assert!(!e.contains('\n') && !e.contains("$__toml"), "{text:?}: {e}"),
            }
        }
    }
}
