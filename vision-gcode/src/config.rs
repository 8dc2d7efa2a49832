//! How the interpreter is set up: machine unit, start-up modes, tolerances, tools, user M-codes.

use std::ops::RangeInclusive;
use std::path::PathBuf;

use vision_math::LengthUnit;

use crate::event::PathMode;
use crate::geom::Xyz;
use crate::tools::ToolTable;

/// Default chord tolerance for arcs turned into polylines: 0.0001 in.
pub const CHORD_TOLERANCE_INCH: f64 = 0.0001;
/// The same tolerance for a millimetre machine: 0.0025 mm.
pub const CHORD_TOLERANCE_MM: f64 = 0.0025;
/// The default limit on polyline segments for one arc.
pub const MAX_ARC_SEGMENTS: u64 = 10_000_000;

/// Whose rules apply where the controllers differ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Dialect {
    /// Seed 002's MachineMotion path following: `G92` zeroes the axes it does not name, tool
    /// offsets apply from `M6` on, parentheses nest inside comments. The default.
    #[default]
    MachineMotion,
    /// Mach4 (the alignment plug-in's controller): `G92` keeps the axes it does not name, tool
    /// length offsets apply from `G43` only, comments end at the first `)`.
    Mach4,
    /// LinuxCNC 2.9: as Mach4, and `G68`/`G69`/`G51`/`G50` (which LinuxCNC does not have) are
    /// refused.
    LinuxCnc,
}

impl Dialect {
    /// The highest numbered parameter: LinuxCNC 2.9's 5601 (`RS274NGC_MAX_PARAMETERS` is 5602,
    /// indices below it); 9999 for Mach4 and seed 002, the range the pound-variable block of
    /// the seed's profile assumes (no source here gives Mach4 a smaller one).
    #[must_use]
    pub const fn last_parameter(self) -> u32 {
        match self {
            Dialect::LinuxCnc => 5601,
            Dialect::MachineMotion | Dialect::Mach4 => 9999,
        }
    }

    /// Every dialect.
    pub const ALL: [Dialect; 3] = [Dialect::MachineMotion, Dialect::Mach4, Dialect::LinuxCnc];

    /// The dialect called `name` ([`Dialect::name`]), if any.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Dialect> {
        Dialect::ALL.into_iter().find(|d| d.name() == name)
    }

    /// The tool offset the placement subtracts from a work point (X, Y) and adds (Z), from the
    /// tool table's entry `table`: the entry itself, except that LinuxCNC *adds* a tool's X/Y
    /// table offset to a programmed point, as it does its length (`machine = … + tool`). Its
    /// own inverse.
    #[must_use]
    pub fn applied_tool_offset(self, table: Xyz) -> Xyz {
        match self {
            Dialect::LinuxCnc => Xyz::new(-table.x, -table.y, table.z),
            Dialect::MachineMotion | Dialect::Mach4 => table,
        }
    }

    /// Its name on the command line: `machinemotion`, `mach4`, `linuxcnc`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Dialect::MachineMotion => "machinemotion",
            Dialect::Mach4 => "mach4",
            Dialect::LinuxCnc => "linuxcnc",
        }
    }
}

/// Set-up of an [`crate::Interpreter`].
#[derive(Debug, Clone, PartialEq)]
pub struct InterpreterConfig {
    /// The unit of machine coordinates, of every event, of the offset parameters and of the
    /// tool table. Default inch (the manual's machine is an inch router).
    pub machine_unit: LengthUnit,
    /// G20/G21 in force when the interpreter starts (and after M2/M30). Default: the machine
    /// unit.
    pub initial_units: LengthUnit,
    /// G61/G64 in force at start. Default G64 with no tolerance (LinuxCNC's default).
    pub initial_path_mode: PathMode,
    /// Feed (machine units per minute) used by feed moves before any `F`. `None` (the default)
    /// makes such a move an error, as on a real control.
    pub default_feed: Option<f64>,
    /// Largest distance (machine units) between an arc and the polyline that replaces it
    /// under non-uniform G51 scaling (or a G18/G19 arc under G68 or G51).
    pub chord_tolerance: f64,
    /// Most polyline segments one arc may become.
    pub max_arc_segments: u64,
    /// The M-codes passed to the handler. Default M100–M999. The built-in codes (M0–M6, M30)
    /// win over this range.
    pub user_mcodes: RangeInclusive<u32>,
    /// The tool table at start. Default: tools 1–254 with zero offsets and no outputs. The
    /// interpreter keeps this one copy up to date: its `config().tools` is the live table, the
    /// same as [`crate::Interpreter::tools`].
    pub tools: ToolTable,
    /// The block-delete switch: when on, lines starting with `/` are skipped; when off (the
    /// default, as on the controllers) the `/` is ignored and the line runs.
    pub block_delete: bool,
    /// Whose rules apply where the controllers differ. Default [`Dialect::MachineMotion`].
    pub dialect: Dialect,
    /// Folders searched, in order, for `name.ngc` when `o<name> call` names a subroutine the
    /// program does not define (LinuxCNC's `SUBROUTINE_PATH`). Default: none.
    pub subroutine_path: Vec<PathBuf>,
    /// Most loop iterations (`while`, `do`, `repeat`, `continue`) one run may make, so that a
    /// runaway loop ends with an error rather than hanging. Default 10 million.
    pub max_loop_iterations: u64,
}

impl Default for InterpreterConfig {
    fn default() -> Self {
        InterpreterConfig::new(LengthUnit::Inch)
    }
}

impl InterpreterConfig {
    /// Defaults for a machine whose coordinates are in `machine_unit`.
    #[must_use]
    pub fn new(machine_unit: LengthUnit) -> InterpreterConfig {
        InterpreterConfig {
            machine_unit,
            initial_units: machine_unit,
            initial_path_mode: PathMode::Blend { tolerance: None },
            default_feed: None,
            chord_tolerance: match machine_unit {
                LengthUnit::Inch => CHORD_TOLERANCE_INCH,
                LengthUnit::Millimetre => CHORD_TOLERANCE_MM,
            },
            max_arc_segments: MAX_ARC_SEGMENTS,
            user_mcodes: 100..=999,
            tools: ToolTable::numbered(1, 254),
            block_delete: false,
            dialect: Dialect::MachineMotion,
            subroutine_path: Vec::new(),
            max_loop_iterations: 10_000_000,
        }
    }
}
