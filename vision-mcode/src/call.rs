//! M280–M284 words → a typed [`VisionCall`].

use vision_core::{Calibrate, Pieces, RunMode};
use vision_math::bounds::MAX_COORDINATE;

use crate::error::McodeError;

/// First and last Vision M-code.
pub const VISION_MCODES: std::ops::RangeInclusive<u32> = 280..=284;

/// One Vision M-code, parsed and range-checked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum VisionCall {
    /// `M280 [P3|P4]`: begin an alignment run.
    Begin(RunMode),
    /// `M281 [D0|D1]`: capture one mark; `true` keeps the camera's image.
    Capture {
        /// `D1`: keep the image.
        keep_image: bool,
    },
    /// `M282 [P0..P3]`: solve the fit and emit the alignment modals.
    Apply(Pieces),
    /// `M283 Qd | Cn`: calibrate.
    Calibrate(Calibrate),
    /// `M284 [Pn]`: switch the camera job (`None` = the stored `VisionActiveJob`).
    SelectJob(Option<u32>),
}

/// One word a Vision M-code takes, as the M-code reference shows it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WordSpec {
    /// The letter (upper case; a program may write either case).
    pub letter: char,
    /// The values it takes and what each means, e.g. `3 similarity, 4 or omitted rectangle`.
    pub values: &'static str,
    /// Values the word refuses, one per way to be wrong: the reference shows the parser's
    /// refusal of each (so the words shown are the parser's own).
    pub refused: &'static [f64],
}

/// One Vision M-code and the words it takes: [`VisionCall::parse`] accepts exactly these
/// letters, and the M-code reference is generated from this table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct McodeSpec {
    /// The M number (280–284).
    pub m: u32,
    /// What it does, in a few words.
    pub title: &'static str,
    /// Its words, in the order [`VisionCall::parse`] reads them.
    pub words: &'static [WordSpec],
}

/// Every Vision M-code with its words, M280 to M284.
pub const MCODES: &[McodeSpec] = &[
    McodeSpec {
        m: 280,
        title: "begin an alignment run",
        words: &[WordSpec {
            letter: 'P',
            values: "3 similarity fit, 4 or omitted rectangle fit",
            refused: &[5.0, 3.5],
        }],
    },
    McodeSpec {
        m: 281,
        title: "capture the mark under the camera",
        words: &[WordSpec {
            letter: 'D',
            values: "0 or omitted discard the camera's image, 1 keep it (the camera driver saves it)",
            refused: &[2.0],
        }],
    },
    McodeSpec {
        m: 282,
        title: "fit the captured marks and apply the alignment",
        words: &[WordSpec {
            letter: 'P',
            values: "0 or omitted all of the fit, 1 the shift only, 2 shift and rotation, 3 shift, rotation and scale",
            refused: &[4.0, -1.0],
        }],
    },
    McodeSpec {
        m: 283,
        title: "calibrate the camera (K, axis flags, camera tool offset)",
        words: &[
            WordSpec {
                letter: 'Q',
                values: "quick calibration on one dot of this diameter, current units, > 0 and at most 1e9",
                refused: &[-0.5, 0.0],
            },
            WordSpec {
                letter: 'C',
                values: "walk calibration sheet n (C1; on LinuxCNC the letter is P: M283 P1)",
                refused: &[1.5, -1.0],
            },
        ],
    },
    McodeSpec {
        m: 284,
        title: "switch the camera job",
        words: &[WordSpec {
            letter: 'P',
            values: "camera job 0..999; omitted: the profile's VisionActiveJob",
            refused: &[1000.0, 1.5, -1.0],
        }],
    },
];

/// The letters M-code `m` takes (none for a number outside M280–M284).
fn allowed(m: u32) -> &'static [WordSpec] {
    MCODES.iter().find(|s| s.m == m).map_or(&[], |s| s.words)
}

