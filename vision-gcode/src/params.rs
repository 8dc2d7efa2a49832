//! Numbered parameters (`#1`–`#9999`, LinuxCNC `#1`–`#5601`) and the addresses that mirror the
//! modal state.
//!
//! The addresses follow LinuxCNC where the state exists here. The offset parameters are the
//! offsets' storage (when a written `#5221` moves the G54 origin depends on the dialect: see the
//! repository's `docs/gcode-interpreter.md`); they hold **machine units**. The read-only parameters report the state in **current units** and
//! are refreshed after every line.

use std::collections::HashMap;

use crate::error::RunProblem;
use crate::geom::MAX_COORDINATE;
use crate::whole::whole_in;

/// Highest parameter number of any dialect ([`crate::Dialect::last_parameter`] gives each one's).
pub const MAX_PARAMETER: u32 = {
    let (mut i, mut max) = (0, 0);
    while i < crate::Dialect::ALL.len() {
        let last = crate::Dialect::ALL[i].last_parameter();
        if last > max {
            max = last;
        }
        i += 1;
    }
    max
};
/// `#5161`–`#5163`: the G28 position (machine coordinates, machine units).
pub const G28_POSITION: u32 = 5161;
/// `#5181`–`#5183`: the G30 position (machine coordinates, machine units).
pub const G30_POSITION: u32 = 5181;
/// `#5211`–`#5213`: the G92 offset (machine units).
pub const G92_OFFSET: u32 = 5211;
/// `#5220`: the active coordinate system, 1 (G54) … 6 (G59). Read-only.
pub const ACTIVE_SYSTEM: u32 = 5220;
/// `#5221 + 20·(n − 1)` … `+ 2`: X, Y, Z origin of coordinate system n (G54 = 1), machine units.
pub const WORK_OFFSET_BASE: u32 = 5221;
/// Distance between two coordinate systems' blocks.
pub const WORK_OFFSET_STRIDE: u32 = 20;
/// `#5230 + 20·(n − 1)`: the XY rotation of coordinate system n about its origin (LinuxCNC's
/// `G10 L2 R`), degrees counter-clockwise.
pub const WORK_ROTATION: u32 = 5230;
/// `#5400`: the active tool number. Read-only.
pub const TOOL_NUMBER: u32 = 5400;
/// `#5401`–`#5403`: the active tool's X, Y offset and Z length, current units. Read-only.
pub const TOOL_OFFSET: u32 = 5401;
/// `#5420`–`#5422`: the current X, Y, Z in the program frame, current units. Read-only.
pub const POSITION: u32 = 5420;

/// LinuxCNC's predefined read-only named parameters provided under its dialect (names as
/// programs read them, lower case): `_task` is 0 as in any preview interpreter (rs274, Axis's
/// preview), `_vmajor`/`_vminor` 2.9 and 0 (rs274 reads "2.9.0" with `%lf%lf`), `_x`/`_y`/`_z`
/// the current point (#5420–#5422), then the units, distance mode, tools, feed and spindle
/// speed.
pub(crate) const PREDEFINED: [&str; 14] = [
    "_task",
    "_vmajor",
    "_vminor",
    "_x",
    "_y",
    "_z",
    "_imperial",
    "_metric",
    "_absolute",
    "_incremental",
    "_current_tool",
    "_selected_tool",
    "_feed",
    "_rpm",
];

/// Number of coordinate systems: 1 (G54) … 6 (G59); G59.1–G59.3 are not supported.
pub(crate) const SYSTEMS: u32 = 6;

/// First parameter of coordinate system `n` (1 = G54 … 6 = G59; a number outside that range
/// stands for the nearest system).
pub(crate) fn work_offset_base(n: u32) -> u32 {
    WORK_OFFSET_BASE + WORK_OFFSET_STRIDE * (n.clamp(1, SYSTEMS) - 1)
}

/// The rotation parameter of coordinate system `n` (as [`work_offset_base`]).
pub(crate) fn work_rotation(n: u32) -> u32 {
    work_offset_base(n) + (WORK_ROTATION - WORK_OFFSET_BASE)
}

/// Whether `#n` holds the X, Y or Z origin of one of the coordinate systems.
pub(crate) fn is_work_offset(n: u32) -> bool {
    (WORK_OFFSET_BASE..work_offset_base(SYSTEMS) + 3).contains(&n) && (n - WORK_OFFSET_BASE) % WORK_OFFSET_STRIDE < 3
}

/// Parameter numbers differing from a whole number by less than this are taken as that number.
const INDEX_TOLERANCE: f64 = 1e-4;

