//! Canned drilling cycles G73, G81, G82, G83, G85 and G89 (XY plane), expanded into straight
//! moves and dwells exactly as LinuxCNC 2.9 does (`interp_cycles.cc`, `convert_cycle_xy`).
//!
//! The cycle's own moves run in exact-stop mode; the path mode is restored after the line.

use crate::error::{GCode, RunProblem};
use crate::event::{Event, EventSink, LinearMove, PathMode, Rate};
use crate::frame::Placement;
use crate::geom::{Plane, Xyz};
use vision_math::LengthUnit;

use super::line::{LineRun, Pending};
use super::modal::MotionMode;
use super::motion::polar_step;

/// LinuxCNC's rapid back-off of G73/G83 between pecks: 0.010 in (the 2.9 rs274 prints 0.2540 mm
/// in a millimetre program, 0.0100 in an inch one).
const PECK_CLEARANCE_INCH: f64 = 0.010;

/// The most pecks one G73/G83 hole may take: a Q far below the hole depth is a typo, and would
/// otherwise never end (a Q below the depth's rounding step does not deepen the hole at all).
const MAX_PECKS: f64 = 100_000.0;

/// The most moves one canned-cycle line may make (repeats × pecks): beyond it the program is a
/// typo, and its moves would take hours to run or print. A cycle's moves are walked, not held,
/// so the bound is one of time, not memory.
pub const MAX_CYCLE_MOVES: u64 = 10_000_000;

/// The G-code of a cycle.
pub(crate) fn cycle_name(code: GCode) -> &'static str {
    match code.0 {
        730 => "G73",
        810 => "G81",
        820 => "G82",
        830 => "G83",
        850 => "G85",
        _ => "G89",
    }
}

/// What a series of cycle lines remembers (LinuxCNC's `cycle_r`, `cycle_cc`, `cycle_p`,
/// `cycle_q`, `cycle_il`). Lengths as (program units as written, machine units); incremental
/// values stay increments.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct CycleState {
    /// The last `R` word.
    pub(crate) r: (f64, f64),
    /// The last `Z` word.
    pub(crate) z: (f64, f64),
    /// The last `P` (seconds).
    pub(crate) p: f64,
    /// The last `Q`.
    pub(crate) q: (f64, f64),
    /// The Z where the current series of cycles started (G98 returns there); `None` once any
    /// other motion ran.
    pub(crate) initial_level: Option<f64>,
}

