//! The profile's text: TOML in, parameters out, and back.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::error::VisionError;
use crate::params::{ParamValue, Params};

/// Decision: a profile holds `[vision]` and the known drivers' tables and nothing else, and
/// each table only the manual's names; anything more is refused naming it. A save rewrites the
/// whole file, so a key kept only in memory would be silently deleted; a host bridge keeps its
/// own settings in its own file.
#[derive(Serialize)]
struct ProfileFile {
    vision: BTreeMap<String, toml::Value>,
    #[serde(flatten)]
    drivers: BTreeMap<String, BTreeMap<String, toml::Value>>,
}

/// The name of the core's table.
const VISION: &str = "vision";

/// A parameter value as TOML.
fn toml_value(v: ParamValue) -> toml::Value {
    match v {
        ParamValue::Bool(b) => toml::Value::Boolean(b),
        ParamValue::Int(i) => toml::Value::Integer(i),
        ParamValue::Float(f) => toml::Value::Float(f),
        ParamValue::Text(s) => toml::Value::String(s),
    }
}

/// The profile text for `params` (configuration parameters only): `[vision]`, then each
/// driver's table.
///
/// # Errors
/// A serialisation failure (not expected for validated parameters).
pub fn to_toml(params: &Params) -> Result<String, String> {
    let named = |values: Vec<(&'static str, ParamValue)>| {
        values.into_iter().map(|(name, v)| (name.to_string(), toml_value(v))).collect::<BTreeMap<_, _>>()
    };
    let vision = named(params.core_values());
    let drivers = params.drivers_settings().map(|d| (d.table().to_string(), named(d.values()))).collect();
    let body = toml::to_string(&ProfileFile { vision, drivers }).map_err(|e| format!("cannot serialise: {e}"))?;
    Ok(format!(
        "# mach-vision: Vision OEM parameters (calibration and configuration).\n\
         # Written atomically by the Vision module; do not edit VisionCal_K11..K22 by hand.\n{body}"
    ))
}

/// Parameters from profile text, starting from the defaults (which know no driver's table).
///
/// # Errors
/// As [`from_toml_with`].
pub fn from_toml(text: &str) -> Result<Params, String> {
    from_toml_with(text, Params::default())
}

/// Parameters from profile text: `base` overridden by every entry of `[vision]` and of the
/// drivers' tables `base` has.
///
/// # Errors
/// A parse error, a missing `[vision]`, an unknown table or key, an unknown or telemetry name,
/// or an invalid value (the message says which).
pub fn from_toml_with(text: &str, base: Params) -> Result<Params, String> {
    if text.trim().is_empty() {
        return Err("cannot parse: the file is empty — a profile holds a [vision] table; remove the file to start \
                    from the defaults"
            .into());
    }
    let mut file: toml::Table =
        toml::from_str(text).map_err(|e| format!("cannot parse: {}", crate::text::toml_error(&e, text)))?;
    let known: Vec<&str> = base.drivers_settings().map(crate::params::DriverSettings::table).collect();
    if let Some(key) = file.keys().find(|k| *k != VISION && !known.contains(&k.as_str())) {
        let tables: String = std::iter::once(VISION).chain(known.iter().copied()).map(|t| format!("[{t}]")).collect();
        return Err(format!(
            "cannot parse: unknown table or key `{key}`: a profile holds {tables} — move it into [vision] or remove it"
        ));
    }
    let mut params = base;
    let tables = |v: toml::Value, name: &str| match v {
        toml::Value::Table(t) => Ok(t),
        other => Err(format!("cannot parse: `{name}` must be a table [{name}], not {}", shown(&other))),
    };
    let vision = tables(file.remove(VISION).ok_or("cannot parse: missing table [vision]")?, VISION)?;
    for (name, value) in vision {
        params.set(&name, param_value(&name, value)?).map_err(|e| match e {
            VisionError::UnknownParam { .. } => unknown_key(&name, &params),
            other => other.to_string(),
        })?;
    }
    for (table, entries) in file {
        let entries = tables(entries, &table)?;
        let Some(settings) = params.driver_settings_mut(&table) else { continue };
        for (name, value) in entries {
            let value = param_value(&name, value)?;
            if !settings.set(&name, &value).map_err(|e| e.to_string())? {
                let names: Vec<&str> = settings.specs().map(|s| s.name).collect();
                let hint = did_you_mean(&name, names.iter().copied()).map(|n| format!(" (did you mean {n}?)"));
                return Err(format!(
                    "[{table}] {name}: unknown setting{} — [{table}] holds {}; the core's parameters go in [vision]",
                    hint.unwrap_or_default(),
                    names.join(", ")
                ));
            }
        }
    }
    params.calibration.check_k().map_err(|e| e.to_string())?;
    Ok(params)
}

