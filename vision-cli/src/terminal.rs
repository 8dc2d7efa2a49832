//! Whether a standard stream reaches a person: progress lines, the note that `fit` waits on the
//! keyboard, and a refusal printed once are for a terminal only; a pipe or a file gets what
//! scripts expect.
//!
//! Decision: the answer comes from the operating system, unless the environment variable
//! [`TERMINAL_ENV`] says `always` or `never` (for every stream at once): a test sees the
//! terminal's output without a pseudo-terminal, and a log can keep the progress lines.

use std::io::IsTerminal as _;

/// `MACH_VISION_TERMINAL`: `always` treats every standard stream as a terminal, `never` as none;
/// unset or any other value asks the operating system.
pub(crate) const TERMINAL_ENV: &str = "MACH_VISION_TERMINAL";

/// A standard stream.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Stream {
    Stdin,
    Stdout,
    Stderr,
}

/// Whether `stream` is a terminal (a person reads or types there), [`TERMINAL_ENV`] first.
pub(crate) fn is_terminal(stream: Stream) -> bool {
    match std::env::var(TERMINAL_ENV).as_deref() {
        Ok("always") => true,
        Ok("never") => false,
        _ => match stream {
            Stream::Stdin => std::io::stdin().is_terminal(),
            Stream::Stdout => std::io::stdout().is_terminal(),
            Stream::Stderr => std::io::stderr().is_terminal(),
        },
    }
}

/// Where a long subcommand tells a person what it is doing: standard error, line by line as it
/// happens, when standard error is a terminal and `--quiet` was not given; nowhere otherwise.
/// Standard output (the report, the JSON) never changes with it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Progress {
    on: bool,
}

impl Progress {
    /// Progress for a run with `--quiet` given or not.
    pub(crate) fn new(quiet: bool) -> Progress {
        Progress { on: !quiet && is_terminal(Stream::Stderr) }
    }

    /// Whether lines are shown.
    pub(crate) fn on(self) -> bool {
        self.on
    }

    /// Shows `text` (one line, made printable).
    pub(crate) fn line(self, text: &str) {
        if self.on {
            show(text);
        }
    }
}

/// `text` as one printable line on standard error, at once (standard error is unbuffered).
pub(crate) fn show(text: &str) {
    eprintln!("{}", vision_core::text::printable_line(text, vision_core::text::MAX_MESSAGE_CHARS));
}
