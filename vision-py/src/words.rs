//! The words of a vision M-code's block, as LinuxCNC hands them to a remap: a dict of
//! lower-case letters to numbers (`{"p": 3.0}`, the remap's `**words`).

use pyo3::prelude::*;
use pyo3::types::PyDict;
use vision_host::{printable_line, MAX_MESSAGE_CHARS};

/// Why a block's words cannot be read. Which letters an M-code takes, and that values are
/// finite, is the M-code's own check (`vision_mcode::VisionCall::parse`).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum WordError {
    /// A key that is not one ASCII letter.
    #[error("word {key} is not a letter: a remap's words are single letters, e.g. {{\"p\": 3.0}}")]
    NotALetter {
        /// The key as Python shows it.
        key: String,
    },
    /// A value that is not a number.
    #[error("word {letter} is {value}, not a number")]
    NotANumber {
        /// The word's letter, upper case.
        letter: char,
        /// The value as Python shows it.
        value: String,
    },
}

/// One word: `key` must be one ASCII letter (either case), `value` a number (`Err` carries
/// the value as shown, when it is not one). The letter comes back upper case.
///
/// # Errors
/// [`WordError::NotALetter`], [`WordError::NotANumber`].
pub fn word(key: &str, value: Result<f64, String>) -> Result<(char, f64), WordError> {
    let mut chars = key.chars();
    let letter = match (chars.next(), chars.next()) {
        (Some(c), None) if c.is_ascii_alphabetic() => c.to_ascii_uppercase(),
        _ => return Err(WordError::NotALetter { key: format!("{key:?}") }),
    };
    let value = value.map_err(|value| WordError::NotANumber { letter, value })?;
    Ok((letter, value))
}

/// Python's `repr` of `value`, made safe to show.
pub(crate) fn shown(value: &Bound<'_, PyAny>) -> String {
    let text = value.repr().map_or_else(|_| "an unprintable value".to_string(), |r| r.to_string());
    printable_line(&text, MAX_MESSAGE_CHARS)
}

/// Every word of `words`, in the dict's order.
///
/// # Errors
/// The first key or value that is not a word ([`WordError`]).
pub(crate) fn from_dict(words: &Bound<'_, PyDict>) -> Result<Vec<(char, f64)>, WordError> {
    words
        .iter()
        .map(|(key, value)| {
            let key = key.extract::<String>().map_err(|_| WordError::NotALetter { key: shown(&key) })?;
            // A bool is an int to Python; no G-code word is one.
            let number = if value.is_instance_of::<pyo3::types::PyBool>() { None } else { value.extract::<f64>().ok() };
            word(&key, number.ok_or_else(|| shown(&value)))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_letter_of_either_case_and_a_number_is_a_word() {
        assert_eq!(word("p", Ok(3.0)), Ok(('P', 3.0)));
        assert_eq!(word("Q", Ok(-0.25)), Ok(('Q', -0.25)));
        // NaN passes here: the M-code refuses it with its own message (NotFinite).
        assert!(word("d", Ok(f64::NAN)).is_ok_and(|(l, v)| l == 'D' && v.is_nan()));
    }

    #[test]
    fn keys_that_are_not_one_letter_are_refused() {
        for key in ["", "pq", "1", "é", "_", "p "] {
            assert_eq!(word(key, Ok(1.0)), Err(WordError::NotALetter { key: format!("{key:?}") }), "{key:?}");
        }
    }

    #[test]
    fn a_value_that_is_not_a_number_is_refused_with_the_letter() {
        let e = word("p", Err("'three'".to_string()));
        assert_eq!(e, Err(WordError::NotANumber { letter: 'P', value: "'three'".to_string() }));
        assert!(e.is_err_and(|e| e.to_string() == "word P is 'three', not a number"));
    }
}