/// The message for `name`, a key of `[vision]` that no parameter has: the name a typo or a
/// name cut short most likely meant, from the parameters `params` holds (the core's and every
/// driver's), when one is that close.
fn unknown_key(name: &str, params: &Params) -> String {
    let e = VisionError::UnknownParam { name: name.to_string() };
    let known =
        Params::specs().chain(params.drivers_settings().flat_map(crate::params::DriverSettings::specs)).map(|s| s.name);
    match did_you_mean(name, known) {
        Some(near) => format!("{e} (did you mean {near}?)"),
        None => e.to_string(),
    }
}

/// The one name of `known` that `name` is one edit away from, ignoring case: a letter wrong,
/// missing or extra, two letters swapped, or the name cut short (a prefix of at least
/// [`MIN_PREFIX_CHARS`] characters that only one known name starts with). `None` when no name
/// is that close, or two are equally close (a guess between them would mislead).
fn did_you_mean<'a>(name: &str, known: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let lower = name.to_ascii_lowercase();
    let mut typo = Vec::new();
    let mut cut = Vec::new();
    for k in known {
        let k_lower = k.to_ascii_lowercase();
        if k_lower == lower {
            continue;
        }
        if edit_distance(&lower, &k_lower) <= 1 {
            typo.push(k);
        } else if lower.chars().count() >= MIN_PREFIX_CHARS && k_lower.starts_with(&lower) {
            cut.push(k);
        }
    }
    typo.dedup();
    cut.dedup();
    match (typo.as_slice(), cut.as_slice()) {
        ([one], _) | ([], [one]) => Some(*one),
        _ => None,
    }
}

/// The shortest prefix [`did_you_mean`] takes for a name cut short: longer than the shared
/// `Vision` and a word, so `VisionCamera` alone suggests nothing.
const MIN_PREFIX_CHARS: usize = 14;

/// The optimal-string-alignment distance between `a` and `b`: the fewest single-character
/// insertions, deletions, substitutions and swaps of two neighbours that turn one into the other.
fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    // Rows i-2, i-1 and i of the table; d[j] = distance between a[..i] and b[..j].
    let mut before: Vec<usize> = vec![0; b.len() + 1];
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for i in 1..=a.len() {
        let mut row = vec![i; b.len() + 1];
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            row[j] = (prev[j] + 1).min(row[j - 1] + 1).min(prev[j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                row[j] = row[j].min(before[j - 2] + 1);
            }
        }
        before = std::mem::replace(&mut prev, row);
    }
    prev[b.len()]
}

/// A TOML value as a parameter value.
fn param_value(name: &str, value: toml::Value) -> Result<ParamValue, String> {
    Ok(match value {
        toml::Value::Boolean(b) => ParamValue::Bool(b),
        toml::Value::Integer(i) => ParamValue::Int(i),
        toml::Value::Float(f) => ParamValue::Float(f),
        toml::Value::String(s) => ParamValue::Text(s),
        // Read as its text, as a number written as text is read as its type.
        toml::Value::Datetime(d) => ParamValue::Text(d.to_string()),
        other => return Err(format!("{name}: unsupported value {}", shown(&other))),
    })
}

