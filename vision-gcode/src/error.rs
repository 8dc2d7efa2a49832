//! The one error type of `vision-gcode` and the problems it names.
//!
//! Every message says what went wrong and what to do about it. A syntax error carries the line
//! and the (1-based, character) column; a run-time error carries the line. Every number a
//! message quotes is shown by [`vision_math::show::number`] (`L1e15`, `0.3`), the one format of
//! numbers in messages.

use std::fmt;

use vision_math::show::number;

/// Why a word is not a whole, non-negative number of at most `u32::MAX` (`L1e15` is whole, and
/// too large).
fn whole_problem(value: f64) -> String {
    if value.is_finite() && value.fract() == 0.0 {
        if value < 0.0 {
            "must not be negative".to_string()
        } else {
            format!("is too large: at most {}", u32::MAX)
        }
    } else {
        "must be a whole number".to_string()
    }
}

/// A G-code number as written, in tenths: `G90.1` is `GCode(901)`, `G1` is `GCode(10)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GCode(pub u16);

impl fmt::Display for GCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.is_multiple_of(10) {
            write!(f, "G{}", self.0 / 10)
        } else {
            write!(f, "G{}.{}", self.0 / 10, self.0 % 10)
        }
    }
}

/// Where a message points in the source: `line 3`, or `line 3, column 7` (1-based, characters).
/// The one format of every message with a position, whichever tool reports it.
#[must_use]
pub fn source_position(line: u64, column: Option<u32>) -> String {
    match column {
        Some(column) => format!("line {line}, column {column}"),
        None => format!("line {line}"),
    }
}

/// Why a program stopped. Nothing is ever silently ignored: an unknown code or an unused word
/// is one of these, with its line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GcodeError {
    /// The line does not parse.
    #[error("{}: {problem}", source_position(u64::from(*line), Some(*column)))]
    Syntax {
        /// 1-based line number in the text being run.
        line: u32,
        /// 1-based column (characters) where the problem was found.
        column: u32,
        /// What is wrong.
        problem: SyntaxProblem,
    },
    /// The line parses but cannot run; the line changed nothing.
    #[error("line {line}: {problem}")]
    Run {
        /// 1-based line number in the text being run.
        line: u32,
        /// What is wrong.
        problem: RunProblem,
    },
    /// A user M-code handler refused or failed.
    #[error("line {line}: M{code} failed: {message}")]
    Handler {
        /// Line of the M-code.
        line: u32,
        /// The M number.
        code: u32,
        /// The handler's own message.
        message: String,
    },
    /// G-code that a user M-code handler ran (or returned) failed; `inner` numbers its lines
    /// from 1 within that text.
    #[error("line {line}: G-code run by M{code} failed: {inner}")]
    HandlerGcode {
        /// Line of the M-code.
        line: u32,
        /// The M number.
        code: u32,
        /// The failure inside the handler's text.
        inner: Box<GcodeError>,
    },
}

impl GcodeError {
    /// The line the error is reported at (for handler failures: the M-code's line).
    #[must_use]
    pub fn line(&self) -> u32 {
        match self {
            GcodeError::Syntax { line, .. }
            | GcodeError::Run { line, .. }
            | GcodeError::Handler { line, .. }
            | GcodeError::HandlerGcode { line, .. } => *line,
        }
    }

    /// The column of a syntax error, `None` for the other kinds.
    #[must_use]
    pub fn column(&self) -> Option<u32> {
        match self {
            GcodeError::Syntax { column, .. } => Some(*column),
            _ => None,
        }
    }

    pub(crate) fn run(line: u32, problem: RunProblem) -> GcodeError {
        GcodeError::Run { line, problem }
    }
}