impl VisionCall {
    /// Parses M-code `m` (280–284) with the words of its line (`letter`, value), letters in any
    /// case. Every word must be one the M-code takes, at most once, with a finite value.
    ///
    /// # Errors
    /// [`McodeError::NotVision`], [`McodeError::UnknownWord`], [`McodeError::RepeatedWord`],
    /// [`McodeError::NotFinite`], or [`McodeError::BadWord`] for a value out of range
    /// (`M280 P5`, `M281 D2`, `M283` without exactly one of Q and C, `M284 P1.5`).
    pub fn parse(m: u32, words: &[(char, f64)]) -> Result<VisionCall, McodeError> {
        if !VISION_MCODES.contains(&m) {
            return Err(McodeError::NotVision { m });
        }
        let letters = allowed(m);
        let mut values: [Option<f64>; 2] = [None, None];
        for &(letter, value) in words {
            let letter = letter.to_ascii_uppercase();
            let Some(slot) = letters.iter().position(|w| w.letter == letter) else {
                return Err(McodeError::UnknownWord { m, letter, allowed: letters.iter().map(|w| w.letter).collect() });
            };
            if values[slot].is_some() {
                return Err(McodeError::RepeatedWord { m, letter });
            }
            if !value.is_finite() {
                return Err(McodeError::NotFinite { m, letter });
            }
            values[slot] = Some(value);
        }
        let [first, second] = values;
        Ok(match m {
            280 => VisionCall::Begin(run_mode_word(first)?),
            281 => VisionCall::Capture { keep_image: d_word(first)? },
            282 => VisionCall::Apply(pieces_word(first)?),
            283 => VisionCall::Calibrate(calibrate_words(first, second)?),
            _ => VisionCall::SelectJob(job_word(first)?),
        })
    }

    /// The M number (280–284).
    #[must_use]
    pub fn mcode(&self) -> u32 {
        match self {
            VisionCall::Begin(_) => 280,
            VisionCall::Capture { .. } => 281,
            VisionCall::Apply(_) => 282,
            VisionCall::Calibrate(_) => 283,
            VisionCall::SelectJob(_) => 284,
        }
    }
}

/// An M-code word's value as an integer; `None` for a fraction or a value too large to be one.
fn integer_word(v: f64) -> Option<i64> {
    #[expect(clippy::cast_possible_truncation, reason = "checked integral and in range")]
    (v.is_finite() && v.fract() == 0.0 && v.abs() < 1e15).then_some(v as i64)
}

/// A word as a message quotes it: its letter and its value, readable however large
/// (`Q1e300`, not 301 digits).
fn word(letter: char, v: f64) -> String {
    format!("{letter}{}", vision_math::show::number(v))
}

fn bad(mcode: &'static str, word: String, reason: &str) -> McodeError {
    McodeError::BadWord { mcode, word, reason: reason.into() }
}

/// M280's `P`: 3 similarity, 4 or omitted rectangle.
fn run_mode_word(p: Option<f64>) -> Result<RunMode, McodeError> {
    match p.map(|v| (v, integer_word(v))) {
        None | Some((_, Some(4))) => Ok(RunMode::Rectangle),
        Some((_, Some(3))) => Ok(RunMode::Similarity),
        Some((v, _)) => Err(bad("M280", word('P', v), "P must be 3 (similarity) or 4 / omitted (rectangle)")),
    }
}

/// M282's `P`: 0 or omitted all, 1 shift, 2 rotation, 3 scale.
fn pieces_word(p: Option<f64>) -> Result<Pieces, McodeError> {
    match p.map(|v| (v, integer_word(v))) {
        None | Some((_, Some(0))) => Ok(Pieces::All),
        Some((_, Some(1))) => Ok(Pieces::Shift),
        Some((_, Some(2))) => Ok(Pieces::Rotation),
        Some((_, Some(3))) => Ok(Pieces::Scale),
        Some((v, _)) => {
            Err(bad("M282", word('P', v), "P must be 0 / omitted (all), 1 (shift), 2 (rotation) or 3 (scale)"))
        }
    }
}

