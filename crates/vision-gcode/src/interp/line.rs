//! One line's execution on a copy of the modal state, in LinuxCNC's order of execution.
//!
//! Nothing here reaches the sink: events are queued in `out` and only flushed by the caller
//! once the whole line succeeded, so a failing line emits nothing and changes nothing.

use crate::arc::{
    Arc, Tolerance, CENTRE_TOLERANCE_INCH, CENTRE_TOLERANCE_MM, RADIUS_TOLERANCE_INCH, RADIUS_TOLERANCE_MM,
};
use crate::config::InterpreterConfig;
use crate::error::{GCode, RunProblem};
use crate::event::{ArcMove, Event, EventSink, LinearMove, OutputChange, OutputWrite, PathMode, Rate, SpindleCommand};
use crate::frame::Placement;
use crate::geom::{ArcDirection, Plane, Xyz, AXIS_LETTERS, CENTRE_LETTERS};
use crate::interp::modal::{work_offset_base, Modal, MotionMode};
use crate::params::{Params, G28_POSITION, G92_OFFSET};
use crate::tools::ToolTable;
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

/// An arc that becomes line segments when flushed (it may be long: it is expanded lazily).
#[derive(Debug, Clone)]
pub(crate) struct Polyline {
    line: u32,
    arc: Arc,
    placement: Placement,
    segments: u64,
    start: Xyz,
    feed: f64,
    /// The line's path mode, for the last segment.
    path: PathMode,
    /// The chord tolerance: interior vertices are not programmed points, so they blend within it.
    chord_tolerance: f64,
}

impl Polyline {
    /// Emits the segments; the last one ends exactly at the arc's mapped end point and carries
    /// the line's path mode, the others blend (G64 P chord tolerance) even under G61.
    pub(crate) fn emit(&self, sink: &mut dyn EventSink) {
        let mut from = self.start;
        let interior = PathMode::Blend { tolerance: Some(self.chord_tolerance) };
        for k in 1..=self.segments {
            // k ≤ segments ≤ the configured limit (10⁷ by default): exact in f64.
            #[allow(clippy::cast_precision_loss)]
            let t = k as f64 / self.segments as f64;
            let to = self.placement.machine_of(self.arc.point_at(t));
            let path = if k == self.segments { self.path } else { interior };
            sink.event(&Event::Linear(LinearMove {
                line: self.line,
                start: from,
                end: to,
                rate: Rate::Feed(self.feed),
                path,
            }));
            from = to;
        }
    }
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

fn motion_name(mode: MotionMode) -> &'static str {
    match mode {
        MotionMode::Rapid => "G0",
        MotionMode::Linear => "G1",
        MotionMode::Arc(ArcDirection::Clockwise) => "G2",
        MotionMode::Arc(ArcDirection::CounterClockwise) => "G3",
    }
}