/// A TOML value for a message: a date-time as written (toml's `Display` shows its private
/// table), anything else as TOML.
fn shown(value: &toml::Value) -> String {
    match value {
        toml::Value::Datetime(d) => d.to_string(),
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::tests::PROBE;

    #[test]
    fn bad_profiles_are_refused_with_the_reason() {
        assert!(from_toml("[vision]\nVisionCameraResX = 0\n").expect_err("range").contains("VisionCameraResX"));
        assert!(from_toml("[vision]\nVisionLastStatus = \"x\"\n").expect_err("ro").contains("read-only"));
        assert!(from_toml("[vision]\nVisionBogus = 1\n").expect_err("unknown").contains("unknown parameter"));
        assert!(from_toml("not toml [").expect_err("parse").starts_with("cannot parse"));
        assert!(from_toml("[vision]\nVisionDriver = [1]\n").expect_err("array").contains("unsupported"));
        assert!(from_toml("vision = 1\n").expect_err("not a table").contains("[vision]"));
        assert!(from_toml("# nothing\n").expect_err("no [vision]").contains("missing table [vision]"));
        assert!(from_toml(" \n").expect_err("empty").contains("the file is empty — a profile holds a [vision] table"));
        let e = from_toml("[vision]\nVisionCameraResX = 16x\n").expect_err("syntax");
        assert!(e.starts_with("cannot parse: line 2, column ") && e.contains("(`VisionCameraResX = 16x`)"), "{e}");
        assert!(!e.contains('\n'), "{e}");
        // A date-time is read as its text (a calibration date written unquoted), and shown as
        // written, never as toml's private table.
        let p = from_toml("[vision]\nVisionCal_Date = 2024-01-02T03:04:05Z\n").expect("a date");
        assert_eq!(p.cal_date(), "2024-01-02T03:04:05Z");
        let e = from_toml("vision = 2024-01-02\n").expect_err("not a table");
        assert!(e.ends_with("not 2024-01-02"), "{e}");
        let e = from_toml("[vision]\nVisionCameraResX = 2024-01-02\n").expect_err("not a number");
        assert!(e.contains("VisionCameraResX") && !e.contains("$__toml"), "{e}");
        assert_eq!(from_toml("[vision]\n"), Ok(Params::default()));
    }

    #[test]
    fn edit_distance_counts_single_edits_and_swaps() {
        assert_eq!(edit_distance("", ""), 0);
        assert_eq!(edit_distance("abc", ""), 3);
        assert_eq!(edit_distance("", "ab"), 2);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("visionport", "visonport"), 1, "a letter missing");
        assert_eq!(edit_distance("visionport", "visionportt"), 1, "a letter extra");
        assert_eq!(edit_distance("visionport", "visionpart"), 1, "a letter wrong");
        assert_eq!(edit_distance("visionport", "visionprot"), 1, "two letters swapped");
        assert_eq!(edit_distance("visionport", "ivsionport"), 1, "the first two letters swapped");
        assert_eq!(edit_distance("ab", "ba"), 1);
        assert_eq!(edit_distance("visionport", "visionip"), 4);
    }

    #[test]
    fn a_key_one_edit_away_gets_did_you_mean() {
        let e = from_toml("[vision]\nVisionCameraTool = 98\n").expect_err("cut short");
        assert!(
            e.contains("unknown parameter \"VisionCameraTool\"") && e.contains("did you mean VisionCameraToolNumber?"),
            "{e}"
        );
        let e = from_toml("[vision]\nVisionEnabeld = true\n").expect_err("swapped");
        assert!(e.contains("did you mean VisionEnabled?"), "{e}");
        let p = from_toml("[vision]\nvisionenabled = true\n").expect("any case is the name itself");
        assert_eq!(p.get("VisionEnabled"), Ok(ParamValue::Bool(true)));
        let e = from_toml("[vision]\nVisionBogus = 1\n").expect_err("far from all");
        assert!(!e.contains("did you mean"), "{e}");
        // `VisionCal_K1` is one edit from K11 and K12 alike: no guess.
        let e = from_toml("[vision]\nVisionCal_K1 = 1\n").expect_err("ambiguous");
        assert!(!e.contains("did you mean"), "{e}");
        let e =
            from_toml_with("[vision]\n[probe]\nVisionProbeLevl = 3\n", Params::default().with_driver_settings(&PROBE))
                .expect_err("a driver's table");
        assert!(e.contains("did you mean VisionProbeLevel?"), "{e}");
    }

    #[test]
    fn unknown_keys_and_tables_are_refused_naming_them() {
        let e = from_toml("[vision]\nVisionEnabled = true\n[mach4]\nPlugin = 1\n").expect_err("table");
        assert!(e.contains("mach4"), "{e}");
        let e = from_toml("VisionEnabled = true\n").expect_err("top-level key");
        assert!(e.contains("VisionEnabled"), "{e}");
    }

    #[test]
    fn k_is_checked_as_a_whole_at_load_naming_it() {
        let k = |k11: f64, k12: f64, k21: f64, k22: f64| {
            format!("[vision]\nVisionCal_K11 = {k11:e}\nVisionCal_K12 = {k12:e}\nVisionCal_K21 = {k21:e}\nVisionCal_K22 = {k22:e}\n")
        };
        assert!(from_toml(&k(0.0, 0.0, 0.0, 0.0)).is_ok(), "all zero = not calibrated");
        assert!(from_toml(&k(0.00203, 1e-5, -1e-5, 0.00204)).is_ok());
        for (bad, why) in [
            (k(1e300, 0.0, 0.0, 1e300), "in per pixel"),
            (k(1e-12, 0.0, 0.0, 1e-12), "in per pixel"),
            (k(0.002, 0.002, 0.002, 0.002), "singular"),
            (k(0.002, 0.0, 0.0, 0.0), "singular"),
            (k(1e300, 1e300, -1e300, 1e300), "in per pixel"),
        ] {
            let e = from_toml(&bad).expect_err(&bad);
            assert!(e.contains("VisionCal_K11..K22") && e.contains(why), "{bad}: {e}");
        }
        // 1 mm per pixel is fine in mm, absurd (25 in) as inches.
        let mm = format!("{}VisionCal_Units = \"mm\"\n", k(1.0, 0.0, 0.0, 1.0));
        assert!(from_toml(&mm).is_ok(), "1 mm per pixel");
        assert!(from_toml(&k(1.0, 0.0, 0.0, 1.0)).is_err(), "1 in per pixel");
    }

    #[test]
    fn a_pound_block_past_9999_is_refused_at_load() {
        let e = from_toml("[vision]\nVisionPoundVarBase = 9990\n").expect_err("past #9999");
        assert!(e.contains("VisionPoundVarBase") && e.contains("#9990..#10029"), "{e}");
        assert!(from_toml("[vision]\nVisionPoundVarBase = 9960\n").is_ok(), "#9960..#9999");
    }

    /// Decision: text values are read like the host's own profile (Mach4 stores every value
    /// as text), and the next save writes them typed.
    #[test]
    fn text_values_are_read_as_their_type() {
        let p = from_toml("[vision]\nVisionCameraResX = \"1601\"\nVisionEnabled = \"yes\"\n").expect("text");
        assert_eq!(p.camera_res_x(), 1601);
        assert!(p.enabled());
        assert!(to_toml(&p).expect("save").contains("VisionCameraResX = 1601\n"));
        let e = from_toml("[vision]\nVisionCameraResX = \"85x\"\n").expect_err("not a number");
        assert!(e.contains("VisionCameraResX"), "{e}");
    }
}
