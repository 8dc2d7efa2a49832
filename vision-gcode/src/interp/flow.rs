//! LinuxCNC o-word subroutines and control flow: `sub`/`endsub`/`call`/`return`,
//! `if`/`elseif`/`else`/`endif`, `while`/`endwhile`, `do`/`while`, `repeat`/`endrepeat`,
//! `break`/`continue`, subroutines in files on the subroutine path.
//!
//! A program runs line by line as text streams in until its first o-word line; from there the
//! whole text is indexed once (every o-line's block and where it jumps) and run with a program
//! counter. Plain lines still go through the same line executor, so the hot path of programs
//! without o-words is untouched.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

use super::line::Flow;
use super::{At, Interpreter, Piece, ProgramStream, RunOutcome, MAX_REPEATS};
use crate::error::{GcodeError, RunProblem, SyntaxProblem};
use crate::event::EventSink;
use crate::expr::eval;
use crate::handler::MCodeHandler;
use crate::parse::Value;

/// Whether `line` starts or calls control flow (an o-word line, M98 or M99). Such a line needs
/// the rest of the program (subroutines may be defined anywhere), so a host that feeds
/// [`Interpreter::run`] one line at a time runs the text from there in one call instead. A
/// comment mentioning M98 also answers true (harmless: the rest then runs in one call).
#[must_use]
pub fn needs_program(line: &str) -> bool {
    let b = line.as_bytes();
    if b.get(o_word_at(b)).is_some_and(|c| c.eq_ignore_ascii_case(&b'o')) {
        return true;
    }
    b.iter().enumerate().any(|(at, c)| {
        if !c.eq_ignore_ascii_case(&b'm') {
            return false;
        }
        let digits: Vec<u8> = b[at + 1..].iter().copied().filter(|d| !d.is_ascii_whitespace()).take(3).collect();
        matches!(digits.as_slice(), [b'9', b'8' | b'9'] | [b'9', b'8' | b'9', _])
            && !digits.get(2).is_some_and(|d| d.is_ascii_digit() || *d == b'.')
    })
}

/// Parameters #1–#30 carry a call's arguments and are local to it (LinuxCNC).
const CALL_PARAMS: usize = 30;
/// Calls nest at most this deep (LinuxCNC: 10).
const MAX_CALL_DEPTH: usize = 10;

/// What an o-word line does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Keyword {
    Sub,
    EndSub,
    Call,
    Return,
    If,
    ElseIf,
    Else,
    EndIf,
    While,
    /// The `while` that closes a `do`.
    DoWhile,
    EndWhile,
    Do,
    Repeat,
    EndRepeat,
    Break,
    Continue,
    /// `O1000` alone: a program number (Fanuc/Mach), the target of `M98 P1000`.
    Program,
}

impl Keyword {
    fn parse(word: &str) -> Option<Keyword> {
        Some(match word {
            "sub" => Keyword::Sub,
            "endsub" => Keyword::EndSub,
            "call" => Keyword::Call,
            "return" => Keyword::Return,
            "if" => Keyword::If,
            "elseif" => Keyword::ElseIf,
            "else" => Keyword::Else,
            "endif" => Keyword::EndIf,
            "while" => Keyword::While,
            "endwhile" => Keyword::EndWhile,
            "do" => Keyword::Do,
            "repeat" => Keyword::Repeat,
            "endrepeat" => Keyword::EndRepeat,
            "break" => Keyword::Break,
            "continue" => Keyword::Continue,
            _ => return None,
        })
    }
}

/// One o-word line: its label (`100`, or a name in lower case), keyword, where its arguments
/// start in the line, and the line it jumps to (meaning by keyword, see [`Source::index`]).
#[derive(Debug, Clone)]
struct OLine {
    label: Box<str>,
    keyword: Keyword,
    args: usize,
    jump: usize,
    /// For `if`/`elseif`/`else`: the `endif`.
    end: usize,
}

/// One text: the program, or a subroutine file.
#[derive(Debug)]
struct Source {
    text: String,
    /// Byte range of each line.
    lines: Vec<(usize, usize)>,
    /// The o-line of each line, if any (shared: reading one costs no allocation).
    olines: Vec<Option<Arc<OLine>>>,
}