/// Why a line does not parse.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum SyntaxProblem {
    /// A character that cannot start or continue anything here.
    #[error("unexpected `{found}`: expected a word (letter and value), `#n = value`, or a comment")]
    Unexpected {
        /// The character found.
        found: char,
    },
    /// A word letter without a value.
    #[error("`{letter}` has no value: write a number, `#n`, `[expression]` or a function after it")]
    MissingValue {
        /// The word letter.
        letter: char,
    },
    /// Digits expected.
    #[error("malformed number: expected digits with at most one `.`")]
    BadNumber,
    /// A `(` comment without its `)`.
    #[error("comment `(` is not closed: add `)` before the end of the line")]
    UnclosedComment,
    /// A `(` inside a comment, which LinuxCNC (rs274) refuses ("Nested comment found").
    #[error(
        "a `(` at column {inner} inside the comment opened at column {open}: LinuxCNC does not \
         allow nested comments; remove the inner parentheses or write [ ] instead"
    )]
    NestedComment {
        /// Column of the comment's `(`.
        open: u32,
        /// Column of the `(` inside it.
        inner: u32,
    },
    /// The rest of a line after a comment that ended at its first `)` although it holds a `(`
    /// (Mach4, when no `)` on the line balances the comment) does not parse.
    #[error(
        "the comment opened at column {open} ended at the `)` at column {close} (its inner `(` is \
         never closed, so it ends at its first `)`), and the text after it is read as G-code: \
         {problem}; balance the parentheses inside the comment, or write [ ] instead"
    )]
    CommentEndedEarly {
        /// Column of the comment's `(`.
        open: u32,
        /// Column of the `)` that ended it.
        close: u32,
        /// What went wrong after it.
        problem: Box<SyntaxProblem>,
    },
    /// A `[` without its `]`.
    #[error("`[` is not closed: add `]`")]
    UnclosedBracket,
    /// A value was expected inside an expression.
    #[error("expected a value: a number, `#n`, `[expression]`, `-value` or a function such as SIN[30]")]
    ExpectedValue,
    /// An operator or the closing bracket was expected.
    #[error("expected an operator (** * / MOD + - EQ NE GT GE LT LE AND OR XOR) or `]`")]
    ExpectedOperator,
    /// A name that is neither a function nor (in operator position) an operator.
    #[error("unknown function: expected one of ABS ACOS ASIN ATAN COS EXP FIX FUP LN ROUND SIN SQRT TAN")]
    UnknownFunction,
    /// A function name not followed by `[`.
    #[error("`{name}` needs its argument in brackets, e.g. {name}[30]")]
    FunctionNeedsBracket {
        /// The function name.
        name: &'static str,
    },
    /// ATAN written other than `ATAN[y]/[x]`.
    #[error("ATAN takes two arguments written ATAN[y]/[x]")]
    AtanForm,
    /// Brackets, `#` or signs nested too deeply.
    #[error("expression nested more than {limit} levels deep: simplify it")]
    TooDeep {
        /// The nesting limit.
        limit: u32,
    },
    /// A line's expressions hold more operands than the parser takes.
    #[error("the line's expressions hold more than {limit} operands: split the computation over several lines")]
    TooLong {
        /// The operand limit.
        limit: usize,
    },
    /// `#n` at the start of an item must be an assignment.
    #[error("expected `=` after `#...`: a parameter at the start of an item is an assignment, `#1 = 2`")]
    ExpectedEquals,
    /// `N` after another item.
    #[error("the line number `N` must be the first word of the line")]
    LineNumberNotFirst,
    /// `N` with a fraction, a sign or an expression.
    #[error("the line number `N` must be a whole number, e.g. N10")]
    BadLineNumber,
    /// An `o` word after other words.
    #[error("an o-word (`o100 sub`, `o<name> call`, `o1 if [...]`) must start its line (after `/` and `N` only)")]
    OWordNotFirst,
    /// A malformed o-word line.
    #[error("o-word line: {detail}")]
    BadOWord {
        /// What is wrong.
        detail: String,
    },
    /// `#<` without its `>`, or an empty name.
    #[error("named parameter `#<` is not closed: write #<name>")]
    UnclosedName,
    /// The same letter twice (G and M may repeat).
    #[error("two `{letter}` words on one line: keep one")]
    DuplicateWord {
        /// The repeated letter.
        letter: char,
    },
}

