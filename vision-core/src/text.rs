//! Making text safe to show a person: messages and reports quote what the user gave (program
//! comments, profile values, file contents), and that input may hold terminal escape
//! sequences, line breaks or megabytes.
//!
//! Decision: this is done once, where text reaches a person (the CLI's output, a host's
//! message box), not in every message: one rule for every source of text.

use std::fmt::Write as _;

/// Longest message [`printable_line`] keeps whole, characters.
pub const MAX_MESSAGE_CHARS: usize = 2000;

/// `text` as one line a terminal shows as it is: every control character (line breaks,
/// vertical tab, escape, DEL, C1) is written as a Rust-style escape (`\n`, `\u{1b}`), and text
/// longer than `max_chars` keeps its head and tail around a `… [N characters cut] …` mark, so
/// a message still says what went wrong and what to do when it quotes a huge input.
#[must_use]
pub fn printable_line(text: &str, max_chars: usize) -> String {
    let total = text.chars().count();
    if total <= max_chars {
        return escape_controls(text, false);
    }
    let keep = max_chars / 2;
    let head: String = text.chars().take(keep).collect();
    let tail: String = text.chars().skip(total - keep).collect();
    let cut = total - 2 * keep;
    format!(
        "{} … [{cut} character{} cut] … {}",
        escape_controls(&head, false),
        if cut == 1 { "" } else { "s" },
        escape_controls(&tail, false)
    )
}

/// `text` with every control character but the line feed escaped: for multi-line reports
/// whose lines the program itself breaks.
#[must_use]
pub fn printable_lines(text: &str) -> String {
    escape_controls(text, true)
}

fn escape_controls(text: &str, keep_newlines: bool) -> String {
    if !text.chars().any(|c| c.is_control() && !(keep_newlines && c == '\n')) {
        return text.to_string();
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if c.is_control() && !(keep_newlines && c == '\n') {
            // Writing to a String cannot fail.
            let _ = write!(out, "{}", c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// Characters of the offending line [`toml_error`] quotes.
const QUOTED_CHARS: usize = 60;

/// A TOML file's parse error as one line: `line 2, column 13 (`max_speed = 2024-01-01`): invalid
/// type: …` (the position
/// as G-code messages give it), or `the file is empty` — not toml's multi-line excerpt, and not
/// its private names (a date-time shows as `$__toml_private_datetime`).
#[must_use]
pub fn toml_error(e: &toml::de::Error, text: &str) -> String {
    if text.trim().is_empty() {
        return "the file is empty".to_string();
    }
    // toml's own message may span lines ("invalid table header\nexpected `.`, `]`").
    let message = e
        .message()
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ")
        .replace("$__toml_private_datetime", "date-time");
    match e.span() {
        Some(span) => {
            let before = text.get(..span.start).unwrap_or(text);
            let line = before.matches('\n').count() + 1;
            let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
            // The line itself, short: it names the key when the message does not.
            let start = before.rfind('\n').map_or(0, |i| i + 1);
            let source = text[start..].lines().next().unwrap_or("").trim();
            let quoted: String = source.chars().take(QUOTED_CHARS).collect();
            let cut = if source.chars().count() > QUOTED_CHARS { "…" } else { "" };
            format!("line {line}, column {column} (`{quoted}{cut}`): {message}")
        }
        None => message,
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_toml_error_is_one_line_with_its_position() {
        let text = "[machine]\nmax_speed = 2024-01-01\n";
        let e = toml::from_str::<std::collections::BTreeMap<String, std::collections::BTreeMap<String, f64>>>(text)
            .expect_err("a date");
        let line = super::toml_error(&e, text);
        assert!(line.starts_with("line 2, column 13 (`max_speed = 2024-01-01`): ") && !line.contains('\n'), "{line}");
        assert!(!line.contains("$__toml_private"), "{line}");
        let e = toml::from_str::<std::collections::BTreeMap<String, f64>>("x = [").expect_err("syntax");
        assert!(super::toml_error(&e, "x = [").starts_with("line 1, column "), "{e}");
        let e = toml::from_str::<std::collections::BTreeMap<String, f64>>("").map(|_| ()).err();
        if let Some(e) = e {
            assert_eq!(super::toml_error(&e, " \n"), "the file is empty");
        }
    }

    use super::*;

    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(printable_line("plain text — ok", 100), "plain text — ok");
        assert_eq!(
            printable_line("a\u{1b}[31mred\u{b}x\ny\r\u{7f}\u{9b}", 100),
            "a\\u{1b}[31mred\\u{b}x\\ny\\r\\u{7f}\\u{9b}"
        );
        assert_eq!(printable_lines("one\ntwo\u{1b}\n"), "one\ntwo\\u{1b}\n");
    }

    #[test]
    fn long_text_keeps_its_head_and_tail() {
        let quoted = format!("VisionCal_Date = \"{}\" is invalid: must be text", "a".repeat(10_000_000));
        let line = printable_line(&quoted, MAX_MESSAGE_CHARS);
        assert!(line.chars().count() < MAX_MESSAGE_CHARS + 60, "{}", line.len());
        assert!(line.starts_with("VisionCal_Date = \"aaa"));
        assert!(line.ends_with("is invalid: must be text"));
        assert!(line.contains(&format!("[{} characters cut]", quoted.chars().count() - MAX_MESSAGE_CHARS)));
        let exact = "é".repeat(10);
        assert_eq!(printable_line(&exact, 10), exact, "exactly the limit is kept whole");
        assert_eq!(printable_line(&"é".repeat(11), 10), "ééééé … [1 character cut] … ééééé");
    }
}
