//! One line's execution on a copy of the modal state, in LinuxCNC's order of execution.
//!
//! Nothing here reaches the sink: events are queued in `out` and only flushed by the caller
//! once the whole line succeeded, so a failing line emits nothing and changes nothing.

use super::motion::Polyline;
use crate::config::InterpreterConfig;
use crate::error::{GCode, RunProblem};
use crate::event::{Event, OutputChange, OutputWrite, PathMode, SpindleCommand};
use crate::frame::Placement;
use crate::geom::Plane;
use crate::interp::modal::Modal;
use crate::params::Params;
use crate::words::{whole, Words};
use vision_math::{LengthUnit, Point2};

/// What the caller does after a line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Flow {
    /// Go on with the next line.
    Continue,
    /// M2 / M30 ended the program.
    End(u32),
}

/// An action queued until the line commits.
#[derive(Debug, Clone)]
pub(crate) enum Pending {
    Event(Event),
    Polyline(Polyline),
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
}

const GROUP_COUNT: usize = 11;

fn group_of(code: u16) -> Option<Group> {
    Some(match code {
        0 | 10 | 20 | 30 => Group::Motion,
        40 | 100 | 280 | 281 | 520 | 920 => Group::NonModal,
        170 | 180 | 190 => Group::Plane,
        200 | 210 => Group::Units,
        500 | 510 => Group::Scale,
        540 | 550 | 560 | 570 | 580 | 590 => Group::System,
        610 | 640 => Group::Path,
        680 | 690 => Group::Rotation,
        900 | 910 => Group::Distance,
        901 | 911 => Group::ArcDistance,
        940 => Group::FeedMode,
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
}

/// Whether `code` is a built-in M-code.
pub(crate) fn is_builtin_m(code: u32) -> bool {
    matches!(code, 0..=6 | 30)
}

/// The G-codes that take the axis words for themselves (besides motion).
fn axis_consumer(code: u16) -> bool {
    matches!(code, 100 | 280 | 520 | 920 | 680 | 510)
}

/// One line at work.
pub(crate) struct LineRun<'a> {
    pub(crate) cfg: &'a InterpreterConfig,
    pub(crate) params: &'a mut Params,
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
        self.feed_rate()?;
        self.select_tool()?;
        if ms.change {
            self.change_tool()?;
        }
        if let Some(code) = ms.spindle {
            self.spindle(code)?;
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
        if let Some(code) = groups.get(Group::System) {
            self.st.system = u32::from(code / 10 - 53);
            self.st.rederive_program(self.params);
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
        // G94 (group FeedMode) is the only feed mode: nothing to do.
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
            Some(280) => self.g28()?,
            Some(281) => self.g28_1(),
            Some(520) => self.g52()?,
            Some(920) => self.g92()?,
            _ => {}
        }
        if groups.get(Group::Rotation) == Some(680) {
            self.g68()?;
        }
        if groups.get(Group::Scale) == Some(510) {
            self.g51()?;
        }
        self.motion(groups.get(Group::Motion), explicit)?;
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
            let group = group_of(code).ok_or(RunProblem::UnknownGCode { code: GCode(code) })?;
            let slot = &mut groups.0[group as usize];
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
                0 | 1 | 2 | 30 => &mut ms.stop,
                3..=5 => &mut ms.spindle,
                6 if !ms.change => {
                    ms.change = true;
                    continue;
                }
                6 => return Err(RunProblem::ModalConflict { first: "M6".into(), second: "M6".into() }),
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
        let owners =
            groups.0.iter().flatten().copied().filter(|&c| axis_consumer(c) || group_of(c) == Some(Group::Motion));
        for code in owners {
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
        Ok(self.w.take(letter, owner)?.map(|v| self.conv(v)))
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
        self.st.tool_offset = entry.offset;
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
        let change = if self.w.has(b'A') {
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
        self.st.path = if code == 610 {
            PathMode::ExactStop
        } else {
            let tolerance = self.w.take(b'P', "G64")?;
            if let Some(p) = tolerance.filter(|p| *p < 0.0) {
                return Err(RunProblem::Negative { code: "G64", letter: 'P', value: p });
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
            Some(c) if self.nested => Err(RunProblem::EndInHandler { code: c }),
            Some(c) => {
                self.emit(Event::ProgramEnd { line: self.line, code: c });
                self.st.end_program(self.cfg, self.params);
                Ok(Flow::End(c))
            }
        }
    }
}