/// One line at work.
pub(crate) struct LineRun<'a> {
    pub(crate) cfg: &'a InterpreterConfig,
    pub(crate) tools: &'a ToolTable,
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

    /// The one code (other than motion) that owns the axis words, if any.
    fn axis_owner(&self, groups: &Groups) -> Result<bool, RunProblem> {
        let mut owner: Option<u16> = None;
        for code in groups.0.iter().flatten().copied().filter(|&c| axis_consumer(c)) {
            if let Some(first) = owner {
                return Err(RunProblem::AxisWordConflict {
                    first: GCode(first).to_string(),
                    second: GCode(code).to_string(),
                });
            }
            owner = Some(code);
        }
        Ok(owner.is_some())
    }

    /// A length in program units, in machine units.
    fn conv(&self, v: f64) -> f64 {
        self.st.machine_len(v, self.cfg.machine_unit)
    }

    /// A length word in machine units.
    fn length(&mut self, letter: u8, owner: &'static str) -> Result<Option<f64>, RunProblem> {
        Ok(self.w.take(letter, owner)?.map(|v| self.conv(v)))
    }

    /// A word the code cannot do without.
    fn require(&mut self, letter: u8, code: &'static str, hint: &'static str) -> Result<f64, RunProblem> {
        self.w.take(letter, code)?.ok_or(RunProblem::MissingWord { code, letter: char::from(letter), hint })
    }

    fn emit(&mut self, event: Event) {
        self.out.push(Pending::Event(event));
    }

    fn placement(&self) -> Placement {
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
            if self.tools.get(tool).is_none() {
                return Err(RunProblem::UnknownTool { tool });
            }
            self.st.selected_tool = tool;
        }
        Ok(())
    }

    fn change_tool(&mut self) -> Result<(), RunProblem> {
        let tool = self.st.selected_tool;
        let entry = self.tools.get(tool).ok_or(RunProblem::UnknownTool { tool })?;
        self.st.tool = tool;
        self.st.tool_offset = entry.offset;
        self.st.rederive_program(self.params);
        self.emit(Event::ToolChange { line: self.line, tool, offset: entry.offset });
        Ok(())
    }

    fn spindle(&mut self, code: u32) -> Result<(), RunProblem> {
        let (name, command) = match code {
            3 => ("M3", SpindleCommand::Clockwise),
            4 => ("M4", SpindleCommand::CounterClockwise),
            _ => ("M5", SpindleCommand::Stop),
        };
        let dollar = self.w.take(b'$', name)?;
        let change = if self.w.has(b'A') {
            let (Some(a), Some(p)) = (self.w.take(b'A', name)?, self.w.take(b'P', name)?) else {
                return Err(RunProblem::OutputForm { code: name });
            };
            if dollar.is_some() {
                return Err(RunProblem::OutputForm { code: name });
            }
            let write = OutputWrite { device: whole(b'A', a)?, port: whole(b'P', p)?, high: code != 5 };
            OutputChange { line: self.line, command, tool: None, writes: vec![write] }
        } else {
            let tool = match dollar {
                Some(d) => whole(b'$', d)?,
                None => self.st.tool,
            };
            if tool == 0 {
                return Err(RunProblem::NoSpindleTool { code: name });
            }
            let entry = self.tools.get(tool).ok_or(RunProblem::UnknownTool { tool })?;
            let writes = entry.outputs.map_or_else(Vec::new, |o| {
                let on = |d: crate::tools::DigitalOutput| OutputWrite {
                    device: d.device,
                    port: d.port,
                    high: d.active_high,
                };
                let off = |d: crate::tools::DigitalOutput| OutputWrite {
                    device: d.device,
                    port: d.port,
                    high: !d.active_high,
                };
                // The opposite direction is released before the requested one is driven.
                match command {
                    SpindleCommand::Clockwise => vec![off(o.counter_clockwise), on(o.clockwise)],
                    SpindleCommand::CounterClockwise => vec![off(o.clockwise), on(o.counter_clockwise)],
                    SpindleCommand::Stop => vec![off(o.clockwise), off(o.counter_clockwise)],
                }
            });
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

    /// The program point the axis words name (absolute or incremental), machine units.
    fn target(&mut self, owner: &'static str) -> Result<Xyz, RunProblem> {
        let mut t = self.st.program;
        for (axis, &letter) in AXIS_LETTERS.iter().enumerate() {
            if let Some(v) = self.length(letter, owner)? {
                t.set_axis(axis, if self.st.absolute { v } else { t.axis(axis) + v });
            }
        }
        Ok(t)
    }

    /// Which axis words are on the line (without claiming them); at least one is required.
    fn given_axes(&self, owner: &'static str) -> Result<[bool; 3], RunProblem> {
        let given = AXIS_LETTERS.map(|l| self.w.has(l));
        if given.iter().any(|g| *g) {
            Ok(given)
        } else {
            Err(RunProblem::NoAxisWords { code: owner })
        }
    }

    /// The given axis words (absolute, converted to machine units), with the current program
    /// coordinate for the others; and which were given.
    fn absolute_point(&mut self, owner: &'static str) -> Result<(Xyz, [bool; 3]), RunProblem> {
        let given = self.given_axes(owner)?;
        let mut p = self.st.program;
        for (axis, &letter) in AXIS_LETTERS.iter().enumerate() {
            if let Some(v) = self.length(letter, owner)? {
                p.set_axis(axis, v);
            }
        }
        Ok((p, given))
    }

    fn g10(&mut self) -> Result<(), RunProblem> {
        let l = self.require(
            b'L',
            "G10",
            "L2 sets a coordinate system's origin, L20 makes the current point read the given values",
        )?;
        if l != 2.0 && l != 20.0 {
            return Err(RunProblem::G10Form { l });
        }
        let p = self.require(b'P', "G10", "the coordinate system, P1 (G54) to P6 (G59), or P0 for the active one")?;
        let mut system = whole(b'P', p)?;
        if system > 6 {
            return Err(RunProblem::OutOfRange {
                code: "G10",
                letter: 'P',
                value: p,
                hint: "P0 (active system) to P6 (G59); G59.1-G59.3 are not supported",
            });
        }
        if system == 0 {
            system = self.st.system;
        }
        let base = work_offset_base(system);
        let (v, given) = self.absolute_point("G10")?;
        if l == 2.0 {
            for axis in (0..3).filter(|&a| given[a]) {
                self.params.set(base + axis as u32, v.axis(axis));
            }
        } else {
            // The origin that makes the current machine point read `v`.
            let pl = self.placement();
            let w = pl.work_of(v);
            let g92 = self.params.triple(G92_OFFSET);
            let tool = self.st.tool_offset;
            let m = self.st.machine;
            let origin =
                [((m.x - w.x) - g92[0]) + tool.x, ((m.y - w.y) - g92[1]) + tool.y, ((m.z - w.z) - g92[2]) - tool.z];
            for axis in (0..3).filter(|&a| given[a]) {
                self.params.set(base + axis as u32, origin[axis]);
            }
        }
        if system == self.st.system {
            self.st.rederive_program(self.params);
            if l == 20.0 {
                self.keep_given(v, given);
            }
        }
        Ok(())
    }

    /// After an offset was computed to make the current point read `v` on the given axes, take
    /// those coordinates exactly (the re-derived ones differ by rounding only).
    fn keep_given(&mut self, v: Xyz, given: [bool; 3]) {
        for axis in (0..3).filter(|&a| given[a]) {
            self.st.program.set_axis(axis, v.axis(axis));
        }
    }

    fn g92(&mut self) -> Result<(), RunProblem> {
        let given = self.given_axes("G92")?;
        // Seed 002: an axis without a word gets a zero G92 offset. Do that first, so the given
        // axes are computed in the frame that will hold.
        for axis in (0..3).filter(|&a| !given[a]) {
            self.params.set(G92_OFFSET + axis as u32, 0.0);
        }
        self.st.rederive_program(self.params);
        let (v, given) = self.absolute_point("G92")?;
        let pl = self.placement();
        let w = pl.work_of(v);
        let work = self.params.triple(work_offset_base(self.st.system));
        let tool = self.st.tool_offset;
        let m = self.st.machine;
        let g92 =
            [((m.x - w.x) - work[0]) + tool.x, ((m.y - w.y) - work[1]) + tool.y, ((m.z - w.z) - work[2]) - tool.z];
        for axis in (0..3).filter(|&a| given[a]) {
            self.params.set(G92_OFFSET + axis as u32, g92[axis]);
        }
        self.st.rederive_program(self.params);
        self.keep_given(v, given);
        Ok(())
    }

    fn g52(&mut self) -> Result<(), RunProblem> {
        let (v, given) = self.absolute_point("G52")?;
        if given[0] {
            self.st.frame.chain.shift.x = v.x;
        }
        if given[1] {
            self.st.frame.chain.shift.y = v.y;
        }
        if given[2] {
            self.st.frame.local_z = v.z;
        }
        self.st.rederive_program(self.params);
        Ok(())
    }

    fn g28(&mut self) -> Result<(), RunProblem> {
        let given = AXIS_LETTERS.map(|l| self.w.has(l));
        let pl = self.placement();
        if given.iter().any(|g| *g) {
            let via = self.target("G28")?;
            let m = self.checked(pl.machine_of(via))?;
            self.rapid_to_machine(m);
        }
        let home = self.params.triple(G28_POSITION);
        let mut m = self.st.machine;
        let all = !given.iter().any(|g| *g);
        for axis in (0..3).filter(|&a| all || given[a]) {
            m.set_axis(axis, home[axis]);
        }
        self.rapid_to_machine(m);
        self.st.rederive_program(self.params);
        Ok(())
    }

    fn rapid_to_machine(&mut self, end: Xyz) {
        let start = self.st.machine;
        self.emit(Event::Linear(LinearMove { line: self.line, start, end, rate: Rate::Rapid, path: self.st.path }));
        self.st.machine = end;
    }

    fn g28_1(&mut self) {
        let m = self.st.machine;
        for axis in 0..3 {
            self.params.set(G28_POSITION + axis as u32, m.axis(axis));
        }
    }

    fn g68(&mut self) -> Result<(), RunProblem> {
        let degrees = self.require(b'R', "G68", "the rotation in degrees, counter-clockwise, e.g. G68 X0 Y0 R30")?;
        // An omitted centre coordinate is the current point's (in the scaled frame), so the
        // machine does not jump.
        let scale = self.st.frame.chain.scale;
        let p = self.st.program;
        let cx = self.length(b'X', "G68")?.unwrap_or(scale.x * p.x);
        let cy = self.length(b'Y', "G68")?.unwrap_or(scale.y * p.y);
        self.st.frame.set_rotation(Point2::new(cx, cy), degrees);
        self.st.rederive_program(self.params);
        Ok(())
    }

    fn g51(&mut self) -> Result<(), RunProblem> {
        if self.w.has(b'Z') {
            return Err(RunProblem::ScaleAxis { letter: 'Z' });
        }
        let sx = self.w.take(b'X', "G51")?;
        let sy = self.w.take(b'Y', "G51")?;
        if sx.is_none() && sy.is_none() {
            return Err(RunProblem::NoAxisWords { code: "G51" });
        }
        for (letter, factor) in [('X', sx), ('Y', sy)] {
            if factor == Some(0.0) {
                return Err(RunProblem::ZeroScale { letter });
            }
        }
        let scale = &mut self.st.frame.chain.scale;
        scale.x = sx.unwrap_or(scale.x);
        scale.y = sy.unwrap_or(scale.y);
        self.st.rederive_program(self.params);
        Ok(())
    }

    fn checked(&self, m: Xyz) -> Result<Xyz, RunProblem> {
        if m.is_finite() {
            Ok(m)
        } else {
            Err(RunProblem::NonFinitePosition)
        }
    }

    fn motion(&mut self, code: Option<u16>, axes_taken: bool) -> Result<(), RunProblem> {
        if let Some(code) = code {
            self.st.motion = Some(match code {
                0 => MotionMode::Rapid,
                10 => MotionMode::Linear,
                20 => MotionMode::Arc(ArcDirection::Clockwise),
                _ => MotionMode::Arc(ArcDirection::CounterClockwise),
            });
        }
        let has_axes = self.w.has(b'X') || self.w.has(b'Y') || self.w.has(b'Z');
        if axes_taken || !has_axes {
            if let (false, Some(MotionMode::Arc(dir))) = (axes_taken, self.st.motion) {
                if [b'I', b'J', b'K', b'R'].iter().any(|&l| self.w.has(l)) {
                    return Err(RunProblem::ArcNoEnd { code: motion_name(MotionMode::Arc(dir)) });
                }
            }
            return Ok(());
        }
        let mode = self.st.motion.ok_or(RunProblem::NoMotionMode)?;
        let name = motion_name(mode);
        let target = self.target(name)?;
        match mode {
            MotionMode::Rapid => self.linear(target, Rate::Rapid),
            MotionMode::Linear => {
                let feed = self.st.feed.ok_or(RunProblem::NoFeedRate { code: name })?;
                self.linear(target, Rate::Feed(feed))
            }
            MotionMode::Arc(direction) => self.arc(target, direction, name),
        }
    }

    fn linear(&mut self, target: Xyz, rate: Rate) -> Result<(), RunProblem> {
        let end = self.checked(self.placement().machine_of(target))?;
        let start = self.st.machine;
        self.emit(Event::Linear(LinearMove { line: self.line, start, end, rate, path: self.st.path }));
        self.st.program = target;
        self.st.machine = end;
        Ok(())
    }

    fn arc(&mut self, target: Xyz, direction: ArcDirection, name: &'static str) -> Result<(), RunProblem> {
        let plane = self.st.plane;
        let (a, b, n) = plane.axes();
        let normal_letter = CENTRE_LETTERS[n];
        if self.w.has(normal_letter) {
            return Err(RunProblem::ArcCentreWord {
                letter: char::from(normal_letter),
                plane: plane.gcode(),
                centre: plane.centre_words(),
            });
        }
        let (la, lb) = plane.centre_letters();
        let radius = self.length(b'R', name)?;
        let ca = self.length(la, name)?;
        let cb = self.length(lb, name)?;
        let turns = match self.w.take(b'P', name)? {
            None => 1,
            Some(p) => match whole(b'P', p)? {
                0 => {
                    return Err(RunProblem::OutOfRange {
                        code: name,
                        letter: 'P',
                        value: p,
                        hint: "P counts full turns and must be at least 1",
                    })
                }
                t => t,
            },
        };
        let feed = self.st.feed.ok_or(RunProblem::NoFeedRate { code: name })?;
        let start = self.st.program;
        let to_user = self.cfg.machine_unit.factor_to(self.st.units);
        let inch = self.st.units == LengthUnit::Inch;
        let center = match (radius, ca, cb) {
            (Some(_), Some(_), _) | (Some(_), _, Some(_)) => return Err(RunProblem::ArcBothForms { code: name }),
            (Some(r), None, None) => {
                if turns != 1 {
                    return Err(RunProblem::OutOfRange {
                        code: name,
                        letter: 'P',
                        value: f64::from(turns),
                        hint: "multi-turn arcs need the centre form (I/J/K)",
                    });
                }
                let machine = self.conv(if inch { RADIUS_TOLERANCE_INCH } else { RADIUS_TOLERANCE_MM });
                Arc::centre_from_radius(plane, start, target, r, direction, Tolerance { machine, to_user })?
            }
            (None, None, None) => {
                return Err(RunProblem::ArcNoCentre { code: name, centre: plane.centre_words() });
            }
            (None, ca, cb) if self.st.arc_absolute => {
                let (Some(ca), Some(cb)) = (ca, cb) else {
                    let missing = if ca.is_none() { la } else { lb };
                    return Err(RunProblem::MissingWord {
                        code: name,
                        letter: char::from(missing),
                        hint: "under G90.1 both centre coordinates are absolute and required",
                    });
                };
                (ca, cb)
            }
            (None, ca, cb) => (start.axis(a) + ca.unwrap_or(0.0), start.axis(b) + cb.unwrap_or(0.0)),
        };
        let machine = self.conv(if inch { CENTRE_TOLERANCE_INCH } else { CENTRE_TOLERANCE_MM });
        let arc = Arc::from_centre(plane, start, target, center, direction, turns, Tolerance { machine, to_user })?;
        let pl = self.placement();
        let end = self.checked(pl.machine_of(target))?;
        let machine_start = self.st.machine;
        let exact = match plane {
            Plane::Xy => pl.frame.is_similarity(),
            Plane::Zx | Plane::Yz => pl.frame.is_translation(),
        };
        if exact {
            let center = self.checked(pl.machine_of(arc.center_point()))?;
            let direction = if plane == Plane::Xy && pl.frame.mirrors() { direction.reversed() } else { direction };
            self.emit(Event::Arc(ArcMove {
                line: self.line,
                start: machine_start,
                end,
                center,
                plane,
                direction,
                angle: arc.angle,
                feed,
                path: self.st.path,
            }));
        } else {
            let segments = arc.segments(pl.frame.stretch(), self.cfg.chord_tolerance);
            if segments > self.cfg.max_arc_segments {
                return Err(RunProblem::ArcTooManySegments { segments });
            }
            self.out.push(Pending::Polyline(Polyline {
                line: self.line,
                arc,
                placement: pl,
                segments,
                start: machine_start,
                feed,
                path: self.st.path,
                chord_tolerance: self.cfg.chord_tolerance,
            }));
        }
        self.st.program = target;
        self.st.machine = end;
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
                self.st.reset(self.cfg);
                for axis in 0..3 {
                    self.params.set(G92_OFFSET + axis, 0.0);
                }
                self.st.rederive_program(self.params);
                Ok(Flow::End(c))
            }
        }
    }
}