fn syntax(line: usize, detail: impl Into<String>) -> GcodeError {
    GcodeError::Syntax {
        line: u32::try_from(line + 1).unwrap_or(u32::MAX),
        column: 1,
        problem: SyntaxProblem::BadOWord { detail: detail.into() },
    }
}

/// Where a line's o-word would be: past blanks, a block-delete `/` and an `N` number.
fn o_word_at(b: &[u8]) -> usize {
    let mut i = 0;
    let skip = |i: &mut usize| {
        while b.get(*i).is_some_and(u8::is_ascii_whitespace) {
            *i += 1;
        }
    };
    skip(&mut i);
    if b.get(i) == Some(&b'/') {
        i += 1;
        skip(&mut i);
    }
    if b.get(i).is_some_and(|c| c.eq_ignore_ascii_case(&b'n')) {
        i += 1;
        while b.get(i).is_some_and(|c| c.is_ascii_digit() || c.is_ascii_whitespace()) {
            i += 1;
        }
    }
    i
}

/// Parses the o-word of a line (`/`, `N…`, blanks before it), or `None` when the line has none.
fn oline(text: &str, index: usize) -> Result<Option<OLine>, GcodeError> {
    let b = text.as_bytes();
    let skip = |i: &mut usize| {
        while b.get(*i).is_some_and(u8::is_ascii_whitespace) {
            *i += 1;
        }
    };
    let mut i = o_word_at(b);
    if !b.get(i).is_some_and(|c| c.eq_ignore_ascii_case(&b'o')) {
        return Ok(None);
    }
    i += 1;
    skip(&mut i);
    let label: String = if b.get(i) == Some(&b'<') {
        let close = b[i..].iter().position(|&c| c == b'>').ok_or_else(|| syntax(index, "`o<` is not closed by `>`"))?;
        let name = &text[i + 1..i + close];
        i += close + 1;
        name.chars().filter(|c| !c.is_whitespace()).flat_map(char::to_lowercase).collect()
    } else {
        let start = i;
        while b.get(i).is_some_and(u8::is_ascii_digit) {
            i += 1;
        }
        // Leading zeros do not count: o010 is o10.
        text[start..i].trim_start_matches('0').to_string()
    };
    if label.is_empty() && !b.get(i.saturating_sub(1)).is_some_and(u8::is_ascii_digit) {
        return Err(syntax(index, "the o-word needs a number or a <name>, e.g. o100 or o<pocket>"));
    }
    skip(&mut i);
    let start = i;
    while b.get(i).is_some_and(u8::is_ascii_alphabetic) {
        i += 1;
    }
    let word = text[start..i].to_ascii_lowercase();
    let rest = text[i..].trim_start();
    if word.is_empty()
        && (rest.is_empty() || rest.starts_with(['(', ';']))
        && !label.starts_with(|c: char| !c.is_ascii_digit())
    {
        return Ok(Some(OLine {
            label: label.into_boxed_str(),
            keyword: Keyword::Program,
            args: i,
            jump: usize::MAX,
            end: usize::MAX,
        }));
    }
    let keyword = Keyword::parse(&word).ok_or_else(|| {
        syntax(
            index,
            format!(
                "`{word}` is not an o-word keyword: use sub, endsub, call, return, if, elseif, else, endif, while, endwhile, do, repeat, endrepeat, break or continue"
            ),
        )
    })?;
    Ok(Some(OLine { label: label.into_boxed_str(), keyword, args: i, jump: usize::MAX, end: usize::MAX }))
}