/// Why a line that parses cannot run. The line changed nothing (for a user M-code line: see
/// "A line is atomic" in the repository's `docs/gcode-interpreter.md`).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RunProblem {
    /// A host's save or restore of the modal state that cannot be done.
    #[error("modal state: {what}")]
    ModalStack {
        /// Why.
        what: &'static str,
    },
    /// A G-code this interpreter does not implement.
    #[error("{code} is not supported: this machine knows G0 G1 G2 G3 G4 G10 G17 G18 G19 G20 G21 G28 G28.1 G30 G30.1 G40 G43 G43.1 G49 G50 G51 G52 G53 G54-G59 G61 G61.1 G64 G68 G69 G73 G80-G83 G85 G89 G90 G90.1 G91 G91.1 G92 G92.1 G92.2 G94 G97 G98 G99")]
    UnknownGCode {
        /// The code.
        code: GCode,
    },
    /// A G value that is not a whole number of tenths (e.g. `G1.25`) or is out of range.
    #[error("G{} is not a G-code: G numbers have at most one decimal", number(*value))]
    BadGCode {
        /// The value written.
        value: f64,
    },
    /// An M-code that is neither built in nor in the user range.
    #[error(
        "M{code} is not supported: built in are M0 M1 M2 M3 M4 M5 M6 M7 M8 M9 M30, user M-codes are M{user_low}-M{user_high}"
    )]
    UnknownMCode {
        /// The M number.
        code: u32,
        /// First user M-code.
        user_low: u32,
        /// Last user M-code.
        user_high: u32,
    },
    /// An M value that is not a non-negative whole number.
    #[error("M{} is not an M-code: M numbers are whole and non-negative", number(*value))]
    BadMCode {
        /// The value written.
        value: f64,
    },
    /// Two codes of one modal group on a line.
    #[error("{first} and {second} are in the same modal group: keep one of them on this line")]
    ModalConflict {
        /// The first code, as written (`G0`, `M3`).
        first: String,
        /// The second code.
        second: String,
    },
    /// Two codes that both want the axis words.
    #[error("{first} and {second} both use the axis words: put them on separate lines")]
    AxisWordConflict {
        /// The first code.
        first: String,
        /// The second code.
        second: String,
    },
    /// One word claimed by two codes (e.g. `P` by both G4 and G64).
    #[error("`{letter}` is used by both {first} and {second}: put them on separate lines")]
    WordConflict {
        /// The word letter.
        letter: char,
        /// The first code.
        first: &'static str,
        /// The second code.
        second: &'static str,
    },
    /// A word no code on the line uses.
    #[error("`{letter}` word is not used by any code on this line: remove it or add the code that uses it")]
    UnusedWord {
        /// The word letter.
        letter: char,
    },
    /// A user M-code shares its line with G- or M-codes.
    #[error("user M-code M{code} must be alone on its line with its own words; move {other} to its own line")]
    UserMCodeNotAlone {
        /// The user M-code.
        code: u32,
        /// The other code found.
        other: String,
    },
    /// A user M-code in G-code that a handler runs.
    #[error("user M-code M{code} inside G-code run by a handler: handlers cannot call user M-codes")]
    NestedUserMCode {
        /// The user M-code.
        code: u32,
    },
    /// M2/M30 in G-code run by a handler.
    #[error("M{code} inside G-code run by a handler: only the program itself can end the program")]
    EndInHandler {
        /// 2 or 30.
        code: u32,
    },
    /// A word that must be a whole, non-negative number (up to `u32::MAX`).
    #[error("`{letter}{}` {}", number(*value), whole_problem(*value))]
    NotWhole {
        /// The word letter.
        letter: char,
        /// The value written.
        value: f64,
    },
    /// A required word is missing.
    #[error("{code} needs `{letter}`: {hint}")]
    MissingWord {
        /// The code.
        code: &'static str,
        /// The missing letter.
        letter: char,
        /// What to write.
        hint: &'static str,
    },
    /// A word value out of its range.
    #[error("{code}: `{letter}{}` is out of range: {hint}", number(*value))]
    OutOfRange {
        /// The code.
        code: &'static str,
        /// The letter.
        letter: char,
        /// The value.
        value: f64,
        /// The valid range.
        hint: &'static str,
    },
    /// A code that needs at least one axis word got none.
    #[error("{code} needs at least one of X, Y, Z")]
    NoAxisWords {
        /// The code.
        code: &'static str,
    },
    /// A rotary or auxiliary axis word.
    #[error("`{letter}` axis is not supported: this machine has X, Y and Z only")]
    AxisNotSupported {
        /// The axis letter.
        letter: char,
    },
    /// G51 with an axis it cannot scale.
    #[error("G51 scales X and Y only; remove `{letter}`")]
    ScaleAxis {
        /// The letter.
        letter: char,
    },
    /// G51 with a zero factor.
    #[error("G51 `{letter}0`: a zero scale factor collapses the axis; use a non-zero factor (1 = unscaled)")]
    ZeroScale {
        /// The axis.
        letter: char,
    },
    /// Axis words with no motion mode active.
    #[error("axis words but no motion mode: program G0, G1, G2 or G3 first")]
    NoMotionMode,
    /// A feed move with no feed rate.
    #[error("{code} with no feed rate: program F (length units per minute) first")]
    NoFeedRate {
        /// The motion code.
        code: &'static str,
    },
    /// A feed move under G95 (feed per revolution) with no spindle speed.
    #[error("{code} under G95 (feed per revolution) with no spindle speed: program S (revolutions per minute), or G94 and a feed per minute")]
    NoSpindleSpeed {
        /// The motion code.
        code: &'static str,
    },
    /// G2/G3 with neither centre words nor R.
    #[error("{code} needs centre words ({centre}) or R")]
    ArcNoCentre {
        /// The motion code.
        code: &'static str,
        /// The centre words of the active plane.
        centre: &'static str,
    },
    /// G2/G3 with a centre word outside the active plane.
    #[error(
        "`{letter}` is not a centre word of the {plane} plane (use {centre}, or select the plane with G17/G18/G19)"
    )]
    ArcCentreWord {
        /// The letter.
        letter: char,
        /// The plane code.
        plane: &'static str,
        /// The plane's centre words.
        centre: &'static str,
    },
    /// G2/G3 with both R and centre words.
    #[error("{code} has both R and centre words: use one form")]
    ArcBothForms {
        /// The motion code.
        code: &'static str,
    },
    /// G2/G3 without an end point in the plane (and not a full circle form).
    #[error("{code} needs at least one axis word; for a full circle repeat the start point, e.g. G2 X.. Y.. I..")]
    ArcNoEnd {
        /// The motion code.
        code: &'static str,
    },
    /// The arc's radius (to its start or its end) is below LinuxCNC's minimum (0.000 05 in,
    /// 0.001 27 mm), or `R0`.
    #[error("arc radius too small: the radius to the start or the end is below 0.00005 in (0.00127 mm); check the centre words, R and G90.1/G91.1")]
    ArcZeroRadius,
    /// Start and end radii differ beyond tolerance.
    #[error("radius to the arc end ({}) differs from the radius to its start ({}) by more than the tolerance: check the centre words, the end point and G90.1/G91.1", number(*end_radius), number(*start_radius))]
    ArcRadiusMismatch {
        /// Radius at the start, current units.
        start_radius: f64,
        /// Radius at the end, current units.
        end_radius: f64,
    },
    /// A code this interpreter deliberately does not implement, named with its feature.
    #[error("{code} is not supported: {feature} is not available on this machine; remove it from the program (or post-process for a 3-axis mill)")]
    Unsupported {
        /// The code as written (`G41`, `M62`).
        code: String,
        /// What it does, e.g. "cutter radius compensation".
        feature: &'static str,
    },
    /// A code the dialect's controller does not have ([`crate::DialectRules::missing_code_note`]).
    #[error("{code} is not supported: {feature} ({codes}: {note}) is not available on this machine; remove it from the program (or post-process for a 3-axis mill)")]
    NotInDialect {
        /// The code as written (`G68`).
        code: String,
        /// What it does, e.g. "scaling and rotation".
        feature: &'static str,
        /// The codes of the feature (`G50/G51, G68/G69`).
        codes: &'static str,
        /// Why, naming the controller.
        note: &'static str,
    },
    /// A feed move with a zero feed rate.
    #[error("{code} with feed rate F0: the move would never end; program a positive F")]
    ZeroFeedRate {
        /// The motion code.
        code: &'static str,
    },
    /// G53 with a motion mode other than G0/G1, or under G91.
    #[error("G53 moves in machine coordinates with G0 or G1 under G90 only: {hint}")]
    G53Form {
        /// What to change.
        hint: &'static str,
    },
    /// G80 with axis words.
    #[error("G80 cancels canned cycles and takes no axis words: put the move on its own line")]
    G80AxisWords,
    /// A canned cycle whose retract plane R lies below its bottom Z.
    #[error("{code}: the retract plane R is below the hole bottom Z; R must be at or above Z")]
    CycleRBelowZ {
        /// The cycle.
        code: &'static str,
    },
    /// R smaller than half the chord.
    #[error("arc radius R{} is too small to reach the end point {} away (half the chord): use a larger R", number(*radius), number(*half_chord))]
    ArcRadiusTooSmall {
        /// |R|, current units.
        radius: f64,
        /// Half the distance from start to end, current units.
        half_chord: f64,
    },
    /// R-format arc whose end is its start.
    #[error("R-format arc with its end at its start: a full circle needs the centre form (I/J/K)")]
    ArcRFullCircle,
    /// An arc that would need more polyline segments than allowed.
    #[error("arc would need {segments} segments at the chord tolerance: raise the tolerance or split the arc")]
    ArcTooManySegments {
        /// The number needed.
        segments: u64,
    },
    /// A tool number not in the tool table.
    #[error("tool {tool} is not in the tool table: define it or use another T number")]
    UnknownTool {
        /// The tool number.
        tool: u32,
    },
    /// M3/M4/M5 with no tool to act on.
    #[error("{code} with no tool: load one with Tn M6, name it with $n, or use the explicit form A<device> P<port>")]
    NoSpindleTool {
        /// The M-code.
        code: &'static str,
    },
    /// The explicit output form with A or P missing.
    #[error("{code} explicit form needs both A<device> and P<port>")]
    OutputForm {
        /// The M-code.
        code: &'static str,
    },
    /// A parameter number out of the dialect's range or not whole.
    #[error("#{} is not a parameter: use a whole number from 1 to {last} (the {dialect} range)", number(*index))]
    BadParameter {
        /// The index as computed.
        index: f64,
        /// The dialect's highest parameter number.
        last: u32,
        /// The dialect's name.
        dialect: &'static str,
    },
    /// A named parameter read before any value was assigned to it.
    #[error("named parameter #<{name}> is not defined: assign it first, e.g. #<{name}> = 0")]
    UndefinedName {
        /// The name (lower case).
        name: String,
    },
    /// LinuxCNC: the text ended without M2/M30 or a closing `%`.
    #[error("the program ended with no M2/M30 or closing %: LinuxCNC refuses that; end it with M2")]
    NoProgramEnd,
    /// LinuxCNC: a `%` line that neither opens the program (first line) nor closes one that a
    /// `%` opened.
    #[error(
        "a % line inside the program: LinuxCNC refuses it (\"Bad character '%' used\"); % may only open the program on its first line and close it; remove this one"
    )]
    PercentInside,
    /// `endsub` or `return` with no call to return from.
    #[error("endsub/return outside a subroutine call")]
    FlowOutsideCall,
    /// o-word calls nested too deeply.
    #[error("subroutine calls nest more than {limit} deep: check for unintended recursion")]
    CallsTooDeep {
        /// The limit.
        limit: usize,
    },
    /// A subroutine neither in the program nor on the subroutine path.
    #[error(
        "subroutine o<{label}> is not defined in the program and no {label}.ngc on the subroutine path defines it"
    )]
    UnknownSubroutine {
        /// The label.
        label: String,
    },
    /// A subroutine file that does not read.
    #[error("subroutine file {file}: {message}")]
    SubroutineFile {
        /// The file.
        file: String,
        /// Its problem.
        message: String,
    },
    /// A repeat count above [`crate::MAX_REPEATS`].
    #[error("{code}: `{}` exceeds the {limit} repeat bound: {}", repeat_word(*.letter, *.value), repeat_advice(.code))]
    RepeatBound {
        /// The code (`G81`, `M98`, `G2`, `repeat`).
        code: &'static str,
        /// The count's letter (`L`, `P`), `None` for an o-word `repeat [n]`.
        letter: Option<char>,
        /// The count written.
        value: f64,
        /// The bound.
        limit: u32,
    },
    /// A canned-cycle line that would make more than [`crate::MAX_CYCLE_MOVES`] moves.
    #[error("{code} would make more than {limit} moves (repeats × pecks): program fewer holes per line or a larger peck depth")]
    CycleTooManyMoves {
        /// The cycle.
        code: &'static str,
        /// The bound.
        limit: u64,
    },
    /// A loop ran more often than allowed.
    #[error("loops ran more than {limit} iterations: the program probably never leaves a loop")]
    TooManyIterations {
        /// The limit.
        limit: u64,
    },
    /// An o-word in G-code a handler runs.
    #[error("o-words (subroutines and control flow) cannot appear in G-code run by a handler")]
    FlowInHandler,
    /// A write to one of LinuxCNC's predefined named parameters.
    #[error("#<{name}> is one of LinuxCNC's predefined parameters and read-only: use another name")]
    ReadOnlyName {
        /// The name (lower case).
        name: String,
    },
    /// A write to a read-only parameter.
    #[error("#{index} is read-only ({what}); write to another parameter")]
    ReadOnlyParameter {
        /// The parameter number.
        index: u32,
        /// What it reports.
        what: &'static str,
    },
    /// Division by zero in an expression.
    #[error("division by zero in an expression")]
    DivisionByZero,
    /// A function outside its domain.
    #[error("{function}[{}] is undefined: {hint}", number(*argument))]
    Domain {
        /// The function or operator.
        function: &'static str,
        /// The argument.
        argument: f64,
        /// The valid domain.
        hint: &'static str,
    },
    /// NaN or infinity from an expression or a computation.
    #[error("{what} is not a finite number: check the expression and its parameters")]
    NonFinite {
        /// What produced it.
        what: &'static str,
    },
    /// A numeric word (not an expression) that is not finite, e.g. a huge literal.
    #[error("`{letter}` value is not a finite number")]
    NonFiniteWord {
        /// The letter.
        letter: char,
    },
    /// A negative or non-finite time/feed/tolerance.
    #[error("{code}: `{letter}{}` must not be negative", number(*value))]
    Negative {
        /// The code.
        code: &'static str,
        /// The letter.
        letter: char,
        /// The value.
        value: f64,
    },
    /// A G10 form other than L2 / L20.
    #[error("G10 L{} is not supported: use G10 L2 (set offset) or G10 L20 (set offset from the current position)", number(*l))]
    G10Form {
        /// The L value.
        l: f64,
    },
    /// LinuxCNC's polar words `@` / `^` where they cannot be used.
    #[error("polar coordinates (`@` distance, `^` angle): {problem}")]
    Polar {
        /// Why not here.
        problem: &'static str,
    },
    /// `R` on `G10 L20` (LinuxCNC rotates a system with `G10 L2 … R` only).
    #[error("R is not allowed on G10 L20: rotate the system with G10 L2 P… R…, then set its origin with G10 L20")]
    G10RotationL20,
    /// A word, computed position or offset beyond ±[`crate::MAX_COORDINATE`] machine units.
    #[error("{what} is {} machine units, beyond ±{}: check the program's units and values", number(*value), number(crate::MAX_COORDINATE))]
    BeyondRange {
        /// What it is (`the X word`, `the move's machine position`, `#5221`).
        what: String,
        /// The value, machine units.
        value: f64,
    },
    /// A computed machine position that is not finite (e.g. huge values through G51).
    #[error("the move's machine position is not a finite number: check the values and the active G51 scale")]
    NonFinitePosition,
}

