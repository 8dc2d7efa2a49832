//! The hand-written line parser: text → words, `#` assignments and comments.
//!
//! One [`Parser`] is reused for every line; its buffers grow to the longest line and are then
//! reused, so parsing allocates nothing per line. Comments are borrowed from the source text.
//! Literal values take a fast path; expressions are only built where `#`, `[`, a sign before
//! either, or a function name appears.
//!
//! Blanks (space, tab, CR) are ignored everywhere outside comments, as in LinuxCNC: `G 1 X 1 . 5`
//! is `G1 X1.5`. Letters are case-insensitive.

// Private unless the `bench-internals` feature exposes the module.
#![cfg_attr(
    not(feature = "bench-internals"),
    allow(unreachable_pub, dead_code, reason = "read only by the unit tests and that benchmark")
)]

mod expr;
mod number;

use crate::config::Dialect;
use crate::error::{GcodeError, SyntaxProblem};
use crate::expr::Node;
use crate::letters::slot;

pub(crate) use number::is_blank;

/// Internal parse result: the byte position of a problem and the problem.
type PResult<T> = Result<T, (usize, SyntaxProblem)>;

/// Brackets, `#`, signs and function calls nest at most this deep.
pub const MAX_DEPTH: u32 = 64;
/// The most operands the expressions of one line may hold together: a line of LinuxCNC holds
/// at most 256 characters, so this is far beyond any program, and it bounds the memory a
/// runaway generated line (`1+1+…` over megabytes) takes to a few hundred kilobytes.
pub const MAX_OPERANDS: usize = 10_000;

/// A byte cursor over one line.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Cursor<'s> {
    pub(crate) bytes: &'s [u8],
    pub(crate) pos: usize,
}

impl<'s> Cursor<'s> {
    fn new(text: &'s str) -> Cursor<'s> {
        Cursor { bytes: text.as_bytes(), pos: 0 }
    }

    #[inline]
    fn peek(&self) -> Option<u8> {
        self.bytes.get(self.pos).copied()
    }

    #[inline]
    fn skip_blanks(&mut self) {
        while self.bytes.get(self.pos).is_some_and(|&b| is_blank(b)) {
            self.pos += 1;
        }
    }
}

/// Where an expression lives in a [`Block`]'s node list.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Expr {
    start: u32,
    end: u32,
}

/// A word's value as written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// A literal number (with its sign).
    Number(f64),
    /// An expression, a parameter read or a function call; evaluated when the line runs.
    Expr(Expr),
}

/// One word: a letter (`A`–`Z`, upper case, or `$`) and its value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Word {
    letter: u8,
    value: Value,
    at: u32,
}

impl Word {
    /// The letter, upper case (or `$`, or the polar `@` / `^`).
    #[must_use]
    pub fn letter(&self) -> char {
        char::from(self.letter)
    }

    /// The letter as an ASCII byte.
    #[must_use]
    pub(crate) fn letter_byte(&self) -> u8 {
        self.letter
    }

    /// The value as written.
    #[must_use]
    pub fn value(&self) -> Value {
        self.value
    }
}

/// `#target = value`: the parameter number is itself an expression.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Assignment {
    target: Expr,
    value: Value,
    at: u32,
}

impl Assignment {
    /// The expression that computes the parameter number.
    #[must_use]
    pub fn target(&self) -> Expr {
        self.target
    }

    /// The value assigned.
    #[must_use]
    pub fn value(&self) -> Value {
        self.value
    }
}

/// A comment's byte range in the line (the text inside `( )` or after `;`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Span {
    start: u32,
    end: u32,
}

/// One parsed line, borrowing the parser's buffers and the source text.
#[derive(Debug, Clone, Copy)]
pub struct Block<'p, 's> {
    text: &'s str,
    line: u32,
    number: Option<u32>,
    marks: Marks,
    words: &'p [Word],
    assignments: &'p [Assignment],
    comments: &'p [Span],
    nodes: &'p [Node],
    names: &'p [Box<str>],
}

impl<'p, 's> Block<'p, 's> {
    /// The line number in the text (1-based).
    #[must_use]
    pub fn line(&self) -> u32 {
        self.line
    }

    /// The `N` number, if the line has one.
    #[must_use]
    pub fn line_number(&self) -> Option<u32> {
        self.number
    }