impl Source {
    /// Indexes `text`: every o-line and its jump. `jump` holds: for `sub` its `endsub`; for
    /// `if`/`elseif` the next branch (`elseif`, `else` or `endif`); for `while` its `endwhile`
    /// and back; for `do` its closing `while` and back; for `repeat` its `endrepeat` and back;
    /// for `break`/`continue` the head of their loop.
    fn index(text: String) -> Result<Source, GcodeError> {
        let mut lines = Vec::new();
        let mut start = 0;
        for piece in text.split('\n') {
            lines.push((start, start + piece.len()));
            start += piece.len() + 1;
        }
        let mut olines = HashMap::new();
        // Open blocks: (line, keyword, label), and the branches of each open `if`.
        let mut open: Vec<(usize, Keyword)> = Vec::new();
        let mut branches: HashMap<usize, Vec<usize>> = HashMap::new();
        for (index, &(s, e)) in lines.iter().enumerate() {
            let Some(mut o) = oline(&text[s..e], index)? else { continue };
            let label = o.label.clone();
            let same =
                |olines: &HashMap<usize, OLine>, at: usize| olines.get(&at).is_some_and(|x: &OLine| x.label == label);
            let top = open.last().copied();
            let close = |open: &mut Vec<(usize, Keyword)>, want: Keyword, name: &str| match open.pop() {
                Some((at, k)) if k == want => Ok(at),
                _ => Err(syntax(index, format!("`{name}` without its opening line"))),
            };
            match o.keyword {
                Keyword::Sub | Keyword::If | Keyword::Do | Keyword::Repeat => open.push((index, o.keyword)),
                Keyword::While if top.is_some_and(|(at, k)| k == Keyword::Do && same(&olines, at)) => {
                    let (at, _) = open.pop().unwrap_or((index, Keyword::Do));
                    o.keyword = Keyword::DoWhile;
                    o.jump = at;
                    if let Some(d) = olines.get_mut(&at) {
                        d.jump = index;
                    }
                }
                Keyword::While => open.push((index, Keyword::While)),
                Keyword::EndSub | Keyword::EndWhile | Keyword::EndRepeat | Keyword::EndIf => {
                    let (want, name) = match o.keyword {
                        Keyword::EndSub => (Keyword::Sub, "endsub"),
                        Keyword::EndWhile => (Keyword::While, "endwhile"),
                        Keyword::EndRepeat => (Keyword::Repeat, "endrepeat"),
                        _ => (Keyword::If, "endif"),
                    };
                    let at = close(&mut open, want, name)?;
                    if !same(&olines, at) {
                        return Err(syntax(index, format!("`{name}` closes a block with another label")));
                    }
                    if o.keyword == Keyword::EndIf {
                        let mut chain = vec![at];
                        chain.extend(branches.remove(&at).unwrap_or_default());
                        chain.push(index);
                        for pair in chain.windows(2) {
                            if let Some(x) = olines.get_mut(&pair[0]) {
                                x.jump = pair[1];
                                x.end = index;
                            }
                        }
                    } else {
                        o.jump = at;
                        if let Some(head) = olines.get_mut(&at) {
                            head.jump = index;
                        }
                    }
                }
                Keyword::ElseIf | Keyword::Else => match top {
                    Some((at, Keyword::If)) if same(&olines, at) => branches.entry(at).or_default().push(index),
                    _ => return Err(syntax(index, "`elseif`/`else` outside its `if`")),
                },
                Keyword::Break | Keyword::Continue => {
                    let head = open
                        .iter()
                        .rev()
                        .find(|(at, k)| matches!(k, Keyword::While | Keyword::Do) && same(&olines, *at));
                    // As in LinuxCNC: `repeat` loops have no break/continue.
                    o.jump = head
                        .map(|h| h.0)
                        .ok_or_else(|| syntax(index, "`break`/`continue` outside a while or do loop of its label"))?;
                }
                Keyword::Call | Keyword::Return | Keyword::DoWhile | Keyword::Program => {}
            }
            olines.insert(index, o);
        }
        if let Some(&(at, _)) = open.last() {
            return Err(syntax(at, "this block is never closed"));
        }
        let mut slots = vec![None; lines.len()];
        for (at, o) in olines {
            if let Some(slot) = slots.get_mut(at) {
                *slot = Some(Arc::new(o));
            }
        }
        Ok(Source { text, lines, olines: slots })
    }

    fn oline(&self, index: usize) -> Option<Arc<OLine>> {
        self.olines.get(index).and_then(Clone::clone)
    }