/// M283's words: exactly one of `Q` (dot diameter, positive) and `C` (sheet number).
fn calibrate_words(q: Option<f64>, c: Option<f64>) -> Result<Calibrate, McodeError> {
    match (q, c) {
        (Some(d), None) if d > 0.0 && d <= MAX_COORDINATE => Ok(Calibrate::Quick { diameter: d }),
        (Some(d), None) => Err(bad("M283", word('Q', d), "Q is the dot diameter and must be positive, at most 1e9")),
        (None, Some(n)) => integer_word(n)
            .and_then(|n| u32::try_from(n).ok())
            .map(|n| Calibrate::Sheet { n })
            .ok_or_else(|| bad("M283", word('C', n), "C is a calibration sheet number (C1)")),
        _ => Err(bad("M283", String::new(), "give exactly one of Qd (quick, dot diameter d) or Cn (sheet n)")),
    }
}

/// M281's `D`: 0 or omitted discards the image, 1 keeps it.
fn d_word(d: Option<f64>) -> Result<bool, McodeError> {
    match d {
        None => Ok(false),
        Some(0.0) => Ok(false),
        Some(1.0) => Ok(true),
        Some(v) => Err(bad("M281", word('D', v), "D must be 0 / omitted (discard the image) or 1 (keep it)")),
    }
}

