//! The one error type of the M-code adapter.

use vision_core::VisionError;

/// "an" before a letter whose spoken name starts with a vowel sound (an X, an F), else "a".
fn article(letter: char) -> &'static str {
    if "AEFHILMNORSX".contains(letter.to_ascii_uppercase()) {
        "an"
    } else {
        "a"
    }
}

/// Why a Vision M-code was refused. Nothing ran and nothing changed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum McodeError {
    /// Not one of M280–M284.
    #[error("M{m} is not a Vision M-code (M280-M284)")]
    NotVision {
        /// The M number.
        m: u32,
    },
    /// A word the M-code does not take.
    #[error("M{m} does not take {} {letter} word (it takes: {allowed}) — put M{m} on a line of its own", article(*letter))]
    UnknownWord {
        /// The M number.
        m: u32,
        /// The letter given.
        letter: char,
        /// The letters it takes.
        allowed: String,
    },
    /// The same letter twice.
    #[error("M{m} has two {letter} words; give each word once")]
    RepeatedWord {
        /// The M number.
        m: u32,
        /// The letter.
        letter: char,
    },
    /// A word whose value is NaN or infinite.
    #[error("M{m} {letter} word is not a finite number; check the expression")]
    NotFinite {
        /// The M number.
        m: u32,
        /// The letter.
        letter: char,
    },
    /// A word whose value the M-code does not accept (e.g. `M280 P5`, `M284 P1000`), or a
    /// word missing (`word` empty: "M283 is invalid: give exactly one of …").
    #[error("{mcode}{}{word} is invalid: {reason}", if word.is_empty() { "" } else { " " })]
    BadWord {
        /// The M-code (`M280`, …).
        mcode: &'static str,
        /// The word as given (`P5`).
        word: String,
        /// What is allowed.
        reason: String,
    },
    /// The Vision module refused (its message is the manual's).
    #[error("{0}")]
    Vision(#[from] VisionError),
}
