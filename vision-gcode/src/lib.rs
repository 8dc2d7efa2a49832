//! A G-code interpreter for the seed-002 dialect (MachineMotion path following) and the Mach
//! alignment modals `G51` / `G68` / `G52` — the machine side of SPEC §6. It proves that the
//! G-code M282 emits moves the tool onto the real part, and lets a whole program run against a
//! simulated machine. It knows nothing of vision: user M-codes (M280–M284 among them) go to an
//! [`MCodeHandler`].
//!
//! * A hand-written line parser (words, `#` parameters, `[expressions]`, comments), private.
//! * [`Interpreter`]: modal state, the frame chain, arcs, tools, outputs; streams [`Event`]s in
//!   machine coordinates to an [`EventSink`], each tagged with its source line.
//! * [`MCodeHandler`] / [`Context`]: the extension point; a handler reads and writes parameters,
//!   reads positions, writes tool offsets and runs G-code synchronously.
//! * [`PositionWatch`] ([`Interpreter::watch_position`]): the machine position, published by
//!   the interpreter for readers that cannot borrow it (a simulated camera).
//!
//! ```
//! use vision_gcode::{Event, Interpreter, InterpreterConfig, Xyz};
//!
//! // An inch machine; M282's alignment: shift, rotate 90° about (3, 2), no scale.
//! let mut interp = Interpreter::new(InterpreterConfig::default());
//! let program = "G90 G20\nG52 X0.1 Y0.05\nG68 X3 Y2 R90\nG0 X6 Y4";
//! let mut events = Vec::new();
//! interp.run(program, None, &mut events)?;
//! // (6, 4) − (3, 2) = (3, 2) → rotated (−2, 3) → + (3, 2) = (1, 5) → + (0.1, 0.05).
//! let m = interp.machine_position();
//! assert!((m - Xyz::new(1.1, 5.05, 0.0)).norm() < 1e-12);
//! assert!(matches!(events.last(), Some(Event::Linear(mv)) if mv.line == 4 && mv.end == m));
//! # Ok::<(), vision_gcode::GcodeError>(())
//! ```
//!
//! # The frame chain
//!
//! A programmed point `p` (program frame, converted to machine units) reaches the machine as
//!
//! ```text
//! w.xy = AlignmentChain::apply(p.xy)          G51 scale → G68 rotate about its centre → + G52
//! w.z  = p.z + G52.z
//! m.x  = w.x + ((work.x + g92.x) − tool.x)    work = G54…G59 origin, tool = tool-table X/Y offset
//! m.y  = w.y + ((work.y + g92.y) − tool.y)
//! m.z  = w.z + ((work.z + g92.z) + tool.length)
//! ```
//!
//! evaluated in exactly this order; `m` is the machine (spindle) position. The X/Y part of
//! program → work is bit-identical to [`vision_math::AlignmentChain::apply`] with the chain in
//! machine units. `G91` increments are increments of `p`.
//!
//! Under LinuxCNC (which has no G68/G51, and keeps G52 in the G92 offset) a coordinate system
//! may be rotated about its origin by `G10 L2 P… R…` (degrees, counter-clockwise, stored per
//! system at #5230 + 20·(n − 1)); then, as LinuxCNC's canon (`rotate_and_offset_pos`) does,
//!
//! ```text
//! m.xy = (work.xy − tool.xy) + R(rotation)·(p.xy + g92.xy)     G92/G52 before the rotation
//! m.z  = p.z + ((work.z + g92.z) + tool.length)
//! ```
//!
//! One function maps every point (moves, arc ends and centres, cycles), so the simulator and the
//! planner, which take the interpreter's machine-coordinate events, see the same map. G53
//! ignores the rotation; a G17 arc stays an exact arc (its centre rotated), a G18/G19 arc in a
//! rotated system leaves the machine planes and becomes feed segments within
//! [`InterpreterConfig::chord_tolerance`]. Mach4 and seed 002 rotate with G68 only (`G10 … R`
//! other than `R0` is refused there), so the two rotations never meet.
//!
//! # Decisions where the spec is open
//!
//! * **Units.** Machine coordinates, events, offset parameters and the tool table are in the
//!   configured machine unit (default inch); G20/G21 convert the words. A line's G20/G21 applies
//!   to every word of that line, `F` included. Start-up units default to the machine unit.
//! * **A line is atomic.** Words and assignments are evaluated first (all reads before any
//!   write, as in LinuxCNC), then the assignments are written, then the line executes on a copy
//!   of the modal state with an undo log on the parameters; events are queued and reach the sink
//!   only when the whole line succeeded. A failing line changes nothing and emits nothing.
//!   Exception: a user M-code line writes its assignments before the call, and whatever G-code
//!   the handler ran stays done (each of its lines atomic in turn).
//! * **Order within a line:** G20/G21, F, S, T, M6, M3/M4/M5, M7/M8/M9, G4, G17–G19,
//!   G43/G43.1/G49, G54–G59, G61/G64, G90/G91, G90.1/G91.1, G98/G99, G69/G50,
//!   G10/G28/G30/G52/G92, G68, G51, motion (G53 with it), M0/M1/M2/M30. Only one code per line
//!   may own the axis words (motion, G10, G28, G30, G43.1, G52, G92, G68, G51); as in LinuxCNC,
//!   a motion code beside one of the others is refused even on a line without axis words
//!   (`G0 G92 X1` is an error, not a silent G92). `G80` may share a line with a motion code,
//!   which wins (post-processors write `G80 G0`).
//! * **LinuxCNC's G-code** (checked move by move against its `rs274`, see
//!   `tools/linuxcnc-oracle`): G40, G49, G80, G94, G97 and G61.1 are accepted; a motion code
//!   alone moves to the current point (`G0`), or makes a full circle from centre words (`G2 I1`);
//!   G28/G30 always make their first leg; G53 moves (with G0/G1, under G90) in machine
//!   coordinates; the canned cycles G73, G81, G82, G83, G85, G89 (XY plane, G98/G99, R, Q, P, L,
//!   G91 repeats) expand into straight moves and dwells in exact-stop mode; `%` on the first
//!   non-blank line makes the next `%` line end the program; `/` at the start of a line is
//!   block delete (skipped only with [`InterpreterConfig::block_delete`]). Polar words (`@`
//!   distance, `^` angle in degrees, G17 only, LinuxCNC only) place moves and cycle holes as in
//!   rs274, absolute from the program origin or, under G91, as changes of the current point's.
//!   G95 feeds per spindle revolution: a feed move goes at F × S (a move with no S is refused);
//!   a change of feed mode needs a new F (under LinuxCNC any G94/G95 does). Features left out
//!   (cutter compensation, lathe modes and cycles, threading, NURBS, probing, inverse-time feed,
//!   HAL M-codes, …) are refused with a message naming them ([`RunProblem::Unsupported`]).
//! * **o-words** (LinuxCNC): `sub`/`endsub`/`call`/`return` (arguments in #1–#30, local to the
//!   call and restored after it; `endsub [v]`/`return [v]` set `#<_value>`), `if`/`elseif`/
//!   `else`/`endif`, `while`/`endwhile`, `do`/`while`, `repeat`/`endrepeat`, `break`/`continue`
//!   (in `while` and `do` loops, as LinuxCNC), and `o<name> call` of a file `name.ngc` on
//!   [`InterpreterConfig::subroutine_path`]. A program streams line by line until its first
//!   o-word line; from there its text is indexed once and run with a program counter. Loops stop
//!   with an error after [`InterpreterConfig::max_loop_iterations`]; calls nest 10 deep.
//! * **Fanuc/Mach subprograms:** `M98 P<n> [L<count>]` calls the program that starts at the
//!   line `O<n>` of the same text (leading zeros ignored), `M99` returns (in the main program it
//!   is an error, not Fanuc's endless restart). They share #1–#30 with their caller.
//! * **Named parameters** `#<name>` (case and blanks ignored): local to the call that wrote
//!   them, global when the name starts with `_`; reading one never written is an error. Under
//!   LinuxCNC a few of its predefined read-only names are provided: `_task` (0, as in any
//!   preview interpreter), `_vmajor`/`_vminor` (2.9, 0), `_x`/`_y`/`_z`, `_imperial`/`_metric`,
//!   `_absolute`/`_incremental`, `_current_tool`/`_selected_tool`, `_feed`, `_rpm`.
//! * **Frame changes never move the machine** (G54–G59, G10 on the active system, G92, G52,
//!   G68/G69, G51/G50, M6, a tool-offset or offset-parameter write): the program position is
//!   re-derived from the machine position, and the next move goes to the new frame.
//! * **Tools.** A tool's X/Y offset is where its point lies relative to the spindle (commanding
//!   P puts the tool at P, the spindle at P − offset); its Z value is a length, positive below
//!   the spindle (commanding Z puts the tip at Z, the spindle at Z + length). Offsets apply from
//!   M6 on (seed 002 has no G43); G43 `H` replaces them with a table entry's (the loaded tool's
//!   without `H`), G43.1 `Z` with a length given in the program, G49 with none. The default
//!   table holds tools 1–254 with zero offsets.
//! * **Dialects** ([`InterpreterConfig::dialect`], default seed 002's MachineMotion) where the
//!   controllers differ: G92 on some axes (seed 002 zeroes the others, Mach4 and LinuxCNC keep
//!   them), tool offsets from M6 (seed 002) or from G43 only (Mach4, LinuxCNC), nested comments
//!   (seed 002) or comments ending at the first `)`, G68/G51 (refused under LinuxCNC).
//! * **G92** with an axis word missing zeroes that axis's G92 offset (seed 002); G52, G51 and
//!   G10 L2 leave unmentioned axes unchanged. G92 and G10 L20 make the current point read exactly
//!   the given values. Under LinuxCNC, G52 and G92 share the offset at #5211 (G52 sets it, G92
//!   computes it), both from the current point as rs274 does, and a G10 that changes the active
//!   system's rotation leaves the current point where rs274 puts it (rotated by the old angle,
//!   moved by the change of origin, rotated back, the G52/G92 offset left out): with a G52/G92
//!   offset in force that is not the point the machine position reads, and the next incremental
//!   or partial move goes where LinuxCNC sends it.
//! * **Ranges.** Axis words, moves' machine positions (arc centres included), offsets and the
//!   offset parameters are refused beyond ±[`MAX_COORDINATE`] machine units, the bound the path
//!   planner uses too; `G68 R` is at most ±360°, a `G51` factor's magnitude 0.001 to 1000.
//! * **G68** needs `R` (degrees, counter-clockwise); an omitted `X`/`Y` centre is the current
//!   point (in the scaled frame), so nothing jumps. **G51** takes `X`/`Y` factors only, refuses
//!   zero, and allows negative factors (a mirror, which reverses arc directions).
//! * **Arcs** stay exact [`ArcMove`]s under any similarity in G17 (rotation, uniform or mirrored
//!   scale); G18/G19 arcs only under a pure translation. Otherwise (non-uniform G51, or G68/G51
//!   with a G18/G19 arc) an arc becomes feed segments whose distance from the true curve is at
//!   most [`InterpreterConfig::chord_tolerance`]; their interior vertices are not programmed
//!   points, so those segments blend (G64 with the chord tolerance) and only the last one carries
//!   the line's G61/G64. Radius checks follow LinuxCNC
//!   ([`CENTRE_TOLERANCE_INCH`], [`RADIUS_TOLERANCE_INCH`]): start and end radius may differ by
//!   more than the centre tolerance only within 0.1 % of the radius, never by more than 100
//!   times it; a radius below the radius tolerance is "too small". Under G90.1 both centre
//!   words are required (seed 002). `P` on G2/G3 counts full turns (with `R` too).
//! * **G28/G30** follow LinuxCNC: a rapid to the intermediate point the axis words name (the
//!   current point without them), then those axes (all, without words) go to the G28.1/G30.1
//!   position (#5161–#5163 / #5181–#5183, machine coordinates).
//! * **Parameters** `#1`–`#9999`, under LinuxCNC `#1`–`#5601` as in rs274 (0 by default; a
//!   number outside the dialect's range is refused, naming it). The offsets live in LinuxCNC's
//!   addresses in machine units (G28 #5161, G92 #5211, G54… #5221 + 20·(n − 1), and under
//!   LinuxCNC the system's rotation at #5230 + 20·(n − 1), degrees); #5220, #5400–#5409 and
//!   #5420–#5428 report the state in current units and are read-only.
//! * **When a written origin takes effect** (`#5221 = …` in the program): in Mach4 and seed 002
//!   from that line on; under LinuxCNC, as rs274 2.9 (pre-release and 2.9.0–2.9.10 alike:
//!   `convert_coordinate_system` returns early for the active system), only when the system
//!   becomes active from another one (`G55` then `G54`; `G54` under G54 does nothing) or a G10
//!   sets it (which loads all its parameters, earlier writes included). A write by a host or a
//!   handler ([`Interpreter::set_param`], [`Context::set_pound`]) stands for the control's
//!   offset table and takes effect at once in every dialect; a written G92 offset (#5211…)
//!   does too.
//! * **Program end.** Under LinuxCNC a text that ends without M2/M30 or a closing `%` is an
//!   error ([`RunProblem::NoProgramEnd`]), as in rs274; the other dialects complete it.
//!   M2/M30 emit [`Event::ProgramEnd`], stop the run, and reset G54, G17, G90,
//!   G91.1, the path mode, the motion mode, G51/G68/G52 and G92; outputs are the host's to
//!   switch off. At start no motion mode is active: axis words before G0–G3 are an error.
//! * **Feed.** A feed move before any `F` is an error unless
//!   [`InterpreterConfig::default_feed`] is set (the seed-002 snippets need one); so is one at
//!   `F0`, as in LinuxCNC.
//! * **Outputs.** M3/M4 first release the tool's other output, then drive the requested one; M5
//!   releases both. A tool with no outputs wired still yields an [`Event::Output`] (no writes).
//!   The explicit form needs both `A` and `P`. With no tool loaded and no `$n` (a CAM program's
//!   `M3 S12000`) M3/M4/M5 yield an [`Event::Spindle`] with the last `S`; M7/M8/M9 yield
//!   [`Event::Coolant`]. Nothing is wired to either here.
//! * **User M-codes** (default M100–M999; built-ins win) must be alone on their line with their
//!   argument words (any letter but G, M, N). G-code a handler runs or returns is tagged with the
//!   M-code's line; its own errors are numbered within that text and wrapped
//!   ([`GcodeError::HandlerGcode`]); user M-codes and M2/M30 inside it are errors.
//! * **Syntax** follows LinuxCNC: blanks are ignored everywhere outside comments (`G1 2` is
//!   `G12`), `N` must come first, a letter may not repeat (G and M excepted). Unlike LinuxCNC,
//!   parentheses nest inside comments, because the manual's own programs write
//!   `( ... (lower-left -2.5,-4.0) )`. Any NaN or infinity in an expression is an error, never a
//!   coordinate. Expressions nest at most 64 deep and one line's hold at most 10 000 operands
//!   ([`SyntaxProblem::TooLong`]), so a runaway generated line costs little memory.
//! * Seed 002's G19 snippet as printed starts 353.6 mm from its arc centre and ends 250 mm from
//!   it; it is refused like LinuxCNC refuses it (the test runs it with the start the other
//!   plane snippets use).