    fn line(&self, index: usize) -> &str {
        self.lines.get(index).and_then(|&(s, e)| self.text.get(s..e)).unwrap_or("")
    }
}

/// An active call.
#[derive(Debug)]
struct CallFrame {
    return_to: (usize, usize),
    /// #1–#30 of the caller (o-word calls; M98 calls share them).
    saved: Option<[f64; CALL_PARAMS]>,
    repeats: usize,
    /// M98: the program's first line and the calls still to make after this one.
    again: Option<((usize, usize), u32)>,
}

/// The control-flow run of one program.
#[derive(Debug, Default)]
struct Runner {
    sources: Vec<Source>,
    subs: HashMap<Box<str>, (usize, usize)>,
    calls: Vec<CallFrame>,
    /// Active `repeat`s: (source, line of the `repeat`, turns left).
    repeats: Vec<(usize, usize, u64)>,
    iterations: u64,
}

/// A program with control flow that runs a line at a time: started by
/// [`Interpreter::start_flow`], advanced by [`Interpreter::step_flow`]. It holds the program's
/// text (indexed), its calls and loops and where it stands, never its events, so a caller that
/// pulls events (the path planner) runs a loop of any length in bounded memory.
#[derive(Debug)]
pub struct FlowRun {
    r: Runner,
    src: usize,
    pc: usize,
    /// The program ended on the line that started it.
    over: Option<Piece>,
}

impl Interpreter {
    /// Starts running `text` a line at a time, by [`Interpreter::run_streamed`]'s rules: its
    /// first line — the one that needs the program ([`needs_program`]) — runs now, the rest
    /// one [`Interpreter::step_flow`] at a time. Lines are numbered from 1 within `text`. No
    /// handler: user M-codes are reported as events.
    ///
    /// # Errors
    /// The first line's error, or a malformed o-word structure anywhere in `text`.
    pub fn start_flow(
        &mut self,
        program: &mut ProgramStream,
        text: &str,
        sink: &mut dyn EventSink,
    ) -> Result<FlowRun, GcodeError> {
        let first = text.split('\n').next().unwrap_or("");
        let at = At { line: 1, tag: 1, nested: false };
        let over = |piece| FlowRun { r: Runner::default(), src: 0, pc: 0, over: Some(piece) };
        match self.exec_line(first, at, None, sink)? {
            Flow::OWord => self.flow_start(text, 0, None, program),
            call @ (Flow::Call { .. } | Flow::Return) => self.flow_start(text, 1, Some(call), program),
            Flow::End(code) => Ok(over(Piece::Over(RunOutcome::Ended { line: 1, code }))),
            Flow::Percent if program.delimited => Ok(over(Piece::Over(RunOutcome::Completed { lines: 1 }))),
            Flow::Percent if program.started && self.config.rules().percent_inside_refused => {
                Err(GcodeError::run(1, RunProblem::PercentInside))
            }
            // A comment that mentions M98: no control flow after all, but the rest runs here.
            flow @ (Flow::Percent | Flow::Continue) => {
                if flow == Flow::Percent {
                    program.delimited = !program.started;
                }
                self.flow_start(text, 1, None, program)
            }
        }
    }

    /// Runs the next line of `run` (a G-code line, or one o-word line and its jump).
    ///
    /// # Errors
    /// As [`Interpreter::run`]; the run is over then.
    pub fn step_flow(
        &mut self,
        run: &mut FlowRun,
        program: &mut ProgramStream,
        sink: &mut dyn EventSink,
    ) -> Result<Option<Piece>, GcodeError> {
        if let Some(piece) = run.over.take() {
            return Ok(Some(piece));
        }
        self.flow_line(run, program, None, sink)
    }

    /// Runs `text` from line `from` (0-based; the first o-word line) with control flow.
    pub(super) fn run_flow(
        &mut self,
        text: &str,
        from: usize,
        pending: Option<Flow>,
        program: &mut ProgramStream,
        mut handler: Option<&mut dyn MCodeHandler>,
        sink: &mut dyn EventSink,
    ) -> Result<Piece, GcodeError> {
        let mut run = self.flow_start(text, from, pending, program)?;
        loop {
            if let Some(piece) = self.flow_line(&mut run, program, handler.as_deref_mut(), sink)? {
                return Ok(piece);
            }
        }
    }

