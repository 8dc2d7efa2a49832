//! The host's writes into the interpreter's state between or during programs: parameters, tool
//! offsets, saved modal states and the machine position.

use super::modal::{is_work_offset, SYSTEMS};
use super::{line, Interpreter, MAX_SAVED_MODAL_STATES};
use crate::error::{GcodeError, RunProblem};
use crate::geom::Xyz;
use crate::params::G92_OFFSET;
use crate::tools::Tool;

impl Interpreter {
    /// Writes `#n` as a program would (read-only parameters refused). Offset parameters take
    /// effect at once: the machine stays, the program position is re-derived.
    ///
    /// # Errors
    /// [`RunProblem::ReadOnlyParameter`], [`RunProblem::BadParameter`], a non-finite value, an
    /// offset or position beyond [`crate::MAX_COORDINATE`]; reported at `line`.
    pub(crate) fn write_param(&mut self, n: u32, value: f64, line: u32) -> Result<(), GcodeError> {
        self.params.begin();
        self.params.write(n, value).map_err(|p| GcodeError::run(line, p))?;
        self.params.begin();
        if affects_frame(n) {
            // A host's or handler's write stands for the control's offset table: it takes
            // effect at once in every dialect.
            self.modal.load_system(&self.config, &self.params);
            self.modal.rederive_program(&self.params);
        }
        self.refresh_mirrors();
        Ok(())
    }

    /// Writes `#n` as a program would (read-only parameters refused). Offset parameters take
    /// effect at once: the machine stays, the program position is re-derived.
    ///
    /// # Errors
    /// As [`Context::set_pound`](crate::Context::set_pound).
    pub fn set_param(&mut self, n: u32, value: f64) -> Result<(), GcodeError> {
        self.write_param(n, value, 0)
    }

    /// Makes `chain` (current units; `None`: none) the alignment applied to every later move,
    /// as a host that rewrites the program's points applies it (a Grbl sender): it replaces
    /// the G51/G68/G52 X/Y modals and is applied exactly as they are, arcs included; M2/M30
    /// cancel it as they cancel them. The machine stays; the program position is re-derived.
    ///
    /// # Errors
    /// A non-finite number, a centre or shift beyond [`crate::MAX_COORDINATE`], a zero scale
    /// factor; reported at `line`. Nothing changes then.
    pub(crate) fn write_host_alignment(
        &mut self,
        chain: Option<vision_math::AlignmentChain>,
        line: u32,
    ) -> Result<(), GcodeError> {
        let chain = chain.unwrap_or(vision_math::AlignmentChain::IDENTITY);
        if !chain.is_finite() {
            return Err(GcodeError::run(line, RunProblem::NonFinite { what: "the host's alignment" }));
        }
        for (letter, factor) in [('X', chain.scale.x), ('Y', chain.scale.y)] {
            if factor == 0.0 {
                return Err(GcodeError::run(line, RunProblem::ZeroScale { letter }));
            }
        }
        let (from, to) = (self.modal.units, self.config.machine_unit);
        let c = |v: f64| from.convert(v, to);
        let (center, shift) = ((c(chain.center.x), c(chain.center.y)), (c(chain.shift.x), c(chain.shift.y)));
        for v in [center.0, center.1, shift.0, shift.1] {
            line::in_range(v, || "the host's alignment".to_string()).map_err(|p| GcodeError::run(line, p))?;
        }
        let frame = &mut self.modal.frame;
        frame.chain.scale = chain.scale;
        frame.chain.shift = vision_math::Vector2::new(shift.0, shift.1);
        frame.set_rotation(vision_math::Point2::new(center.0, center.1), chain.rotation_deg);
        self.modal.rederive_program(&self.params);
        Ok(())
    }

    /// Sets tool `tool`'s X/Y offset (current units), keeping its length; for the active tool
    /// the machine stays and the program position is re-derived.
    ///
    /// # Errors
    /// [`RunProblem::UnknownTool`] for tool 0 or a tool not in the table; a non-finite value;
    /// [`RunProblem::BeyondRange`] for one beyond [`crate::MAX_COORDINATE`].
    pub(crate) fn write_tool_offset(&mut self, tool: u32, x: f64, y: f64, line: u32) -> Result<(), GcodeError> {
        if !(x.is_finite() && y.is_finite()) {
            return Err(GcodeError::run(line, RunProblem::NonFinite { what: "the tool offset" }));
        }
        let (from, to) = (self.modal.units, self.config.machine_unit);
        let (x, y) = (from.convert(x, to), from.convert(y, to));
        for v in [x, y] {
            line::in_range(v, || format!("tool {tool}'s offset")).map_err(|p| GcodeError::run(line, p))?;
        }
        let entry = self.config.tools.get_mut(tool).ok_or(GcodeError::run(line, RunProblem::UnknownTool { tool }))?;
        entry.offset.x = x;
        entry.offset.y = y;
        let offset = entry.offset;
        self.after_tool_write(tool, offset);
        Ok(())
    }