impl LineRun<'_> {
    /// One canned-cycle line: `code` is the cycle, `previous` the motion mode before the line
    /// (a repeated cycle may omit R, Z, P and Q).
    pub(super) fn canned_cycle(&mut self, code: GCode, previous: Option<MotionMode>) -> Result<(), RunProblem> {
        let name = cycle_name(code);
        if self.st.plane != Plane::Xy {
            return Err(RunProblem::Unsupported {
                code: format!("{name} in {}", self.st.plane.gcode()),
                feature: "a canned cycle outside the XY plane (G17)",
            });
        }
        let feed = self.feed(name)?;
        let repeated = previous == Some(MotionMode::Cycle(code));
        let r_word = match (self.length_as_written(b'R', name)?, repeated) {
            (Some(r), _) => r,
            (None, true) => self.st.cycle.r,
            (None, false) => {
                return Err(RunProblem::MissingWord { code: name, letter: 'R', hint: "the retract plane, e.g. R0.1" })
            }
        };
        let repeats = self.count(b'L', name, "L counts repeats and must be at least 1")?;
        let z_word = match (self.length_as_written(b'Z', name)?, repeated) {
            (Some(z), _) => z,
            (None, true) => self.st.cycle.z,
            (None, false) => {
                return Err(RunProblem::MissingWord { code: name, letter: 'Z', hint: "the hole bottom, e.g. Z-0.5" })
            }
        };
        let dwell = if matches!(code.0, 820 | 890) {
            match (self.w.take(b'P', name)?, repeated) {
                (Some(p), _) if p < 0.0 => return Err(RunProblem::Negative { code: name, letter: 'P', value: p }),
                (Some(p), _) => p,
                (None, true) => self.st.cycle.p,
                (None, false) => {
                    return Err(RunProblem::MissingWord {
                        code: name,
                        letter: 'P',
                        hint: "the dwell in seconds, e.g. P0.5",
                    })
                }
            }
        } else {
            0.0
        };
        let peck = if matches!(code.0, 730 | 830) {
            let q = match (self.length_as_written(b'Q', name)?, repeated) {
                (Some(q), _) => q,
                (None, true) => self.st.cycle.q,
                (None, false) => {
                    return Err(RunProblem::MissingWord { code: name, letter: 'Q', hint: "the peck depth, e.g. Q0.1" })
                }
            };
            if q.1 <= 0.0 {
                return Err(RunProblem::OutOfRange {
                    code: name,
                    letter: 'Q',
                    value: q.1 * self.cfg.machine_unit.factor_to(self.st.units),
                    hint: "the peck depth must be positive",
                });
            }
            q
        } else {
            (0.0, 0.0)
        };
        let start = self.st.program;
        let old_level = *self.st.cycle.initial_level.get_or_insert(start.z);
        // R and the bottom in machine units, and in program units for counting the pecks.
        let (mut x, mut y, step_x, step_y, r, bottom, r_written, bottom_written);
        // LinuxCNC's polar words: a hole position (G90), or a step per repeat (G91).
        let polar = if self.w.has(b'@') || self.w.has(b'^') { Some(self.polar_words(name)?) } else { None };
        let (mut step_distance, mut step_angle) = (None, None);
        if self.st.absolute {
            x = self.length(b'X', name)?.unwrap_or(start.x);
            y = self.length(b'Y', name)?.unwrap_or(start.y);
            if let Some((distance, angle)) = polar {
                let radius = distance.unwrap_or(start.x.hypot(start.y));
                let theta = angle.unwrap_or(start.y.atan2(start.x));
                (x, y) = (radius * theta.cos(), radius * theta.sin());
            }
            (step_x, step_y) = (0.0, 0.0);
            (r_written, r) = r_word;
            (bottom_written, bottom) = z_word;
        } else {
            step_x = self.length(b'X', name)?.unwrap_or(0.0);
            step_y = self.length(b'Y', name)?.unwrap_or(0.0);
            if let Some((distance, angle)) = polar {
                // rs274 steps only by a non-zero increment.
                (step_distance, step_angle) = (distance.filter(|d| *d != 0.0), angle.filter(|a| *a != 0.0));
            }
            (x, y) = (start.x, start.y);
            r = r_word.1 + old_level;
            bottom = r + z_word.1;
            r_written = r_word.0 + self.cfg.machine_unit.convert(old_level, self.st.units);
            bottom_written = r_written + z_word.0;
        }
        if r < bottom {
            return Err(RunProblem::CycleRBelowZ { code: name });
        }
        if peck.0 > 0.0 && (r_written - bottom_written) / peck.0 > MAX_PECKS {
            return Err(RunProblem::OutOfRange {
                code: name,
                letter: 'Q',
                value: peck.0,
                hint: "the hole would take more than 100 000 pecks; program a larger peck depth",
            });
        }
        let clear_level = if self.st.retract_to_r { r } else { old_level.max(r) };
        let plan = CyclePlan {
            code: code.0,
            line: self.line,
            placement: self.placement(),
            units: self.st.units,
            machine_unit: self.cfg.machine_unit,
            start,
            machine: self.st.machine,
            first: (x, y),
            step: (step_x, step_y),
            polar_step: (step_distance, step_angle),
            repeats,
            r,
            bottom,
            clear: clear_level,
            r_written,
            bottom_written,
            peck: peck.0,
            feed,
            dwell,
            rise_to_r: old_level < r,
            clearance: LengthUnit::Inch.convert(PECK_CLEARANCE_INCH, self.cfg.machine_unit),
        };
        // Checked now, emitted when the line commits: a failing cycle emits nothing, and its
        // moves are never held in memory (a cycle may make millions).
        let mut moves = 0u64;
        let mut last = None;
        plan.walk(&mut |step| {
            if let CycleStep::Move(p, _) = step {
                moves += 1;
                if moves > MAX_CYCLE_MOVES {
                    return Err(RunProblem::CycleTooManyMoves { code: name, limit: MAX_CYCLE_MOVES });
                }
                last = Some((p, self.checked(plan.placement.machine_of(p))?));
            }
            Ok(())
        })?;
        if let Some((program, machine)) = last {
            self.st.program = program;
            self.st.machine = machine;
        }
        self.out.push(Pending::Cycle(Box::new(CycleCursor::new(plan))));
        self.st.cycle.r = r_word;
        self.st.cycle.z = z_word;
        self.st.cycle.p = dwell;
        self.st.cycle.q = peck;
        Ok(())
    }
}

/// One step of a canned cycle: a straight move to a program point, or the bottom dwell.
#[derive(Debug, Clone, Copy)]
enum CycleStep {
    Move(Xyz, Rate),
    Dwell,
}

/// A canned-cycle line, checked: everything needed to walk its moves again when the line
/// commits. Lengths in machine units unless said otherwise.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CyclePlan {
    /// The cycle's code ×10 (810 = G81).
    code: u16,
    line: u32,
    placement: Placement,
    /// The program's units (pecks are counted in them).
    units: LengthUnit,
    machine_unit: LengthUnit,
    /// The program point before the cycle.
    start: Xyz,
    /// The machine position before the cycle.
    machine: Xyz,
    /// X/Y before the first step (the hole position under G90).
    first: (f64, f64),
    /// X/Y step per repeat (G91).
    step: (f64, f64),
    /// LinuxCNC's polar step per repeat: distance (machine units) and angle (radians).
    polar_step: (Option<f64>, Option<f64>),
    repeats: u32,
    /// The R plane and the hole bottom.
    r: f64,
    bottom: f64,
    /// Where each hole retracts to (R under G99, else the initial level).
    clear: f64,
    /// R and the bottom in program units, for counting pecks as rs274 does.
    r_written: f64,
    bottom_written: f64,
    /// The peck depth, program units (0 for cycles without pecks).
    peck: f64,
    /// Feed, machine units per minute.
    feed: f64,
    /// G82/G89's dwell at the bottom, seconds.
    dwell: f64,
    /// Whether the tool first rises from below R to R.
    rise_to_r: bool,
    /// The back-off of G73/G83 between pecks.
    clearance: f64,
}