/// A repeat count as written: `L10000000`, or `[200000]` for an o-word `repeat`.
fn repeat_word(letter: Option<char>, value: f64) -> String {
    match letter {
        Some(l) => format!("{l}{}", number(value)),
        None => format!("[{}]", number(value)),
    }
}

/// What to do instead of a repeat count over the bound, by code.
fn repeat_advice(code: &str) -> &'static str {
    match code {
        "M98" => "call it from a loop instead",
        "repeat" => "nest two repeats, or use a while loop",
        "G2" | "G3" => "program the turns over several lines",
        _ => "split the holes over several lines",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 33: every number a message quotes goes through the one formatter
    /// ([`vision_math::show::number`]): `L1e15`, never `L1000000000000000`, and no message
    /// grows with a number's digits.
    #[test]
    fn every_number_in_a_message_is_shown_by_the_one_formatter() {
        let cases: Vec<(RunProblem, &str)> = vec![
            (RunProblem::RepeatBound { code: "M98", letter: Some('L'), value: 1e15, limit: 100_000 }, "`L1e15`"),
            (RunProblem::RepeatBound { code: "repeat", letter: None, value: 1e15, limit: 100_000 }, "`[1e15]`"),
            (RunProblem::RepeatBound { code: "G81", letter: Some('L'), value: 100_001.0, limit: 100_000 }, "`L100001`"),
            (RunProblem::G10Form { l: 1e300 }, "G10 L1e300 is not"),
            (RunProblem::G10Form { l: 3.0 }, "G10 L3 is not"),
            (RunProblem::BadParameter { index: 1e300, last: 5601, dialect: "LinuxCNC" }, "#1e300 is not"),
            (RunProblem::BadParameter { index: 0.5, last: 5601, dialect: "LinuxCNC" }, "#0.5 is not"),
            (RunProblem::Domain { function: "SQRT", argument: -1e300, hint: "h" }, "SQRT[-1e300]"),
            (RunProblem::ArcRadiusTooSmall { radius: 1e300, half_chord: 2e300 }, "R1e300 is too small"),
            (RunProblem::ArcRadiusTooSmall { radius: 0.1, half_chord: 0.1 + 0.2 }, "0.3 away"),
            (RunProblem::ArcRadiusMismatch { start_radius: 1e300, end_radius: 0.1 + 0.2 }, "end (0.3) differs"),
            (RunProblem::ArcRadiusMismatch { start_radius: 1e300, end_radius: 1.0 }, "its start (1e300)"),
        ];
        for (problem, shown) in cases {
            let text = problem.to_string();
            assert!(text.contains(shown), "{shown:?} not in {text}");
            assert!(!text.contains("00000000000"), "{text}");
            assert!(text.len() < 300, "{} bytes: {text}", text.len());
        }
    }
}