mod arc;
pub mod config;
pub mod error;
pub mod event;
mod expr;
mod frame;
pub mod geom;
pub mod handler;
mod interp;
mod letters;
pub mod params;
/// The line parser is crate-private; the `bench-internals` feature exposes it (unstable, not
/// part of the API) for the parse-only benchmark.
#[cfg(feature = "bench-internals")]
#[doc(hidden)]
pub mod parse;
#[cfg(not(feature = "bench-internals"))]
mod parse;
pub mod tools;
mod watch;
mod whole;
mod words;

pub use arc::{CENTRE_TOLERANCE_INCH, CENTRE_TOLERANCE_MM, RADIUS_TOLERANCE_INCH, RADIUS_TOLERANCE_MM};
pub use config::{Dialect, InterpreterConfig};
pub use error::{GCode, GcodeError, RunProblem, SyntaxProblem};
pub use event::{
    ArcMove, Coolant, Event, EventSink, LinearMove, OutputChange, OutputWrite, PathMode, Rate, SpindleCommand, UserCall,
};
pub use geom::{ArcDirection, Plane, Xyz, MAX_COORDINATE};
pub use handler::{Context, HandlerError, MCodeHandler, UserMCode};
pub use interp::{needs_program, Interpreter, MotionMode, Piece, ProgramStream, RunOutcome};
pub use tools::{DigitalOutput, Tool, ToolOutputs, ToolTable};
pub use watch::PositionWatch;