    /// Indexes `text` and stands at line `from` (0-based), after the M98/M99 `pending` of the
    /// line before it.
    fn flow_start(
        &mut self,
        text: &str,
        from: usize,
        pending: Option<Flow>,
        program: &mut ProgramStream,
    ) -> Result<FlowRun, GcodeError> {
        let main = Source::index(text.to_string())?;
        let mut r = Runner::default();
        r.register(main);
        let (mut src, mut pc) = (0, from);
        if let Some(flow) = pending {
            let line = u32::try_from(from).unwrap_or(u32::MAX);
            (src, pc) = self.m98(&mut r, flow, (src, pc), line)?;
        }
        program.started = true;
        Ok(FlowRun { r, src, pc, over: None })
    }

    /// One line of a run with control flow; `Some` when the program is over.
    fn flow_line<'h>(
        &mut self,
        run: &mut FlowRun,
        program: &mut ProgramStream,
        handler: Option<&mut (dyn MCodeHandler + 'h)>,
        sink: &mut dyn EventSink,
    ) -> Result<Option<Piece>, GcodeError> {
        let (r, mut src, mut pc) = (&mut run.r, run.src, run.pc);
        // `break 'step` ends the line, where the text's loop had `continue`.
        'step: {
            let Some(source) = r.sources.get(src) else {
                return Ok(Some(Piece::RanOut { lines: 0 }));
            };
            if pc >= source.lines.len() {
                if src != 0 || !r.calls.is_empty() {
                    return Err(syntax(pc.saturating_sub(1), "the text ended inside a subroutine: add its endsub"));
                }
                let lines = r.sources.first().map_or(0, |s| s.lines.len());
                return Ok(Some(Piece::RanOut { lines: u32::try_from(lines).unwrap_or(u32::MAX) }));
            }
            let line = u32::try_from(pc + 1).unwrap_or(u32::MAX);
            let Some(o) = source.oline(pc) else {
                let raw = source.line(pc);
                let at = At { line, tag: line, nested: false };
                match self.exec_line(raw, at, handler, sink)? {
                    Flow::End(code) => return Ok(Some(Piece::Over(RunOutcome::Ended { line, code }))),
                    flow @ (Flow::Call { .. } | Flow::Return) => {
                        (src, pc) = self.m98(r, flow, (src, pc + 1), line)?;
                        break 'step;
                    }
                    Flow::Percent if program.delimited && src == 0 => {
                        return Ok(Some(Piece::Over(RunOutcome::Completed { lines: line })))
                    }
                    Flow::Percent if src == 0 && self.config.rules().percent_inside_refused => {
                        return Err(GcodeError::run(line, RunProblem::PercentInside))
                    }
                    Flow::Percent => program.delimited = false,
                    Flow::Continue | Flow::OWord => {}
                }
                pc += 1;
                break 'step;
            };
            let args = self.flow_args(source.line(pc).get(o.args..).unwrap_or(""), line)?;
            let cond = |args: &[f64]| args.first().is_some_and(|v| *v != 0.0);
            let next = match o.keyword {
                Keyword::Sub => o.jump + 1,
                Keyword::Program => pc + 1,
                Keyword::EndSub | Keyword::Return => {
                    if let Some(&v) = args.first() {
                        let _ = self.params.write_named("_value", v);
                    }
                    (src, pc) = self.leave(r, line)?;
                    break 'step;
                }
                Keyword::Call => {
                    let target = r.find(&o.label, &self.config.subroutine_path, line)?;
                    if r.calls.len() >= MAX_CALL_DEPTH {
                        return Err(GcodeError::run(line, RunProblem::CallsTooDeep { limit: MAX_CALL_DEPTH }));
                    }
                    let mut saved = [0.0; CALL_PARAMS];
                    for (i, slot) in saved.iter_mut().enumerate() {
                        let n = u32::try_from(i + 1).unwrap_or(1);
                        *slot = self.params.get(n);
                        self.params.set(n, args.get(i).copied().unwrap_or(0.0));
                    }
                    self.params.push_frame();
                    r.calls.push(CallFrame {
                        return_to: (src, pc + 1),
                        saved: Some(saved),
                        repeats: r.repeats.len(),
                        again: None,
                    });
                    src = target.0;
                    target.1 + 1
                }
                Keyword::If => {
                    if cond(&args) {
                        pc + 1
                    } else {
                        self.branch(r, src, o.jump, line)?
                    }
                }
                // Reached in sequence only from the end of a taken branch: leave the `if`.
                Keyword::ElseIf | Keyword::Else => o.end + 1,
                Keyword::EndIf => pc + 1,
                Keyword::While => {
                    if cond(&args) {
                        pc + 1
                    } else {
                        o.jump + 1
                    }
                }
                Keyword::EndWhile => {
                    r.tick(line, self.config.max_loop_iterations)?;
                    o.jump
                }
                Keyword::Do => pc + 1,
                Keyword::DoWhile => {
                    if cond(&args) {
                        r.tick(line, self.config.max_loop_iterations)?;
                        o.jump + 1
                    } else {
                        pc + 1
                    }
                }
                Keyword::Repeat => {
                    let count = args.first().copied().unwrap_or(0.0);
                    if count > f64::from(MAX_REPEATS) {
                        return Err(GcodeError::run(
                            line,
                            RunProblem::RepeatBound { code: "repeat", letter: None, value: count, limit: MAX_REPEATS },
                        ));
                    }
                    if count >= 1.0 {
                        #[expect(
                            clippy::cast_possible_truncation,
                            clippy::cast_sign_loss,
                            reason = "At most MAX_REPEATS here."
                        )]
                        r.repeats.push((src, pc, count.floor() as u64));
                        pc + 1
                    } else {
                        o.jump + 1
                    }
                }
                Keyword::EndRepeat => {
                    let head = o.jump;
                    match r.repeats.last_mut() {
                        Some((s, at, left)) if *s == src && *at == head && *left > 1 => {
                            *left -= 1;
                            r.tick(line, self.config.max_loop_iterations)?;
                            head + 1
                        }
                        _ => {
                            r.repeats.pop();
                            pc + 1
                        }
                    }
                }
                Keyword::Break | Keyword::Continue => {
                    let head = r.sources[src].oline(o.jump);
                    let Some(head) = head else { return Err(syntax(pc, "`break`/`continue` outside its loop")) };
                    let brk = o.keyword == Keyword::Break;
                    match head.keyword {
                        Keyword::Do if !brk => head.jump,
                        Keyword::While if brk => head.jump + 1,
                        Keyword::While => {
                            r.tick(line, self.config.max_loop_iterations)?;
                            o.jump
                        }
                        _ => head.jump + 1,
                    }
                }
            };
            pc = next;
        }
        (run.src, run.pc) = (src, pc);
        Ok(None)
    }

    /// Returns from the innermost call (endsub, return, M99): restores its caller's #1–#30 and
    /// local names; an M98 call with repeats left starts its program again.
    fn leave(&mut self, r: &mut Runner, line: u32) -> Result<(usize, usize), GcodeError> {
        let mut frame = r.calls.pop().ok_or_else(|| GcodeError::run(line, RunProblem::FlowOutsideCall))?;
        r.repeats.truncate(frame.repeats);
        if let Some((start, left)) = frame.again.filter(|(_, left)| *left > 0) {
            frame.again = Some((start, left - 1));
            r.calls.push(frame);
            r.tick(line, self.config.max_loop_iterations)?;
            return Ok((start.0, start.1 + 1));
        }
        if let Some(saved) = frame.saved {
            for (i, v) in saved.iter().enumerate() {
                self.params.set(u32::try_from(i + 1).unwrap_or(1), *v);
            }
            self.params.pop_frame();
        }
        Ok(frame.return_to)
    }

    /// M98 (call program `O<P>`, `L` times) or M99 (return), from a line whose next line is
    /// `next`; where to go on.
    fn m98(
        &mut self,
        r: &mut Runner,
        flow: Flow,
        next: (usize, usize),
        line: u32,
    ) -> Result<(usize, usize), GcodeError> {
        let Flow::Call { program, repeats } = flow else {
            return self.leave(r, line);
        };
        let label = program.to_string();
        let start = r.find(&label, &[], line)?;
        if r.sources[start.0].oline(start.1).map(|o| o.keyword) != Some(Keyword::Program) {
            return Err(GcodeError::run(line, RunProblem::UnknownSubroutine { label: format!("O{program}") }));
        }
        if r.calls.len() >= MAX_CALL_DEPTH {
            return Err(GcodeError::run(line, RunProblem::CallsTooDeep { limit: MAX_CALL_DEPTH }));
        }
        r.calls.push(CallFrame {
            return_to: next,
            saved: None,
            repeats: r.repeats.len(),
            again: Some((start, repeats - 1)),
        });
        Ok((start.0, start.1 + 1))
    }

    /// From a false `if`/`elseif`, the next branch to run: a true `elseif`, the `else`, or past
    /// the `endif`.
    fn branch(&mut self, r: &Runner, src: usize, mut at: usize, line: u32) -> Result<usize, GcodeError> {
        let source = &r.sources[src];
        loop {
            let Some(o) = source.oline(at) else { return Ok(at + 1) };
            match o.keyword {
                Keyword::ElseIf => {
                    let text = source.line(at).get(o.args..).unwrap_or("").to_string();
                    let args = self.flow_args(&text, line)?;
                    if args.first().is_some_and(|v| *v != 0.0) {
                        return Ok(at + 1);
                    }
                    at = o.jump;
                }
                _ => return Ok(at + 1),
            }
        }
    }

    /// Evaluates an o-line's bracketed arguments.
    fn flow_args(&mut self, text: &str, line: u32) -> Result<Vec<f64>, GcodeError> {
        let block = self.parser.parse_args(text, line)?;
        let mut out = Vec::with_capacity(block.words().len());
        for w in block.words() {
            let v = match w.value() {
                Value::Number(n) => n,
                Value::Expr(e) => eval(block.nodes(e), block.names(), &self.params, &mut self.stack)
                    .map_err(|p| GcodeError::run(line, p))?,
            };
            out.push(v);
        }
        Ok(out)
    }
}

