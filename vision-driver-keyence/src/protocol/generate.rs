//! Proptest strategies for Data Output lines: structured lines in the three formats and both
//! number styles, with the reading each must parse as, and small edits that corrupt them.
//!
//! Every value is a whole number of thousandths, so the expected `f64` is `k / 1000` — one
//! correctly rounded division, the same value any correct decimal parser returns for the text.

use proptest::prelude::*;
use vision_core::{Judgment, Reading};

use super::reply::{MAX_ABS_ANGLE_DEG, MAX_ABS_PIXELS, MAX_ABS_SCORE};

/// A generated Data Output line and what it must read as.
#[derive(Debug, Clone)]
pub(crate) struct DataLine {
    /// The line, without delimiter (printable ASCII).
    pub(crate) text: String,
    /// The reading it must parse as; `None` when it claims a mark with a value out of range,
    /// so it must be refused.
    pub(crate) expected: Option<Reading>,
}

/// One numeric field: the value in thousandths and whether it lies within the parser's range.
#[derive(Debug, Clone, Copy)]
struct Value {
    thousandths: i64,
    inside: bool,
}

impl Value {
    fn f64(self) -> f64 {
        let k = self.thousandths as f64;
        k / 1000.0
    }
}

/// A value within `lo..=hi` (units) nine times in ten, else up to 20 % of the range beyond it.
fn value(lo: f64, hi: f64) -> impl Strategy<Value = Value> {
    #[expect(clippy::cast_possible_truncation, reason = "the bounds are whole thousandths far below 2^63")]
    let (lo, hi) = ((lo * 1000.0) as i64, (hi * 1000.0) as i64);
    let beyond = (hi - lo) / 5;
    prop_oneof![
        9 => (lo..=hi).prop_map(|thousandths| Value { thousandths, inside: true }),
        1 => prop_oneof![(hi + 1)..=(hi + beyond), (lo - beyond)..=(lo - 1)]
            .prop_map(|thousandths| Value { thousandths, inside: false }),
    ]
}

/// The text of a numeric field: plain (`-12.5`, `888.123`, `7`) or Keyence fixed width
/// (`-0000000012.500000`), sometimes with spaces around it.
fn number_text(v: f64) -> impl Strategy<Value = String> {
    let plain = prop_oneof![Just(format!("{v}")), Just(format!("{v:.3}"))];
    let sign = if v.is_sign_negative() && v != 0.0 { '-' } else { '+' };
    let fixed = Just(format!("{sign}{:017.6}", v.abs()));
    (prop_oneof![plain, fixed], 0usize..2, 0usize..2)
        .prop_map(|(t, a, b)| format!("{}{t}{}", " ".repeat(a), " ".repeat(b)))
}

/// A judgment field and the judgment it stands for.
fn judgment() -> impl Strategy<Value = (String, Judgment)> {
    prop_oneof![
        Just(("OK", Judgment::Ok)),
        Just(("ok", Judgment::Ok)),
        Just(("1", Judgment::Ok)),
        Just(("1.0", Judgment::Ok)),
        Just(("+0000000001.000000", Judgment::Ok)),
        Just(("NG", Judgment::Ng)),
        Just(("ng", Judgment::Ng)),
        Just(("0", Judgment::Ng)),
        Just(("+0000000000.000000", Judgment::Ng)),
    ]
    .prop_map(|(t, j)| (t.to_string(), j))
}

/// A count field (0–3, mostly 1) and its value.
fn count() -> impl Strategy<Value = (String, u32)> {
    prop_oneof![1 => Just(0u32), 3 => Just(1u32), 1 => 2u32..=3]
        .prop_flat_map(|n| number_text(f64::from(n)).prop_map(move |t| (t, n)))
}

/// The six measured values of a full line: x, y, width, height, angle, score.
fn measured() -> impl Strategy<Value = [Value; 6]> {
    let px = || value(-MAX_ABS_PIXELS, MAX_ABS_PIXELS);
    let size = || value(0.0, MAX_ABS_PIXELS);
    (px(), px(), size(), size(), value(-MAX_ABS_ANGLE_DEG, MAX_ABS_ANGLE_DEG), value(-MAX_ABS_SCORE, MAX_ABS_SCORE))
        .prop_map(|(x, y, w, h, a, s)| [x, y, w, h, a, s])
}

/// A Data Output line of 2 (`x,y`), 3 (`judgment,x,y`) or 8 fields, and what it reads as.
pub(crate) fn data_line() -> impl Strategy<Value = DataLine> {
    (prop_oneof![Just(2usize), Just(3), Just(8)], judgment(), count(), measured()).prop_flat_map(
        |(fields, (judgment_text, judgment), (count_text, count), values)| {
            let used = if fields == 8 { &values[..] } else { &values[..2] };
            let texts: Vec<BoxedStrategy<String>> = used.iter().map(|v| number_text(v.f64()).boxed()).collect();
            let all_inside = used.iter().all(|v| v.inside);
            texts.prop_map(move |numbers| {
                let [x, y, width, height, angle, score] = values.map(Value::f64);
                let (mut parts, reading) = match fields {
                    2 => (Vec::new(), Reading::position(x, y)),
                    3 => (vec![judgment_text.clone()], Reading { judgment, ..Reading::position(x, y) }),
                    _ => (
                        vec![judgment_text.clone(), count_text.clone()],
                        Reading {
                            judgment,
                            count: Some(count),
                            x_px: x,
                            y_px: y,
                            width_px: width,
                            height_px: height,
                            angle_deg: angle,
                            score,
                        },
                    ),
                };
                parts.extend(numbers);
                let claims_mark = reading.judgment != Judgment::Ng && reading.count != Some(0);
                DataLine { text: parts.join(","), expected: (all_inside || !claims_mark).then_some(reading) }
            })
        },
    )
}

/// A small edit that may break a line.
#[derive(Debug, Clone)]
pub(crate) enum Edit {
    /// Removes the character at the index.
    Remove(prop::sample::Index),
    /// Inserts a character at the index.
    Insert(prop::sample::Index, char),
    /// Replaces the character at the index.
    Replace(prop::sample::Index, char),
    /// Cuts the line at the index.
    Truncate(prop::sample::Index),
}

impl Edit {
    /// The edited line (`line` must be ASCII).
    pub(crate) fn apply(&self, line: &str) -> String {
        let mut s = line.to_string();
        let at = |i: &prop::sample::Index, len: usize| if len == 0 { 0 } else { i.index(len) };
        match self {
            Edit::Remove(i) if !s.is_empty() => {
                s.remove(at(i, s.len()));
            }
            Edit::Insert(i, c) => s.insert(at(i, s.len() + 1), *c),
            Edit::Replace(i, c) if !s.is_empty() => {
                let k = at(i, s.len());
                s.replace_range(k..=k, &c.to_string());
            }
            Edit::Truncate(i) => s.truncate(at(i, s.len() + 1)),
            _ => {}
        }
        s
    }
}

/// Edits that keep the line ASCII: characters that matter to the grammar, and a few that do not.
pub(crate) fn edit() -> impl Strategy<Value = Edit> {
    let c = || prop::sample::select(vec!['-', '+', '.', ',', 'e', 'E', ' ', '9', '0', 'x', 'N', '\u{0}', '\u{7f}']);
    let i = any::<prop::sample::Index>;
    prop_oneof![
        i().prop_map(Edit::Remove),
        (i(), c()).prop_map(|(i, c)| Edit::Insert(i, c)),
        (i(), c()).prop_map(|(i, c)| Edit::Replace(i, c)),
        i().prop_map(Edit::Truncate),
    ]
}
