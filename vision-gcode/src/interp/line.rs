//! One line's execution on a copy of the modal state, in LinuxCNC's order of execution.
//!
//! Nothing here reaches the sink: events are queued in `out` and only flushed by the caller
//! once the whole line succeeded, so a failing line emits nothing and changes nothing.

use super::cycles::CycleCursor;
use super::motion::Polyline;
use crate::config::InterpreterConfig;
use crate::error::{GCode, RunProblem};
use crate::event::{Coolant, Event, OutputChange, OutputWrite, PathMode, SpindleCommand};
use crate::frame::{Placement, SystemRotation};
use crate::geom::{Plane, Xyz, MAX_COORDINATE};
use crate::interp::modal::Modal;
use crate::interp::MAX_REPEATS;
use crate::params::{ParameterTable, G28_POSITION, G30_POSITION};
use crate::words::{whole, Words};
use vision_math::{LengthUnit, Point2};

/// What the caller does after a line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Flow {
    /// Go on with the next line.
    Continue,
    /// M2 / M30 ended the program.
    End(u32),
    /// A `%` delimiter line.
    Percent,
    /// An o-word line: control flow takes over.
    OWord,
    /// M98: call program `O<program>` `repeats` times.
    Call {
        /// The program number (`P`).
        program: u32,
        /// How many times (`L`, default 1).
        repeats: u32,
    },
    /// M99: return from a program called by M98.
    Return,
}

/// An action queued until the line commits.
#[derive(Debug, Clone)]
#[expect(
    clippy::large_enum_variant,
    reason = "Not boxed: the queue is a reused Vec, and a box would allocate per polyline (tests/no_alloc.rs)."
)]
pub(crate) enum Pending {
    Event(Event),
    Polyline(Polyline),
    // Boxed: a cycle is rare and its plan large; every queued event would pay for its size.
    Cycle(Box<CycleCursor>),
}

/// Modal groups of the G-codes this interpreter knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Group {
    Motion,
    Plane,
    Distance,
    ArcDistance,
    FeedMode,
    Units,
    System,
    Path,
    NonModal,
    Rotation,
    Scale,
    CutterComp,
    ToolLength,
    Retract,
    SpindleMode,
}

const GROUP_COUNT: usize = 15;

fn group_of(code: u16) -> Option<Group> {
    Some(match code {
        0 | 10 | 20 | 30 | 800 | 730 | 810 | 820 | 830 | 850 | 890 => Group::Motion,
        40 | 100 | 280 | 281 | 300 | 301 | 520 | 530 | 920 | 921 | 922 => Group::NonModal,
        170 | 180 | 190 => Group::Plane,
        200 | 210 => Group::Units,
        400 => Group::CutterComp,
        430 | 431 | 490 => Group::ToolLength,
        500 | 510 => Group::Scale,
        540 | 550 | 560 | 570 | 580 | 590 => Group::System,
        610 | 611 | 640 => Group::Path,
        680 | 690 => Group::Rotation,
        900 | 910 => Group::Distance,
        901 | 911 => Group::ArcDistance,
        940 | 950 => Group::FeedMode,
        970 => Group::SpindleMode,
        980 | 990 => Group::Retract,
        _ => return None,
    })
}

/// The feature of a G-code this interpreter deliberately leaves out, for a message that names
/// it (rather than "unknown code").
fn unsupported_g(code: u16) -> Option<&'static str> {
    Some(match code {
        50..=53 | 62 => "spline and NURBS interpolation (G5, G5.1, G5.2, G6.2)",
        70 | 80 => "lathe diameter/radius mode (G7/G8)",
        120 | 130 => "circular pocket cycles (G12/G13)",
        150 | 160 => "polar coordinates (G15/G16)",
        330 | 331 => "spindle-synchronised motion (G33/G33.1 threading and rigid tapping)",
        382..=385 => "probing (G38.2-G38.5)",
        410 | 411 | 420 | 421 => "cutter radius compensation (G41/G42)",
        432 => "additional tool length offsets (G43.2)",
        591..=593 => "coordinate systems G59.1-G59.3",
        700 | 710 | 711 | 720 | 721 => "lathe roughing and finishing cycles (G70-G72)",
        740 | 840 => "tapping cycles (G74/G84)",
        760 => "the lathe threading cycle (G76)",
        860 | 870 | 880 => "boring cycles with spindle stop (G86-G88)",
        923 => "restoring G92 offsets (G92.3)",
        930 => "inverse-time feed (G93)",
        960 => "constant surface speed (G96)",
        _ => return None,
    })
}