impl Runner {
    fn register(&mut self, source: Source) {
        let index = self.sources.len();
        for (at, o) in source.olines.iter().enumerate().filter_map(|(at, o)| o.as_ref().map(|o| (at, o))) {
            if matches!(o.keyword, Keyword::Sub | Keyword::Program) {
                self.subs.entry(o.label.clone()).or_insert((index, at));
            }
        }
        self.sources.push(source);
    }

    /// The `sub` line of `label`: in the texts read so far, else in `label.ngc` on the path.
    fn find(&mut self, label: &str, path: &[PathBuf], line: u32) -> Result<(usize, usize), GcodeError> {
        if let Some(&at) = self.subs.get(label) {
            return Ok(at);
        }
        for dir in path {
            let file = dir.join(format!("{label}.ngc"));
            if let Ok(bytes) = std::fs::read(&file) {
                let text = String::from_utf8(bytes)
                    .unwrap_or_else(|e| e.into_bytes().iter().map(|&b| char::from(b)).collect());
                let source = Source::index(text).map_err(|e| {
                    GcodeError::run(
                        line,
                        RunProblem::SubroutineFile { file: file.display().to_string(), message: e.to_string() },
                    )
                })?;
                self.register(source);
                if let Some(&at) = self.subs.get(label) {
                    return Ok(at);
                }
            }
        }
        Err(GcodeError::run(line, RunProblem::UnknownSubroutine { label: label.to_string() }))
    }

    /// Counts one loop iteration against the limit.
    fn tick(&mut self, line: u32, limit: u64) -> Result<(), GcodeError> {
        self.iterations += 1;
        if self.iterations > limit {
            return Err(GcodeError::run(line, RunProblem::TooManyIterations { limit }));
        }
        Ok(())
    }
}
