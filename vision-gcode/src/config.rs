//! How the interpreter is set up: machine unit, start-up modes, tolerances, tools, user M-codes.

use std::ops::RangeInclusive;
use std::path::PathBuf;

use vision_math::LengthUnit;

pub use crate::dialect::Dialect;
use crate::dialect::DialectRules;
use crate::event::PathMode;
use crate::tools::ToolTable;

/// Default chord tolerance for arcs turned into polylines: 0.0001 in.
pub const CHORD_TOLERANCE_INCH: f64 = 0.0001;
/// The same tolerance for a millimetre machine: 0.0025 mm.
pub const CHORD_TOLERANCE_MM: f64 = 0.0025;
/// The default limit on polyline segments for one arc.
pub const MAX_ARC_SEGMENTS: u64 = 10_000_000;

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
    /// Whose rules apply where the controllers differ ([`Dialect::rules`]). Default
    /// [`Dialect::MachineMotion`].
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
    /// The rules of its dialect: what the interpreter asks where the controllers differ.
    #[must_use]
    pub const fn rules(&self) -> &'static DialectRules {
        self.dialect.rules()
    }

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
            dialect: Dialect::default(),
            subroutine_path: Vec::new(),
            max_loop_iterations: 10_000_000,
        }
    }
}