/// The same for M-codes below the user range.
fn unsupported_m(code: u32) -> Option<&'static str> {
    Some(match code {
        19 => "spindle orientation (M19)",
        48..=53 => "feed and speed override control (M48-M53)",
        60 => "pallet change (M60)",
        61 => "setting the tool without a change (M61)",
        62..=68 => "HAL digital/analog I/O (M62-M68)",
        70..=73 => "saving and restoring the modal state (M70-M73)",
        _ => return None,
    })
}

/// The G-codes of one line, by group.
#[derive(Debug, Clone, Copy, Default)]
struct Groups([Option<u16>; GROUP_COUNT]);

impl Groups {
    fn get(&self, g: Group) -> Option<u16> {
        self.0[g as usize]
    }
}

/// The built-in M-codes of one line.
#[derive(Debug, Clone, Copy, Default)]
struct MCodes {
    stop: Option<u32>,
    spindle: Option<u32>,
    change: bool,
    mist: bool,
    flood: bool,
    coolant_off: bool,
}

/// Whether `code` is a built-in M-code.
pub(crate) fn is_builtin_m(code: u32) -> bool {
    matches!(code, 0..=9 | 30 | 98 | 99)
}

/// The G-codes that take the axis words for themselves (besides motion).
fn axis_consumer(code: u16) -> bool {
    matches!(code, 100 | 280 | 300 | 431 | 520 | 920 | 680 | 510)
}

/// One line at work.
pub(crate) struct LineRun<'a> {
    pub(crate) cfg: &'a InterpreterConfig,
    pub(crate) params: &'a mut ParameterTable,
    /// The working copy of the modal state.
    pub(crate) st: Modal,
    pub(crate) out: &'a mut Vec<Pending>,
    pub(crate) w: Words,
    /// Line events are tagged with.
    pub(crate) line: u32,
    /// Inside G-code run by a handler.
    pub(crate) nested: bool,
}