    /// Sets tool `tool`'s X/Y offset in current units (see
    /// [`Context::set_tool_offset`](crate::Context::set_tool_offset)).
    ///
    /// # Errors
    /// As [`Context::set_tool_offset`](crate::Context::set_tool_offset).
    pub fn set_tool_offset(&mut self, tool: u32, x: f64, y: f64) -> Result<(), GcodeError> {
        self.write_tool_offset(tool, x, y, 0)
    }

    /// Saves the modal state — motion mode, plane, distance and arc distance modes, units, path
    /// mode, feed and feed mode, the canned cycles' return mode — on a stack, as Mach4's
    /// `mcCntlMachineStatePush` and LinuxCNC's `M70` do, so that a host's own moves can be
    /// undone by [`Interpreter::pop_modal_state`].
    ///
    /// # Errors
    /// [`RunProblem::ModalStack`] when [`MAX_SAVED_MODAL_STATES`] are saved already.
    pub fn push_modal_state(&mut self) -> Result<(), GcodeError> {
        if self.saved_modal.len() >= MAX_SAVED_MODAL_STATES {
            return Err(GcodeError::run(0, RunProblem::ModalStack { what: "too many modal states are saved already" }));
        }
        self.saved_modal.push(self.modal);
        Ok(())
    }

    /// Restores the modal state [`Interpreter::push_modal_state`] saved last and forgets it.
    /// The position, the work system and its offsets, the tool and the alignment stay as they
    /// are now (the moves in between happened).
    ///
    /// # Errors
    /// [`RunProblem::ModalStack`] when none is saved.
    pub fn pop_modal_state(&mut self) -> Result<(), GcodeError> {
        let saved = self
            .saved_modal
            .pop()
            .ok_or_else(|| GcodeError::run(0, RunProblem::ModalStack { what: "no modal state is saved" }))?;
        let m = &mut self.modal;
        m.motion = saved.motion;
        m.plane = saved.plane;
        m.absolute = saved.absolute;
        m.arc_absolute = saved.arc_absolute;
        m.units = saved.units;
        m.path = saved.path;
        m.feed = saved.feed;
        m.per_revolution = saved.per_revolution;
        m.retract_to_r = saved.retract_to_r;
        m.cycle = saved.cycle;
        self.refresh_mirrors();
        Ok(())
    }

    /// Adds or replaces a tool-table entry (machine units). Tool 0 is ignored.
    pub fn set_tool(&mut self, number: u32, tool: Tool) {
        self.config.tools.insert(number, tool);
        if number != 0 {
            self.after_tool_write(number, tool.offset);
        }
    }

    fn after_tool_write(&mut self, tool: u32, offset: Xyz) {
        if tool == self.modal.tool {
            let rules = self.config.rules();
            let offset = rules.applied_tool_offset(offset);
            self.modal.tool_offset = rules.table_write_applies.take(self.modal.tool_offset, offset);
            self.modal.rederive_program(&self.params);
            self.refresh_mirrors();
        }
    }

    /// Puts the machine at `machine` (machine units) without a move event — where a host's
    /// homing or jogging left it. The program position is re-derived.
    ///
    /// # Errors
    /// [`RunProblem::NonFinitePosition`] for a NaN or infinite coordinate.
    pub fn set_machine_position(&mut self, machine: Xyz) -> Result<(), GcodeError> {
        if !machine.is_finite() {
            return Err(GcodeError::run(0, RunProblem::NonFinitePosition));
        }
        self.modal.machine = machine;
        self.modal.rederive_program(&self.params);
        self.refresh_mirrors();
        Ok(())
    }
}

/// Whether writing `#n` moves the program frame (G92, work offsets and, under LinuxCNC, their
/// rotations).
pub(super) fn affects_frame(n: u32) -> bool {
    (G92_OFFSET..G92_OFFSET + 3).contains(&n)
        || is_work_offset(n)
        || (1..=SYSTEMS).any(|system| crate::params::work_rotation(system) == n)
}