impl CyclePlan {
    /// Walks the cycle's steps in order (LinuxCNC's `convert_cycle_xy`), stopping at the first
    /// error `f` returns.
    fn walk(self, f: &mut dyn FnMut(CycleStep) -> Result<(), RunProblem>) -> Result<(), RunProblem> {
        let mut holes = CycleCursor::new(self);
        while holes.hole(f)? {}
        Ok(())
    }
}

/// A checked canned cycle on its way to the sink, a hole at a time.
#[derive(Debug, Clone)]
pub(crate) struct CycleCursor {
    plan: CyclePlan,
    /// Holes walked so far.
    repeat: u32,
    /// X/Y of the last hole (before the first: where the steps start).
    x: f64,
    y: f64,
    /// Machine position after the last step emitted.
    from: Xyz,
}

impl CycleCursor {
    fn new(plan: CyclePlan) -> CycleCursor {
        CycleCursor { plan, repeat: 0, x: plan.first.0, y: plan.first.1, from: plan.machine }
    }

    /// Walks the next hole (after the rise to R, for the first); whether holes are left.
    fn hole(&mut self, f: &mut dyn FnMut(CycleStep) -> Result<(), RunProblem>) -> Result<bool, RunProblem> {
        let p = self.plan;
        if self.repeat >= p.repeats {
            return Ok(false);
        }
        let (r, bottom, clear, feed) = (p.r, p.bottom, p.clear, p.feed);
        let to = |x: f64, y: f64, z: f64, rate: Rate| CycleStep::Move(Xyz::new(x, y, z), rate);
        let current = if p.rise_to_r { r } else { p.start.z };
        if self.repeat == 0 && p.rise_to_r {
            f(to(p.start.x, p.start.y, r, Rate::Rapid))?;
        }
        let (x, y) = polar_step(self.x + p.step.0, self.y + p.step.1, p.polar_step.0, p.polar_step.1)?;
        (self.x, self.y) = (x, y);
        if self.repeat == 0 && current > r {
            f(to(x, y, current, Rate::Rapid))?;
            f(to(x, y, r, Rate::Rapid))?;
        } else {
            f(to(x, y, clear, Rate::Rapid))?;
            if clear > r {
                f(to(x, y, r, Rate::Rapid))?;
            }
        }
        match p.code {
            730 | 830 => {
                // Counted in program units, as rs274 does: converted to machine units, a hole
                // depth that is an exact multiple of Q can round to one peck more or less.
                let mut depth_written = p.r_written - p.peck;
                while depth_written > p.bottom_written {
                    let depth = p.units.convert(depth_written, p.machine_unit);
                    f(to(x, y, depth, Rate::Feed(feed)))?;
                    if p.code == 830 {
                        f(to(x, y, r, Rate::Rapid))?;
                    }
                    f(to(x, y, depth + p.clearance, Rate::Rapid))?;
                    depth_written -= p.peck;
                }
                f(to(x, y, bottom, Rate::Feed(feed)))?;
                f(to(x, y, clear, Rate::Rapid))?;
            }
            850 => {
                f(to(x, y, bottom, Rate::Feed(feed)))?;
                f(to(x, y, r, Rate::Feed(feed)))?;
                f(to(x, y, clear, Rate::Rapid))?;
            }
            _ => {
                f(to(x, y, bottom, Rate::Feed(feed)))?;
                if matches!(p.code, 820 | 890) {
                    f(CycleStep::Dwell)?;
                }
                let out = if p.code == 890 { Rate::Feed(feed) } else { Rate::Rapid };
                f(to(x, y, clear, out))?;
            }
        }
        self.repeat += 1;
        Ok(self.repeat < p.repeats)
    }

    /// Emits every remaining move (exact stop at each) and dwell; the plan was checked when its
    /// line ran, so no step fails here.
    pub(crate) fn emit(&mut self, sink: &mut dyn EventSink) {
        while self.emit_some(sink) {}
    }

    /// Emits the next hole; whether holes are left.
    pub(crate) fn emit_some(&mut self, sink: &mut dyn EventSink) -> bool {
        let (line, placement, dwell) = (self.plan.line, self.plan.placement, self.plan.dwell);
        let mut from = self.from;
        let more = self.hole(&mut |step| {
            let event = match step {
                CycleStep::Move(p, rate) => {
                    let end = placement.machine_of(p);
                    let start = std::mem::replace(&mut from, end);
                    Event::Linear(LinearMove { line, start, end, rate, path: PathMode::ExactStop })
                }
                CycleStep::Dwell => Event::Dwell { line, seconds: dwell },
            };
            sink.event(&event);
            Ok(())
        });
        self.from = from;
        more.unwrap_or(false)
    }
}