/// M284's `P`: a whole camera job 0..=999, or omitted (the stored `VisionActiveJob`).
fn job_word(p: Option<f64>) -> Result<Option<u32>, McodeError> {
    match p.map(|v| (v, integer_word(v))) {
        None => Ok(None),
        Some((v, Some(j))) => u32::try_from(j)
            .ok()
            .filter(|j| *j <= vision_core::module::MAX_JOB)
            .map(Some)
            .ok_or_else(|| bad("M284", word('P', v), "P is the camera job and must be a whole number 0..999")),
        Some((v, None)) => Err(bad("M284", word('P', v), "P is the camera job and must be a whole number 0..999")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn every_mcode_with_its_words() {
        let p = VisionCall::parse;
        assert_eq!(p(280, &[]), Ok(VisionCall::Begin(RunMode::Rectangle)));
        assert_eq!(p(280, &[('p', 3.0)]), Ok(VisionCall::Begin(RunMode::Similarity)));
        assert_eq!(p(281, &[]), Ok(VisionCall::Capture { keep_image: false }));
        assert_eq!(p(281, &[('D', 1.0)]), Ok(VisionCall::Capture { keep_image: true }));
        assert_eq!(p(282, &[('P', 2.0)]), Ok(VisionCall::Apply(Pieces::Rotation)));
        assert_eq!(p(283, &[('C', 1.0)]), Ok(VisionCall::Calibrate(Calibrate::Sheet { n: 1 })));
        assert_eq!(p(283, &[('Q', 0.5)]), Ok(VisionCall::Calibrate(Calibrate::Quick { diameter: 0.5 })));
        assert_eq!(p(284, &[]), Ok(VisionCall::SelectJob(None)));
        assert_eq!(p(284, &[('P', 2.0)]), Ok(VisionCall::SelectJob(Some(2))));
        assert_eq!(p(284, &[('P', 999.0)]), Ok(VisionCall::SelectJob(Some(999))));
        assert_eq!(p(280, &[('P', 4.0)]), Ok(VisionCall::Begin(RunMode::Rectangle)));
        assert_eq!(p(282, &[]), Ok(VisionCall::Apply(Pieces::All)));
        assert_eq!(p(282, &[('P', 0.0)]), Ok(VisionCall::Apply(Pieces::All)));
        assert_eq!(p(282, &[('P', 1.0)]), Ok(VisionCall::Apply(Pieces::Shift)));
        assert_eq!(p(282, &[('P', 3.0)]), Ok(VisionCall::Apply(Pieces::Scale)));
        for m in VISION_MCODES {
            let call = p(m, if m == 283 { &[('C', 1.0)] } else { &[] }).expect("valid");
            assert_eq!(call.mcode(), m);
        }
    }

    #[test]
    fn the_table_is_what_the_parser_takes() {
        let numbers: Vec<u32> = MCODES.iter().map(|s| s.m).collect();
        assert_eq!(numbers, VISION_MCODES.collect::<Vec<_>>());
        for spec in MCODES {
            assert!(spec.words.len() <= 2, "M{}: parse keeps two word slots", spec.m);
            for w in spec.words {
                // Alone a word of M283 is complete; every refused value is refused as a bad word.
                for &v in w.refused {
                    let e = VisionCall::parse(spec.m, &[(w.letter, v)]).expect_err("refused");
                    assert!(matches!(e, McodeError::BadWord { .. }), "M{} {}{v}: {e}", spec.m, w.letter);
                }
            }
            let unknown = VisionCall::parse(spec.m, &[('X', 1.0)]).expect_err("X");
            let letters: String = spec.words.iter().map(|w| w.letter).collect();
            assert_eq!(unknown, McodeError::UnknownWord { m: spec.m, letter: 'X', allowed: letters });
        }
    }

    #[test]
    fn bad_words_are_typed_errors_with_a_clear_message() {
        let p = VisionCall::parse;
        let e = p(281, &[('X', 1.0)]).expect_err("X");
        assert_eq!(e, McodeError::UnknownWord { m: 281, letter: 'X', allowed: "D".into() });
        assert_eq!(e.to_string(), "M281 does not take an X word (it takes: D) — put M281 on a line of its own");
        let q = p(281, &[('Q', 1.0)]).expect_err("Q");
        assert_eq!(q.to_string(), "M281 does not take a Q word (it takes: D) — put M281 on a line of its own");
        assert_eq!(p(280, &[('P', 3.0), ('P', 4.0)]), Err(McodeError::RepeatedWord { m: 280, letter: 'P' }));
        assert_eq!(p(282, &[('P', f64::NAN)]), Err(McodeError::NotFinite { m: 282, letter: 'P' }));
        assert_eq!(p(279, &[]), Err(McodeError::NotVision { m: 279 }));
        assert_eq!(
            p(280, &[('P', 5.0)]).expect_err("P5").to_string(),
            "M280 P5 is invalid: P must be 3 (similarity) or 4 / omitted (rectangle)"
        );
        // A missing word leaves no gap; a huge value reads short.
        assert_eq!(
            p(283, &[]).expect_err("no word").to_string(),
            "M283 is invalid: give exactly one of Qd (quick, dot diameter d) or Cn (sheet n)"
        );
        assert_eq!(
            p(284, &[('P', 1e300)]).expect_err("huge").to_string(),
            "M284 P1e300 is invalid: P is the camera job and must be a whole number 0..999"
        );
        assert!(p(283, &[('Q', -1e-300)]).expect_err("tiny").to_string().starts_with("M283 Q-1e-300 is invalid"));
        // A diameter past the bound of lengths is refused as a word, not calibrated with.
        assert!(p(283, &[('Q', 1e300)]).expect_err("huge").to_string().starts_with("M283 Q1e300 is invalid"));
        for (m, words) in [
            (280, vec![('P', 5.0)]),
            (281, vec![('D', 2.0)]),
            (282, vec![('P', 4.0)]),
            (283, vec![]),
            (283, vec![('Q', 0.5), ('C', 1.0)]),
            (283, vec![('Q', -0.5)]),
            (283, vec![('C', 1.5)]),
            (283, vec![('C', -1.0)]),
            (280, vec![('P', 3.5)]),
            (282, vec![('P', -1.0)]),
            (284, vec![('P', 1.5)]),
            (284, vec![('P', 1000.0)]),
            (284, vec![('P', -1.0)]),
        ] {
            let e = p(m, &words).expect_err("out of range");
            assert!(matches!(e, McodeError::BadWord { .. }), "M{m} {words:?}: {e}");
            assert!(e.to_string().starts_with(&format!("M{m} ")), "{e}");
        }
    }

    proptest! {
        #[test]
        fn arbitrary_words_never_panic(m in 270u32..295, words in proptest::collection::vec(
            (proptest::char::range('A', 'z'), prop_oneof![any::<f64>(), -5.0f64..1500.0, proptest::num::f64::NORMAL, (0u32..6).prop_map(f64::from)]),
            0..4,
        )) {
            match VisionCall::parse(m, &words) {
                Ok(call) => prop_assert_eq!(call.mcode(), m),
                // Short whatever the value (no 300-digit decimals).
                Err(e) => prop_assert!(!e.to_string().is_empty() && e.to_string().len() < 200, "{}", e),
            }
        }
    }
}