    /// Whether the line starts with `/` (block delete: skipped when the switch is on).
    #[must_use]
    pub fn block_delete(&self) -> bool {
        self.marks.block_delete
    }

    /// Whether the line is an o-word line (`o100 sub`, `o<name> call [1]`, …): its text is
    /// left to the control-flow reader; only `/` and `N` before the `o` are parsed.
    #[must_use]
    pub fn is_oword(&self) -> bool {
        self.marks.oword
    }

    /// Whether the line is a `%` program delimiter.
    #[must_use]
    pub fn is_percent(&self) -> bool {
        self.marks.percent
    }

    /// The words in order of appearance.
    #[must_use]
    pub fn words(&self) -> &'p [Word] {
        self.words
    }

    /// The `#n = value` assignments in order of appearance.
    #[must_use]
    pub fn assignments(&self) -> &'p [Assignment] {
        self.assignments
    }

    /// The comments' text (inside `( )`, or after `;`), in order.
    pub fn comments(&self) -> impl Iterator<Item = &'s str> + 'p
    where
        's: 'p,
    {
        let text = self.text;
        self.comments.iter().map(move |s| text.get(s.start as usize..s.end as usize).unwrap_or(""))
    }

    /// True when the line has no words and no assignments (blank, comments only, or `%`).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.words.is_empty() && self.assignments.is_empty()
    }

    /// The named parameters the line mentions (lower case, blanks removed), by
    /// [`Node::Named`] index.
    pub(crate) fn names(&self) -> &'p [Box<str>] {
        self.names
    }

    /// The postfix nodes of `expr`.
    pub(crate) fn nodes(&self, expr: Expr) -> &'p [Node] {
        self.nodes.get(expr.start as usize..expr.end as usize).unwrap_or(&[])
    }
}

/// 1-based character column of byte `offset` in `text`.
fn column(text: &str, offset: usize) -> u32 {
    let mut end = offset.min(text.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    u32::try_from(text[..end].chars().count() + 1).unwrap_or(u32::MAX)
}

/// The marks a line can start with.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct Marks {
    block_delete: bool,
    percent: bool,
    oword: bool,
}

/// The reusable line parser.
#[derive(Debug, Clone, Default)]
pub struct Parser {
    /// Where a comment ends.
    comments_rule: CommentRule,
    words: Vec<Word>,
    assignments: Vec<Assignment>,
    comments: Vec<Span>,
    nodes: Vec<Node>,
    names: Vec<Box<str>>,
}

impl Parser {
    /// A parser with empty buffers.
    #[must_use]
    pub fn new() -> Parser {
        Parser::default()
    }

    /// A parser with `dialect`'s comment rule ([`crate::DialectRules::comments`]);
    /// [`Parser::new`] nests parentheses inside comments (seed 002's).
    #[must_use]
    pub fn for_dialect(dialect: Dialect) -> Parser {
        Parser { comments_rule: dialect.rules().comments, ..Parser::default() }
    }

    /// Parses one line of text (without its line break).
    ///
    /// # Errors
    /// [`GcodeError::Syntax`] with `line` and the column of the problem.
    pub fn parse_line<'p, 's>(&'p mut self, text: &'s str, line: u32) -> Result<Block<'p, 's>, GcodeError> {
        self.parse_with(text, line, Parser::items)
    }