/// The parameter table with an undo log, so a failing line leaves no write behind.
///
/// Named parameters (`#<name>`): a name starting with `_` is global; any other is local to the
/// subroutine call that wrote it (the main program has its own frame).
#[derive(Debug, Clone)]
pub(crate) struct ParameterTable {
    values: Box<[f64]>,
    /// The highest parameter number (the dialect's).
    last: u32,
    /// The dialect's name, for the error message.
    dialect: &'static str,
    /// The values of [`PREDEFINED`] (LinuxCNC only), refreshed after every line.
    predefined: Option<[f64; PREDEFINED.len()]>,
    undo: Vec<(u32, f64)>,
    globals: HashMap<Box<str>, f64>,
    /// Local names, one map per active call (the first for the main program).
    frames: Vec<HashMap<Box<str>, f64>>,
    /// (name, previous value) of named writes since [`ParameterTable::begin`].
    named_undo: Vec<(Box<str>, Option<f64>)>,
}

impl Default for ParameterTable {
    fn default() -> Self {
        ParameterTable::for_dialect(crate::Dialect::default())
    }
}

#[cfg(test)]
impl ParameterTable {
    /// All parameters zero, the default dialect's (seed 002's) range.
    #[must_use]
    pub(crate) fn new() -> ParameterTable {
        ParameterTable::for_dialect(crate::Dialect::default())
    }
}

impl ParameterTable {
    /// All parameters zero, numbered 1 to `dialect`'s last.
    #[must_use]
    pub(crate) fn for_dialect(dialect: crate::Dialect) -> ParameterTable {
        let last = dialect.last_parameter();
        ParameterTable {
            values: vec![0.0; last as usize + 1].into_boxed_slice(),
            last,
            dialect: dialect.name(),
            predefined: dialect.rules().named_predefined_parameters.then_some([0.0; PREDEFINED.len()]),
            undo: Vec::new(),
            globals: HashMap::new(),
            frames: vec![HashMap::new()],
            named_undo: Vec::new(),
        }
    }

    /// The parameter number `index` stands for.
    ///
    /// # Errors
    /// [`RunProblem::BadParameter`] unless `index` is (within 1e-4) a whole number from 1 to
    /// the dialect's last.
    pub(crate) fn index(&self, index: f64) -> Result<u32, RunProblem> {
        match whole_in(index, INDEX_TOLERANCE, self.last).filter(|&n| n >= 1) {
            Some(n) => Ok(n),
            None => Err(self.bad(index)),
        }
    }

    /// The error for parameter number `index`, which is not one.
    pub(crate) fn bad(&self, index: f64) -> RunProblem {
        RunProblem::BadParameter { index, last: self.last, dialect: self.dialect }
    }

    /// Whether `#n` exists in the dialect.
    pub(crate) fn exists(&self, n: u32) -> bool {
        (1..=self.last).contains(&n)
    }

    /// Reads `#index` (the index as an expression computed it).
    ///
    /// # Errors
    /// [`RunProblem::BadParameter`] for an index outside the dialect's range.
    pub(crate) fn read(&self, index: f64) -> Result<f64, RunProblem> {
        Ok(self.get(self.index(index)?))
    }

    /// Reads `#<name>` (lower case).
    ///
    /// # Errors
    /// [`RunProblem::UndefinedName`] when nothing was assigned to it (in this call, for a local).
    pub(crate) fn read_named(&self, name: &str) -> Result<f64, RunProblem> {
        if let Some(v) = self.predefined(name) {
            return Ok(v);
        }
        let value =
            if name.starts_with('_') { self.globals.get(name) } else { self.frames.last().and_then(|f| f.get(name)) };
        value.copied().ok_or_else(|| RunProblem::UndefinedName { name: name.to_string() })
    }

    /// Writes `#<name>` (global when it starts with `_`, else local to the current call).
    ///
    /// # Errors
    /// [`RunProblem::NonFinite`] for a NaN or infinite value.
    pub(crate) fn write_named(&mut self, name: &str, value: f64) -> Result<(), RunProblem> {
        if self.predefined(name).is_some() {
            return Err(RunProblem::ReadOnlyName { name: name.to_string() });
        }
        if !value.is_finite() {
            return Err(RunProblem::NonFinite { what: "the value written to a parameter" });
        }
        let map =
            if name.starts_with('_') { &mut self.globals } else { self.frames.last_mut().unwrap_or(&mut self.globals) };
        let old = map.insert(name.into(), value);
        self.named_undo.push((name.into(), old));
        Ok(())
    }

    /// The value of a predefined name (under LinuxCNC), `None` for any other name.
    fn predefined(&self, name: &str) -> Option<f64> {
        let values = self.predefined.as_ref().filter(|_| name.starts_with('_'))?;
        PREDEFINED.iter().position(|p| *p == name).map(|i| values[i])
    }

    /// Sets the predefined names' values (ignored outside LinuxCNC).
    pub(crate) fn set_predefined(&mut self, values: [f64; PREDEFINED.len()]) {
        if let Some(slot) = self.predefined.as_mut() {
            *slot = values;
        }
    }

    /// A subroutine call starts: a fresh frame of local names.
    pub(crate) fn push_frame(&mut self) {
        self.frames.push(HashMap::new());
    }

    /// The call returns: its local names go.
    pub(crate) fn pop_frame(&mut self) {
        if self.frames.len() > 1 {
            self.frames.pop();
        }
    }