impl LineRun<'_> {
    /// Runs the line.
    pub(crate) fn run(&mut self) -> Result<Flow, RunProblem> {
        let groups = self.classify_g()?;
        let ms = self.classify_m()?;
        let explicit = self.axis_owner(&groups)?;

        if let Some(code) = groups.get(Group::Units) {
            self.st.units = if code == 200 { LengthUnit::Inch } else { LengthUnit::Millimetre };
        }
        if let Some(code) = groups.get(Group::FeedMode) {
            self.feed_mode(code == 950);
        }
        self.feed_rate()?;
        self.spindle_speed()?;
        self.select_tool()?;
        if ms.change {
            self.change_tool()?;
        }
        if let Some(code) = ms.spindle {
            self.spindle(code)?;
        }
        if ms.mist || ms.flood || ms.coolant_off {
            self.coolant(&ms);
        }
        if groups.get(Group::NonModal) == Some(40) {
            self.dwell()?;
        }
        if let Some(code) = groups.get(Group::Plane) {
            self.st.plane = match code {
                170 => Plane::Xy,
                180 => Plane::Zx,
                _ => Plane::Yz,
            };
        }
        // G40 (the only cutter-compensation state) and G97 (the only spindle mode) change
        // nothing.
        if let Some(code) = groups.get(Group::ToolLength) {
            self.tool_length(code)?;
        }
        if let Some(code) = groups.get(Group::System) {
            let system = u32::from(code / 10 - 53);
            // rs274 reloads a system's parameters only when it becomes active, not when it is
            // selected again (a written #5221 waits for that).
            let rules = self.cfg.rules();
            let reloads = system != self.st.system || !rules.origin_reloads_on_system_change;
            if reloads && rules.carries_current_point {
                // rs274 carries its current point into the new system rather than reading the
                // machine position; the two differ after a rotation change with a G92/G52
                // offset in force, and the next G28 leg or incremental move goes from rs274's.
                let program = self.current_in_system(system);
                self.st.system = system;
                self.st.load_system(self.cfg, self.params);
                self.st.program = program;
            } else if reloads {
                self.st.system = system;
                self.st.load_system(self.cfg, self.params);
                self.st.rederive_program(self.params);
            }
        }
        if let Some(code) = groups.get(Group::Path) {
            self.path_mode(code)?;
        }
        if let Some(code) = groups.get(Group::Distance) {
            self.st.absolute = code == 900;
        }
        if let Some(code) = groups.get(Group::ArcDistance) {
            self.st.arc_absolute = code == 901;
        }
        if let Some(code) = groups.get(Group::Retract) {
            self.st.retract_to_r = code == 990;
        }
        if groups.get(Group::Rotation) == Some(690) {
            self.st.frame.set_rotation(Point2::origin(), 0.0);
            self.st.rederive_program(self.params);
        }
        if groups.get(Group::Scale) == Some(500) {
            self.st.frame.chain.scale = vision_math::Vector2::new(1.0, 1.0);
            self.st.rederive_program(self.params);
        }
        match groups.get(Group::NonModal) {
            Some(100) => self.g10()?,
            Some(280) => self.g28(G28_POSITION, "G28")?,
            Some(281) => self.g28_1(G28_POSITION),
            Some(300) => self.g28(G30_POSITION, "G30")?,
            Some(301) => self.g28_1(G30_POSITION),
            Some(520) => self.g52()?,
            Some(920) => self.g92()?,
            Some(921 | 922) => self.g92_reset(),
            _ => {}
        }
        if groups.get(Group::Rotation) == Some(680) {
            self.g68()?;
        }
        if groups.get(Group::Scale) == Some(510) {
            self.g51()?;
        }
        self.motion(groups.get(Group::Motion), explicit, groups.get(Group::NonModal) == Some(530))?;
        let flow = self.stop(ms.stop)?;
        match self.w.unused() {
            None => Ok(flow),
            Some(letter @ ('A' | 'B' | 'C' | 'U' | 'V' | 'W')) => Err(RunProblem::AxisNotSupported { letter }),
            Some(letter) => Err(RunProblem::UnusedWord { letter }),
        }
    }

    fn classify_g(&self) -> Result<Groups, RunProblem> {
        let mut groups = Groups::default();
        for &code in self.w.g.as_slice() {
            let group = group_of(code).ok_or_else(|| match unsupported_g(code) {
                Some(feature) => RunProblem::Unsupported { code: GCode(code).to_string(), feature },
                None => RunProblem::UnknownGCode { code: GCode(code) },
            })?;
            let rules = self.cfg.rules();
            if matches!(group, Group::Rotation | Group::Scale) && !rules.rotation_and_scale_codes {
                return Err(RunProblem::NotInDialect {
                    code: GCode(code).to_string(),
                    feature: "scaling and rotation",
                    codes: "G50/G51, G68/G69",
                    note: rules.missing_code_note,
                });
            }
            if code == 520 && !rules.local_shift_code {
                return Err(RunProblem::NotInDialect {
                    code: GCode(code).to_string(),
                    feature: "the local shift",
                    codes: "G52",
                    note: rules.missing_code_note,
                });
            }
            let slot = &mut groups.0[group as usize];
            // LinuxCNC lets G80 share a line with a motion code (post-processors write
            // `G80 G0`); the motion code wins.
            if group == Group::Motion && (code == 800 || *slot == Some(800)) {
                if code != 800 || slot.is_none() {
                    *slot = Some(code);
                }
                continue;
            }
            if let Some(first) = *slot {
                return Err(RunProblem::ModalConflict {
                    first: GCode(first).to_string(),
                    second: GCode(code).to_string(),
                });
            }
            *slot = Some(code);
        }
        Ok(groups)
    }

    fn classify_m(&self) -> Result<MCodes, RunProblem> {
        let mut ms = MCodes::default();
        for &code in self.w.m.as_slice() {
            let slot = match code {
                0 | 1 | 2 | 30 | 98 | 99 => &mut ms.stop,
                3..=5 => &mut ms.spindle,
                6 if !ms.change => {
                    ms.change = true;
                    continue;
                }
                6 => return Err(RunProblem::ModalConflict { first: "M6".into(), second: "M6".into() }),
                7..=9 => {
                    let (mist, flood, off) = (ms.mist, ms.flood, ms.coolant_off);
                    let clash = match code {
                        7 => (mist || off).then_some(if mist { 7 } else { 9 }),
                        8 => (flood || off).then_some(if flood { 8 } else { 9 }),
                        _ => (mist || flood || off).then_some(if mist {
                            7
                        } else if flood {
                            8
                        } else {
                            9
                        }),
                    };
                    if let Some(first) = clash {
                        return Err(RunProblem::ModalConflict {
                            first: format!("M{first}"),
                            second: format!("M{code}"),
                        });
                    }
                    match code {
                        7 => ms.mist = true,
                        8 => ms.flood = true,
                        _ => ms.coolant_off = true,
                    }
                    continue;
                }
                _ if unsupported_m(code).is_some() => {
                    let feature = unsupported_m(code).unwrap_or_default();
                    return Err(RunProblem::Unsupported { code: format!("M{code}"), feature });
                }
                _ => {
                    return Err(RunProblem::UnknownMCode {
                        code,
                        user_low: *self.cfg.user_mcodes.start(),
                        user_high: *self.cfg.user_mcodes.end(),
                    })
                }
            };
            if let Some(first) = *slot {
                return Err(RunProblem::ModalConflict { first: format!("M{first}"), second: format!("M{code}") });
            }
            *slot = Some(code);
        }
        Ok(ms)
    }

    /// Whether a code other than motion owns the axis words. At most one code per line may
    /// own them, a motion code included: as in LinuxCNC, `G0 G92 X1` is refused whether or not
    /// the line has axis words, rather than one of the two codes silently doing nothing.
    fn axis_owner(&self, groups: &Groups) -> Result<bool, RunProblem> {
        let mut owner: Option<u16> = None;
        // The motion group comes first, so a motion code is always named first.
        let consumer = |g: Group| groups.get(g).filter(|&c| axis_consumer(c));
        let owners = [
            groups.get(Group::Motion),
            consumer(Group::NonModal),
            consumer(Group::Rotation),
            consumer(Group::Scale),
            consumer(Group::ToolLength),
        ];
        for code in owners.into_iter().flatten() {
            if let Some(first) = owner {
                return Err(RunProblem::AxisWordConflict {
                    first: GCode(first).to_string(),
                    second: GCode(code).to_string(),
                });
            }
            owner = Some(code);
        }
        Ok(owner.is_some_and(axis_consumer))
    }

    /// A length in program units, in machine units.
    pub(super) fn conv(&self, v: f64) -> f64 {
        self.st.units.convert(v, self.cfg.machine_unit)
    }

    /// A length word in machine units.
    pub(super) fn length(&mut self, letter: u8, owner: &'static str) -> Result<Option<f64>, RunProblem> {
        Ok(self.length_as_written(letter, owner)?.map(|(_, machine)| machine))
    }

    /// A length word as written (program units) and in machine units.
    pub(super) fn length_as_written(
        &mut self,
        letter: u8,
        owner: &'static str,
    ) -> Result<Option<(f64, f64)>, RunProblem> {
        match self.w.take(letter, owner)? {
            None => Ok(None),
            Some(v) => Ok(Some((v, in_range(self.conv(v), || format!("{owner}'s {} word", char::from(letter)))?))),
        }
    }

    /// A count word (turns, repeats): a whole number from 1 to [`MAX_REPEATS`], 1 when absent.
    pub(super) fn count(&mut self, letter: u8, code: &'static str, hint: &'static str) -> Result<u32, RunProblem> {
        match self.w.take(letter, code)? {
            None => Ok(1),
            Some(v) if v > f64::from(MAX_REPEATS) => {
                Err(RunProblem::RepeatBound { code, letter: Some(char::from(letter)), value: v, limit: MAX_REPEATS })
            }
            Some(v) => match whole(letter, v)? {
                0 => Err(RunProblem::OutOfRange { code, letter: char::from(letter), value: v, hint }),
                n => Ok(n),
            },
        }
    }

    /// A word the code cannot do without.
    pub(super) fn require(&mut self, letter: u8, code: &'static str, hint: &'static str) -> Result<f64, RunProblem> {
        self.w.take(letter, code)?.ok_or(RunProblem::MissingWord { code, letter: char::from(letter), hint })
    }

    pub(super) fn emit(&mut self, event: Event) {
        self.out.push(Pending::Event(event));
    }

    pub(super) fn placement(&self) -> Placement {
        self.st.placement(self.params)
    }

    fn feed_rate(&mut self) -> Result<(), RunProblem> {
        if let Some(f) = self.w.take(b'F', "F")? {
            if f < 0.0 {
                return Err(RunProblem::Negative { code: "F", letter: 'F', value: f });
            }
            self.st.feed = Some(self.conv(f));
        }
        Ok(())
    }

    /// G94 (per minute) / G95 (per revolution). LinuxCNC sets the feed rate to 0 on either (a
    /// feed move needs a new F); the others do so when the mode changes, since F then means
    /// another thing.
    fn feed_mode(&mut self, per_revolution: bool) {
        if self.cfg.rules().feed_mode_always_zeroes_feed || self.st.per_revolution != per_revolution {
            self.st.feed = Some(0.0);
        }
        self.st.per_revolution = per_revolution;
    }

    fn spindle_speed(&mut self) -> Result<(), RunProblem> {
        if let Some(s) = self.w.take(b'S', "S")? {
            if s < 0.0 {
                return Err(RunProblem::Negative { code: "S", letter: 'S', value: s });
            }
            self.st.speed = Some(s);
        }
        Ok(())
    }

    /// M7 / M8 / M9, in that order (M7 and M8 may share a line).
    fn coolant(&mut self, ms: &MCodes) {
        for (on, coolant) in [(ms.mist, Coolant::Mist), (ms.flood, Coolant::Flood), (ms.coolant_off, Coolant::Off)] {
            if on {
                self.emit(Event::Coolant { line: self.line, coolant });
            }
        }
    }

    /// G43 `H` (a tool's offsets from the table; the loaded tool without `H`), G43.1 `Z` (a
    /// length given here, current units), G49 (none). Under Mach4 they set the length only: the
    /// X/Y offset is the loaded tool's, from M6.
    fn tool_length(&mut self, code: u16) -> Result<(), RunProblem> {
        let offset = match code {
            430 => {
                let tool = match self.w.take(b'H', "G43")? {
                    Some(h) => whole(b'H', h)?,
                    None => self.st.tool,
                };
                if tool == 0 {
                    Xyz::ZERO
                } else {
                    self.cfg.tools.get(tool).ok_or(RunProblem::UnknownTool { tool })?.offset
                }
            }
            431 => {
                let z = self.length(b'Z', "G43.1")?.ok_or(RunProblem::MissingWord {
                    code: "G43.1",
                    letter: 'Z',
                    hint: "the tool length, e.g. G43.1 Z1.5",
                })?;
                Xyz::new(0.0, 0.0, z)
            }
            _ => Xyz::ZERO,
        };
        let rules = self.cfg.rules();
        let offset = rules.applied_tool_offset(offset);
        let old = self.st.tool_offset;
        self.st.tool_offset = rules.tool_length_applies.take(old, offset);
        if rules.carries_current_point {
            // rs274 (`convert_tool_length_offset`) moves its current point by the change,
            // rotated into the system: the same as re-deriving it while the point reads the
            // machine position, and it keeps rs274's point where it does not.
            let p = self.st.program;
            let d = SystemRotation::turn(-self.st.rotation, Point2::new(old.x - offset.x, old.y - offset.y));
            self.st.program = Xyz::new(p.x + d.x, p.y + d.y, p.z + old.z - offset.z);
        } else {
            self.st.rederive_program(self.params);
        }
        Ok(())
    }

    fn select_tool(&mut self) -> Result<(), RunProblem> {
        if let Some(t) = self.w.take(b'T', "T")? {
            let tool = whole(b'T', t)?;
            if self.cfg.tools.get(tool).is_none() {
                return Err(RunProblem::UnknownTool { tool });
            }
            self.st.selected_tool = tool;
        }
        Ok(())
    }

    fn change_tool(&mut self) -> Result<(), RunProblem> {
        let tool = self.st.selected_tool;
        let entry = self.cfg.tools.get(tool).ok_or(RunProblem::UnknownTool { tool })?;
        self.st.tool = tool;
        let rules = self.cfg.rules();
        let offset = rules.applied_tool_offset(entry.offset);
        self.st.tool_offset = rules.tool_change_applies.take(self.st.tool_offset, offset);
        // LinuxCNC too: after a tool change its task re-reads the current point from the
        // machine position (emccanon.cc `GET_EXTERNAL_POSITION`, unrotated, offsets off). The
        // standalone rs274 keeps its last printed point unrotated instead (saicanon.cc), so it
        // differs after a rotation change with G52/G92 in force; the machine is right.
        self.st.rederive_program(self.params);
        self.emit(Event::ToolChange { line: self.line, tool, offset: entry.offset });
        Ok(())
    }

    fn spindle(&mut self, code: u32) -> Result<(), RunProblem> {
        let command = match code {
            3 => SpindleCommand::Clockwise,
            4 => SpindleCommand::CounterClockwise,
            _ => SpindleCommand::Stop,
        };
        let name = command.gcode();
        let dollar = self.w.take(b'$', name)?;
        // Seed 002's explicit `A<device> P<port>` form; elsewhere a lone A is the rotary axis.
        let explicit = self.w.has(b'A') && (self.cfg.rules().lone_a_selects_output || self.w.has(b'P'));
        let change = if explicit {
            let (Some(a), Some(p)) = (self.w.take(b'A', name)?, self.w.take(b'P', name)?) else {
                return Err(RunProblem::OutputForm { code: name });
            };
            if dollar.is_some() {
                return Err(RunProblem::OutputForm { code: name });
            }
            let write = OutputWrite { device: whole(b'A', a)?, port: whole(b'P', p)?, high: command.is_on() };
            OutputChange { line: self.line, command, tool: None, writes: vec![write] }
        } else {
            let tool = match dollar {
                Some(d) => whole(b'$', d)?,
                None => self.st.tool,
            };
            if tool == 0 && dollar.is_none() {
                // No tool to drive outputs of: a plain spindle (CAM programs' `M3 S12000`).
                self.emit(Event::Spindle { line: self.line, command, speed: self.st.speed });
                return Ok(());
            }
            if tool == 0 {
                return Err(RunProblem::NoSpindleTool { code: name });
            }
            let entry = self.cfg.tools.get(tool).ok_or(RunProblem::UnknownTool { tool })?;
            let writes = entry.outputs.map_or_else(Vec::new, |o| o.writes(command).to_vec());
            OutputChange { line: self.line, command, tool: Some(tool), writes }
        };
        self.emit(Event::Output(change));
        Ok(())
    }

    fn dwell(&mut self) -> Result<(), RunProblem> {
        let seconds = self.require(b'P', "G4", "the dwell time in seconds, e.g. G4 P0.5")?;
        if seconds < 0.0 {
            return Err(RunProblem::Negative { code: "G4", letter: 'P', value: seconds });
        }
        self.emit(Event::Dwell { line: self.line, seconds });
        Ok(())
    }

    fn path_mode(&mut self, code: u16) -> Result<(), RunProblem> {
        self.st.path = if code == 610 || code == 611 {
            PathMode::ExactStop
        } else {
            let tolerance = self.w.take(b'P', "G64")?;
            if let Some(p) = tolerance.filter(|p| *p < 0.0) {
                return Err(RunProblem::Negative { code: "G64", letter: 'P', value: p });
            }
            // Q, LinuxCNC's naive-CAM tolerance, merges nearly co-linear feeds in the
            // controller; the path stays within P either way, so it is accepted and not used.
            if let Some(q) = self.w.take(b'Q', "G64")?.filter(|q| *q < 0.0) {
                return Err(RunProblem::Negative { code: "G64", letter: 'Q', value: q });
            }
            PathMode::Blend { tolerance: tolerance.map(|p| self.conv(p)) }
        };
        Ok(())
    }

    fn stop(&mut self, code: Option<u32>) -> Result<Flow, RunProblem> {
        match code {
            None => Ok(Flow::Continue),
            Some(c @ (0 | 1)) => {
                self.emit(Event::Stop { line: self.line, optional: c == 1 });
                Ok(Flow::Continue)
            }
            Some(98 | 99) if self.nested => Err(RunProblem::FlowInHandler),
            Some(98) => {
                let p = self.require(b'P', "M98", "the program number to call, e.g. M98 P1000 for O1000")?;
                let program = whole(b'P', p)?;
                let repeats = self.count(b'L', "M98", "L counts calls and must be at least 1")?;
                Ok(Flow::Call { program, repeats })
            }
            Some(99) => Ok(Flow::Return),
            Some(c) if self.nested => Err(RunProblem::EndInHandler { code: c }),
            Some(c) => {
                self.emit(Event::ProgramEnd { line: self.line, code: c });
                self.st.end_program(self.cfg, self.params);
                Ok(Flow::End(c))
            }
        }
    }
}

/// `value` (machine units) when its magnitude is at most [`MAX_COORDINATE`]; `what` names it in
/// the error.
pub(super) fn in_range(value: f64, what: impl FnOnce() -> String) -> Result<f64, RunProblem> {
    if value.abs() <= MAX_COORDINATE {
        Ok(value)
    } else {
        Err(RunProblem::BeyondRange { what: what(), value })
    }
}