    /// Clears the buffers, runs `read` over `text` and wraps what it left in a [`Block`].
    #[inline]
    fn parse_with<'p, 's>(
        &'p mut self,
        text: &'s str,
        line: u32,
        read: impl FnOnce(&mut Parser, &mut Cursor<'_>, &mut Marks) -> PResult<Option<u32>>,
    ) -> Result<Block<'p, 's>, GcodeError> {
        self.words.clear();
        self.assignments.clear();
        self.comments.clear();
        self.nodes.clear();
        self.names.clear();
        let mut cur = Cursor::new(text);
        let mut marks = Marks::default();
        match read(self, &mut cur, &mut marks) {
            Ok(number) => Ok(Block {
                text,
                line,
                number,
                marks,
                words: &self.words,
                assignments: &self.assignments,
                comments: &self.comments,
                nodes: &self.nodes,
                names: &self.names,
            }),
            Err((at, problem)) => Err(GcodeError::Syntax { line, column: column(text, at), problem }),
        }
    }

    fn items(&mut self, cur: &mut Cursor<'_>, marks: &mut Marks) -> PResult<Option<u32>> {
        let mut early = None;
        self.items_noting(cur, marks, &mut early).map_err(|(at, problem)| match early {
            // The text after a comment that ended at its first `)` although it holds a `(`:
            // say so, since the writer most likely meant it as the rest of the comment.
            Some((open, close)) if at > close => {
                let problem = SyntaxProblem::CommentEndedEarly {
                    open: column_of(cur.bytes, open),
                    close: column_of(cur.bytes, close),
                    problem: Box::new(problem),
                };
                (at, problem)
            }
            _ => (at, problem),
        })
    }

    /// [`Parser::items`], noting in `early` the last comment that ended at its first `)`
    /// although it holds a `(` (its `(` and `)` positions).
    fn items_noting(
        &mut self,
        cur: &mut Cursor<'_>,
        marks: &mut Marks,
        early: &mut Option<(usize, usize)>,
    ) -> PResult<Option<u32>> {
        let mut number = None;
        let mut seen: u32 = 0;
        let mut first = true;
        loop {
            cur.skip_blanks();
            let Some(b) = cur.peek() else { break };
            let at = cur.pos;
            match b {
                b'(' => {
                    let end = self.comments_rule.end(cur.bytes, at)?;
                    if end.early {
                        *early = Some((at, end.close));
                    }
                    self.comments.push(span(at + 1, end.close));
                    cur.pos = end.close + 1;
                    continue;
                }
                b';' => {
                    self.comments.push(span(at + 1, cur.bytes.len()));
                    cur.pos = cur.bytes.len();
                    break;
                }
                b'%' if first => {
                    // Program delimiter: the line holds nothing else but comments.
                    cur.pos += 1;
                    first = false;
                    marks.percent = true;
                    continue;
                }
                b'/' if first && !marks.block_delete => {
                    // Block delete: the line's first character; `N` may follow.
                    cur.pos += 1;
                    marks.block_delete = true;
                    continue;
                }
                b'#' => {
                    cur.pos += 1;
                    let target = self.expr_of(cur, |p, c| if p.named(c)? { Ok(()) } else { p.operand(c, 1) })?;
                    cur.skip_blanks();
                    if cur.peek() != Some(b'=') {
                        return Err((cur.pos, SyntaxProblem::ExpectedEquals));
                    }
                    cur.pos += 1;
                    let value = self.value(cur, b'=', cur.pos)?;
                    self.assignments.push(Assignment { target, value, at: offset(at) });
                }
                _ => {
                    let letter = b.to_ascii_uppercase();
                    // `@` and `^` are LinuxCNC's polar distance and angle.
                    if !(letter.is_ascii_uppercase() || matches!(letter, b'$' | b'@' | b'^')) {
                        return Err((at, unexpected(cur, at)));
                    }
                    if letter == b'O' {
                        if !self.words.is_empty() || !self.assignments.is_empty() {
                            return Err((at, SyntaxProblem::OWordNotFirst));
                        }
                        marks.oword = true;
                        return Ok(number);
                    }
                    cur.pos += 1;
                    if letter == b'N' {
                        if !first {
                            return Err((at, SyntaxProblem::LineNumberNotFirst));
                        }
                        number = Some(line_number(cur)?);
                        first = false;
                        continue;
                    }
                    if letter != b'G' && letter != b'M' {
                        let bit = 1u32 << slot(letter);
                        if seen & bit != 0 {
                            return Err((at, SyntaxProblem::DuplicateWord { letter: char::from(letter) }));
                        }
                        seen |= bit;
                    }
                    let value = self.value(cur, letter, at)?;
                    self.words.push(Word { letter, value, at: offset(at) });
                }
            }
            first = false;
        }
        Ok(number)
    }

    /// The bracketed arguments of an o-word line (`[1] [#2 * 3]`, comments allowed), each as a
    /// word with the letter `[`.
    ///
    /// # Errors
    /// [`GcodeError::Syntax`] for anything but brackets and comments.
    pub(crate) fn parse_args<'p, 's>(&'p mut self, text: &'s str, line: u32) -> Result<Block<'p, 's>, GcodeError> {
        self.parse_with(text, line, |p, cur, _| p.args(cur).map(|()| None))
    }

    fn args(&mut self, cur: &mut Cursor<'_>) -> PResult<()> {
        loop {
            cur.skip_blanks();
            let at = cur.pos;
            match cur.peek() {
                None => return Ok(()),
                Some(b'(') => {
                    let close = self.comments_rule.end(cur.bytes, at)?.close;
                    self.comments.push(span(at + 1, close));
                    cur.pos = close + 1;
                }
                Some(b';') => {
                    self.comments.push(span(at + 1, cur.bytes.len()));
                    return Ok(());
                }
                Some(b'[') => {
                    let value = self.value(cur, b'[', at)?;
                    self.words.push(Word { letter: b'[', value, at: offset(at) });
                }
                Some(_) => return Err((at, unexpected(cur, at))),
            }
        }
    }

    /// A word's (or an assignment's) value: a literal on the fast path, else an expression.
    /// `letter_at` is where a missing value is reported (the word's letter).
    #[inline(always)]
    fn value(&mut self, cur: &mut Cursor<'_>, letter: u8, letter_at: usize) -> PResult<Value> {
        cur.skip_blanks();
        let at = cur.pos;
        match cur.peek() {
            Some(b'0'..=b'9' | b'.') => Ok(Value::Number(number::number(cur)?)),
            Some(sign @ (b'+' | b'-')) => {
                cur.pos += 1;
                cur.skip_blanks();
                if matches!(cur.peek(), Some(b'0'..=b'9' | b'.')) {
                    let v = number::number(cur)?;
                    return Ok(Value::Number(if sign == b'-' { -v } else { v }));
                }
                cur.pos = at;
                Ok(Value::Expr(self.expr_of(cur, |p, c| p.operand(c, 0))?))
            }
            Some(b'#' | b'[') => Ok(Value::Expr(self.expr_of(cur, |p, c| p.operand(c, 0))?)),
            Some(c) if c.is_ascii_alphabetic() && expr::function_at(cur).is_some() => {
                Ok(Value::Expr(self.expr_of(cur, |p, c| p.operand(c, 0))?))
            }
            _ if letter == b'=' => Err((at, SyntaxProblem::ExpectedValue)),
            _ => Err((letter_at, SyntaxProblem::MissingValue { letter: char::from(letter) })),
        }
    }

    /// Runs `f` and returns the range of nodes it pushed.
    fn expr_of(
        &mut self,
        cur: &mut Cursor<'_>,
        f: impl FnOnce(&mut Parser, &mut Cursor<'_>) -> PResult<()>,
    ) -> PResult<Expr> {
        let start = self.nodes.len();
        f(self, cur)?;
        Ok(Expr { start: offset(start), end: offset(self.nodes.len()) })
    }
}

/// Where a `(` comment ends ([`crate::DialectRules::comments`]).
///
/// * [`CommentRule::Nested`] (seed 002, MachineMotion): at the `)` that balances its `(`; the
///   manual's programs write `( Corners at (+/- 2.5, +/- 4.0) inch )`.
/// * [`CommentRule::Mach4`]: at the `)` that balances its `(` when one on the line does, else at
///   its first `)`. Every line the first-`)` rule of RS274/NGC reads is read the same, and so is
///   every line the nesting rule reads: where both read a line they agree (a `(` inside a
///   comment leaves the flat reading one `)` short of balanced), so this rule only adds lines and
///   never changes one. Mach4's G-code manuals do not say; the seed manual, written for Mach4,
///   nests (docs/gcode-interpreter.md, "Comments").
/// * [`CommentRule::Rs274`] (LinuxCNC): at its first `)`, and a `(` inside a comment is an
///   error, as `close_and_downcase` in LinuxCNC's `interp_internal.cc` refuses it ("Nested
///   comment found").
/// * [`CommentRule::FirstClose`] (Grbl 1.1): at its first `)`; Grbl's line reader ignores
///   every byte of a comment until then, a `(` included.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum CommentRule {
    /// Parentheses nest inside comments.
    #[default]
    Nested,
    /// Balanced when the line balances the comment, else the first `)`.
    Mach4,
    /// The first `)`; a `(` inside a comment is refused.
    Rs274,
    /// The first `)`; a `(` inside a comment is part of it.
    FirstClose,
}

/// Where a comment ended, and whether it ended at its first `)` although it holds a `(` (so
/// the text after that `)` may be the rest of the comment the writer meant).
#[derive(Debug, Clone, Copy)]
struct CommentEnd {
    close: usize,
    early: bool,
}

impl CommentRule {
    /// Where the comment opened at `open` (a `(`) ends.
    fn end(self, bytes: &[u8], open: usize) -> PResult<CommentEnd> {
        let rest = bytes.get(open + 1..).unwrap_or(&[]);
        // The common case in one pass: the first parenthesis after `(` is its `)`.
        let inner = match rest.iter().position(|&b| b == b'(' || b == b')').map(|i| open + 1 + i) {
            None => return Err((open, SyntaxProblem::UnclosedComment)),
            Some(close) if bytes[close] == b')' => return Ok(CommentEnd { close, early: false }),
            Some(inner) => inner,
        };
        match self {
            CommentRule::Rs274 => Err((
                inner,
                SyntaxProblem::NestedComment { open: column_of(bytes, open), inner: column_of(bytes, inner) },
            )),
            CommentRule::FirstClose => {
                let first = bytes[inner..].iter().position(|&b| b == b')').map(|i| inner + i);
                first.map(|close| CommentEnd { close, early: true }).ok_or((open, SyntaxProblem::UnclosedComment))
            }
            CommentRule::Nested => balanced(bytes, open)
                .map(|close| CommentEnd { close, early: false })
                .ok_or((open, SyntaxProblem::UnclosedComment)),
            CommentRule::Mach4 => match balanced(bytes, open) {
                Some(close) => Ok(CommentEnd { close, early: false }),
                None => {
                    let first = bytes[inner..].iter().position(|&b| b == b')').map(|i| inner + i);
                    first.map(|close| CommentEnd { close, early: true }).ok_or((open, SyntaxProblem::UnclosedComment))
                }
            },
        }
    }
}

/// The `)` that balances the `(` at `open`, if the line has one.
fn balanced(bytes: &[u8], open: usize) -> Option<usize> {
    let mut depth = 0usize;
    for (i, &b) in bytes.iter().enumerate().skip(open) {
        match b {
            b'(' => depth += 1,
            b')' => {
                depth -= 1;
                if depth == 0 {
                    return Some(i);
                }
            }
            _ => {}
        }
    }
    None
}

/// 1-based character column of byte `offset` in a line's bytes.
fn column_of(bytes: &[u8], offset: usize) -> u32 {
    match std::str::from_utf8(bytes) {
        Ok(text) => column(text, offset),
        Err(_) => u32::try_from(offset + 1).unwrap_or(u32::MAX),
    }
}

fn span(start: usize, end: usize) -> Span {
    Span { start: offset(start), end: offset(end) }
}

/// Offsets and node counts fit in `u32` for any line shorter than 4 GiB; saturate beyond.
fn offset(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

fn unexpected(cur: &Cursor<'_>, at: usize) -> SyntaxProblem {
    let found = std::str::from_utf8(&cur.bytes[at..])
        .ok()
        .and_then(|s| s.chars().next())
        .or_else(|| cur.bytes.get(at).map(|&b| char::from(b)))
        .unwrap_or('?');
    SyntaxProblem::Unexpected { found }
}

/// `N` digits: a whole, unsigned number.
fn line_number(cur: &mut Cursor<'_>) -> PResult<u32> {
    cur.skip_blanks();
    let at = cur.pos;
    let mut n: u32 = 0;
    let mut digits = false;
    while let Some(b) = cur.peek() {
        if b.is_ascii_digit() {
            n = n
                .checked_mul(10)
                .and_then(|n| n.checked_add(u32::from(b - b'0')))
                .ok_or((at, SyntaxProblem::BadLineNumber))?;
            digits = true;
        } else if !is_blank(b) {
            break;
        }
        cur.pos += 1;
    }
    if !digits || cur.peek() == Some(b'.') {
        return Err((at, SyntaxProblem::BadLineNumber));
    }
    Ok(n)
}

#[cfg(test)]
mod tests;