    /// The value of `#n` (0 for numbers outside the table).
    #[must_use]
    pub(crate) fn get(&self, n: u32) -> f64 {
        self.values.get(n as usize).copied().unwrap_or(0.0)
    }

    /// What a read-only parameter reports, or `None` when `n` is writable.
    #[must_use]
    pub(crate) fn read_only(n: u32) -> Option<&'static str> {
        match n {
            ACTIVE_SYSTEM => Some("the active coordinate system"),
            5400 => Some("the active tool number"),
            5401..=5409 => Some("the active tool's offsets"),
            5420..=5428 => Some("the current position"),
            _ => None,
        }
    }

    /// Writes `#n` as a program or a handler does: refuses read-only parameters.
    ///
    /// # Errors
    /// [`RunProblem::ReadOnlyParameter`], [`RunProblem::BadParameter`] for `n` outside the
    /// dialect's range,
    /// [`RunProblem::NonFinite`] for a NaN or infinite value.
    pub(crate) fn write(&mut self, n: u32, value: f64) -> Result<(), RunProblem> {
        if !self.exists(n) {
            return Err(self.bad(f64::from(n)));
        }
        if let Some(what) = ParameterTable::read_only(n) {
            return Err(RunProblem::ReadOnlyParameter { index: n, what });
        }
        if !value.is_finite() {
            return Err(RunProblem::NonFinite { what: "the value written to a parameter" });
        }
        if ParameterTable::holds_machine_length(n) && value.abs() > MAX_COORDINATE {
            return Err(RunProblem::BeyondRange { what: format!("the value written to #{n}"), value });
        }
        self.set(n, value);
        Ok(())
    }

    /// Whether `#n` holds a position or an offset (machine units) that reaches the machine.
    fn holds_machine_length(n: u32) -> bool {
        let in_block = |base: u32| (base..base + 3).contains(&n);
        in_block(G28_POSITION) || in_block(G30_POSITION) || in_block(G92_OFFSET) || is_work_offset(n)
    }

    /// Writes `#n` unconditionally, logging the old value (the interpreter's own writes).
    pub(crate) fn set(&mut self, n: u32, value: f64) {
        if let Some(slot) = self.values.get_mut(n as usize) {
            self.undo.push((n, *slot));
            *slot = value;
        }
    }

    /// Writes a read-only mirror (not logged: mirrors are recomputed after every line).
    pub(crate) fn set_mirror(&mut self, n: u32, value: f64) {
        if let Some(slot) = self.values.get_mut(n as usize) {
            *slot = value;
        }
    }

    /// Three consecutive parameters `#n`, `#n+1`, `#n+2`.
    #[must_use]
    pub(crate) fn triple(&self, n: u32) -> [f64; 3] {
        [self.get(n), self.get(n + 1), self.get(n + 2)]
    }

    /// Starts a line: forget the previous line's undo log.
    pub(crate) fn begin(&mut self) {
        self.undo.clear();
        self.named_undo.clear();
    }

    /// Undoes every write since [`ParameterTable::begin`], newest first.
    pub(crate) fn rollback(&mut self) {
        while let Some((n, old)) = self.undo.pop() {
            if let Some(slot) = self.values.get_mut(n as usize) {
                *slot = old;
            }
        }
        while let Some((name, old)) = self.named_undo.pop() {
            let map = if name.starts_with('_') {
                &mut self.globals
            } else {
                self.frames.last_mut().unwrap_or(&mut self.globals)
            };
            match old {
                Some(v) => map.insert(name, v),
                None => map.remove(&name),
            };
        }
    }
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;

    #[test]
    fn indices_reads_writes_and_rollback() {
        let mut p = ParameterTable::new();
        assert_eq!(p.index(5.00001), Ok(5));
        assert!(p.index(0.0).is_err());
        assert_eq!(p.index(9999.0), Ok(9999));
        assert!(p.index(10_000.0).is_err());
        assert!(p.index(1.5).is_err());
        assert!(p.index(f64::NAN).is_err());
        let lcnc = ParameterTable::for_dialect(crate::Dialect::LinuxCnc);
        assert_eq!(lcnc.index(5601.0), Ok(5601));
        assert_eq!(
            lcnc.index(5602.0),
            Err(RunProblem::BadParameter { index: 5602.0, last: 5601, dialect: "linuxcnc" })
        );
        p.begin();
        p.write(7, 2.5).expect("writable");
        p.write(G92_OFFSET, 1.0).expect("offsets are writable");
        assert_eq!(p.read(7.0), Ok(2.5));
        assert!(matches!(p.write(5420, 1.0), Err(RunProblem::ReadOnlyParameter { index: 5420, .. })));
        assert!(p.write(8, f64::INFINITY).is_err());
        p.rollback();
        assert_eq!(p.get(7), 0.0);
        assert_eq!(p.get(G92_OFFSET), 0.0);
    }
}
