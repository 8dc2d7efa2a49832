//! One G-code block, checked and executed as Grbl's `gcode.c` (`gc_execute_line`) does: the
//! same checks in the same order, so the same line gets the same `error:N`.
//!
//! The block updates the parser state at once and returns the [`Op`]s the protocol then runs
//! in order (motion into the planner, buffer syncs, dwells).

use super::status as st;
use super::Flavour;

/// mm per inch (G20).
pub(crate) const INCH: f64 = 25.4;
/// gcode.c: `MAX_LINE_NUMBER`.
pub(crate) const MAX_N: f64 = 10_000_000.0;

/// What a block asks of the planner and the protocol, in order.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Op {
    /// Wait until all queued motion has finished (`protocol_buffer_synchronize`).
    Sync,
    /// A straight move to a machine position (mm) at a rate (mm/min; `None`: rapid).
    Line([f64; 3], Option<f64>),
    /// Wait this long (s), after a sync (`mc_dwell`).
    Dwell(f64),
    /// M0: a feed hold once the buffer is empty.
    Pause,
    /// The work offset changed: the next status report carries `WCO` (`system_flag_wco_change`).
    WcoChanged,
    /// A feedback message, e.g. `Pgm End` after M2/M30.
    Message(&'static str),
}

/// The parser's modal state (`gc_state`), in mm.
#[derive(Debug, Clone)]
pub(crate) struct GcState {
    /// 0, 1, 2, 3 or 80.
    pub(crate) motion: u8,
    /// 0..=5 for G54..G59.
    pub(crate) coord_select: usize,
    /// 0: G17, 1: G18, 2: G19.
    pub(crate) plane: u8,
    pub(crate) inches: bool,
    pub(crate) incremental: bool,
    pub(crate) inverse_time: bool,
    /// 3, 4 or 5.
    pub(crate) spindle: u8,
    pub(crate) mist: bool,
    pub(crate) flood: bool,
    pub(crate) tool: u8,
    pub(crate) feed: f64,
    pub(crate) speed: f64,
    /// The parser's position (mm, machine).
    pub(crate) position: [f64; 3],
    /// The active work offset (G54..G59) (mm).
    pub(crate) coord_system: [f64; 3],
    /// The G92 offset (mm).
    pub(crate) coord_offset: [f64; 3],
    /// The tool length offset on Z (mm).
    pub(crate) tlo: f64,
    /// grblHAL's G51 scale factors and origin.
    pub(crate) scale: Option<([f64; 3], [f64; 3])>,
    /// grblHAL canned cycles: the sticky R (retract plane, mm machine) and Z (depth, mm machine).
    pub(crate) canned: (Option<f64>, Option<f64>),
    /// grblHAL G99: retract to R rather than to the starting Z (G98).
    pub(crate) retract_to_r: bool,
}

/// What survives a reset: G54..G59, G28 and G30 (EEPROM).
#[derive(Debug, Clone, Default)]
pub(crate) struct Stored {
    pub(crate) coords: [[f64; 3]; 6],
    pub(crate) g28: [f64; 3],
    pub(crate) g30: [f64; 3],
}

impl GcState {
    /// `gc_init`: the defaults, at `position`, with G54 loaded from `stored`.
    pub(crate) fn new(position: [f64; 3], stored: &Stored) -> Self {
        Self {
            motion: 0,
            coord_select: 0,
            plane: 0,
            inches: false,
            incremental: false,
            inverse_time: false,
            spindle: 5,
            mist: false,
            flood: false,
            tool: 0,
            feed: 0.0,
            speed: 0.0,
            position,
            coord_system: stored.coords[0],
            coord_offset: [0.0; 3],
            tlo: 0.0,
            scale: None,
            canned: (None, None),
            retract_to_r: false,
        }
    }

    /// The work coordinate offset a status report shows (mm).
    pub(crate) fn wco(&self) -> [f64; 3] {
        let mut w: [f64; 3] = std::array::from_fn(|i| self.coord_system[i] + self.coord_offset[i]);
        w[2] += self.tlo;
        w
    }
}

/// `read_float` (nuts_bolts.c): sign, digits and one point, no exponent. Returns the value and
/// the bytes read.
pub(crate) fn read_float(s: &[u8]) -> Option<(f64, usize)> {
    let mut i = 0;
    let negative = match s.first() {
        Some(b'-') => {
            i += 1;
            true
        }
        Some(b'+') => {
            i += 1;
            false
        }
        _ => false,
    };
    let (mut intval, mut exp, mut digits, mut decimal) = (0u32, 0i32, 0u32, false);
    while let Some(&c) = s.get(i) {
        if c.is_ascii_digit() {
            digits += 1;
            if digits <= 8 {
                if decimal {
                    exp -= 1;
                }
                intval = intval * 10 + u32::from(c - b'0');
            } else if !decimal {
                exp += 1;
            }
        } else if c == b'.' && !decimal {
            decimal = true;
        } else {
            break;
        }
        i += 1;
    }
    if digits == 0 {
        return None;
    }
    let v = f64::from(intval) * 10f64.powi(exp);
    Some((if negative { -v } else { v }, i))
}

/// The value words of a block, as read.
#[derive(Default)]
pub(crate) struct Words {
    pub(crate) f: Option<f64>,
    pub(crate) ijk: [Option<f64>; 3],
    pub(crate) l: Option<f64>,
    pub(crate) n: Option<f64>,
    pub(crate) p: Option<f64>,
    pub(crate) r: Option<f64>,
    pub(crate) s: Option<f64>,
    pub(crate) t: Option<f64>,
    pub(crate) xyz: [Option<f64>; 3],
}

/// `non_modal_command` of gcode.h.
#[derive(Clone, Copy, PartialEq)]
pub(crate) enum NonModal {
    None,
    Dwell,
    SetCoord,
    Home(bool),
    SetHome(bool),
    Offset,
    ResetOffset,
    Absolute,
}

/// `axis_command` of gcode.c.
#[derive(Clone, Copy, PartialEq)]
pub(crate) enum AxisCommand {
    None,
    NonModal,
    Motion,
    ToolLength,
    Scaling,
}

/// Executes one block (uppercase, no spaces or comments). `Err` is Grbl's status code.
#[expect(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    reason = "Grbl keeps a G or M number in a byte and its fraction in a u16 (the wrap is emulated); numbers are checked below 256 before they narrow"
)]
pub(crate) fn execute(
    line: &[u8],
    gc: &mut GcState,
    stored: &mut Stored,
    flavour: Flavour,
    m7: bool,
    arc_tolerance: f64,
) -> Result<Vec<Op>, u8> {
    let byte_numbers = flavour == Flavour::Grbl;
    let mut w = Words::default();
    let mut motion = gc.motion;
    let (mut plane, mut inches, mut incremental, mut inverse_time) =
        (gc.plane, gc.inches, gc.incremental, gc.inverse_time);
    let mut coord_select: Option<usize> = None;
    let (mut spindle, mut mist, mut flood) = (gc.spindle, gc.mist, gc.flood);
    let mut flow: Option<u8> = None;
    let mut non_modal = NonModal::None;
    let mut axis_command = AxisCommand::None;
    let mut tool_length: Option<bool> = None; // Some(true): G43.1, Some(false): G49
    let mut scaling: Option<bool> = None;
    let mut retract_to_r: Option<bool> = None;
    let mut groups = 0u32;
    let mut i = 0;
    // STEP 2: import the words (gcode.c).
    while i < line.len() {
        let letter = line[i];
        if !letter.is_ascii_uppercase() {
            return Err(st::EXPECTED_COMMAND_LETTER);
        }
        i += 1;
        let Some((value, used)) = read_float(&line[i..]) else { return Err(st::BAD_NUMBER_FORMAT) };
        i += used;
        // Grbl keeps the command number in a byte and 100x its fraction in a u16, so M280
        // becomes M24 with a fraction and fails as a non-integer (error:23).
        let (int_value, mut mantissa) = if byte_numbers {
            let int = (value.trunc() as i64) as u8;
            let m = ((100.0 * (value as f32 - f32::from(int))).round() as i64) as u16;
            (u32::from(int), u32::from(m))
        } else {
            let int = value.trunc().clamp(0.0, 1e9) as u32;
            (int, (100.0 * (value - value.trunc())).round().abs() as u32)
        };
        match letter {
            b'G' => {
                let group = match int_value {
                    10 | 28 | 30 | 92 | 4 | 53 => {
                        if matches!(int_value, 10 | 28 | 30 | 92) && mantissa == 0 {
                            if axis_command != AxisCommand::None {
                                return Err(st::AXIS_COMMAND_CONFLICT);
                            }
                            axis_command = AxisCommand::NonModal;
                        }
                        if matches!(int_value, 28 | 30 | 92) {
                            if !(mantissa == 0 || mantissa == 10) {
                                return Err(st::UNSUPPORTED_COMMAND);
                            }
                            let dot = mantissa == 10;
                            mantissa = 0;
                            non_modal = match (int_value, dot) {
                                (28, false) => NonModal::Home(false),
                                (30, false) => NonModal::Home(true),
                                (28, true) => NonModal::SetHome(false),
                                (30, true) => NonModal::SetHome(true),
                                (_, false) => NonModal::Offset,
                                _ => NonModal::ResetOffset,
                            };
                        } else {
                            non_modal = match int_value {
                                4 => NonModal::Dwell,
                                10 => NonModal::SetCoord,
                                _ => NonModal::Absolute,
                            };
                        }
                        0
                    }
                    0..=3 | 80 => {
                        if int_value != 80 {
                            if axis_command != AxisCommand::None {
                                return Err(st::AXIS_COMMAND_CONFLICT);
                            }
                            axis_command = AxisCommand::Motion;
                        }
                        motion = int_value as u8;
                        1
                    }
                    17..=19 => {
                        plane = (int_value - 17) as u8;
                        2
                    }
                    90 | 91 => {
                        if mantissa == 0 {
                            incremental = int_value == 91;
                            3
                        } else {
                            if mantissa != 10 || int_value == 90 {
                                return Err(st::UNSUPPORTED_COMMAND);
                            }
                            mantissa = 0;
                            4
                        }
                    }
                    93 | 94 => {
                        inverse_time = int_value == 93;
                        5
                    }
                    20 | 21 => {
                        inches = int_value == 20;
                        6
                    }
                    40 => 7,
                    43 | 49 => {
                        if axis_command != AxisCommand::None {
                            return Err(st::AXIS_COMMAND_CONFLICT);
                        }
                        axis_command = AxisCommand::ToolLength;
                        if int_value == 49 {
                            tool_length = Some(false);
                        } else if mantissa == 10 {
                            tool_length = Some(true);
                        } else {
                            return Err(st::UNSUPPORTED_COMMAND);
                        }
                        mantissa = 0;
                        8
                    }
                    54..=59 => {
                        coord_select = Some((int_value - 54) as usize);
                        12
                    }
                    61 => {
                        if mantissa != 0 {
                            return Err(st::UNSUPPORTED_COMMAND);
                        }
                        13
                    }
                    // grblHAL (gcode.c): G50/G51 scaling, modal group G11, as built without
                    // MACH3_SCALING (`P` or `I`/`J`/`K` factors about the axis words); a
                    // MACH3_SCALING build (grblHAL's simulator) takes the axis words as factors.
                    // grblHAL: the drilling cycles G81 (drill) and G82 (drill, dwell).
                    81 | 82 if flavour == Flavour::GrblHal => {
                        if axis_command != AxisCommand::None {
                            return Err(st::AXIS_COMMAND_CONFLICT);
                        }
                        axis_command = AxisCommand::Motion;
                        motion = int_value as u8;
                        1
                    }
                    98 | 99 if flavour == Flavour::GrblHal => {
                        retract_to_r = Some(int_value == 99);
                        10
                    }
                    50 | 51 if flavour == Flavour::GrblHal => {
                        axis_command = AxisCommand::Scaling;
                        scaling = Some(int_value == 51);
                        11
                    }
                    _ => return Err(st::UNSUPPORTED_COMMAND),
                };
                if mantissa > 0 {
                    return Err(st::COMMAND_VALUE_NOT_INTEGER);
                }
                if groups & (1 << group) != 0 {
                    return Err(st::MODAL_GROUP_VIOLATION);
                }
                groups |= 1 << group;
            }
            b'M' => {
                if mantissa > 0 {
                    return Err(st::COMMAND_VALUE_NOT_INTEGER);
                }
                let group = match int_value {
                    0 | 1 | 2 | 30 => {
                        if int_value != 1 {
                            flow = Some(int_value as u8);
                        }
                        20
                    }
                    3..=5 => {
                        spindle = int_value as u8;
                        21
                    }
                    7 if m7 => {
                        mist = true;
                        22
                    }
                    8 => {
                        flood = true;
                        22
                    }
                    9 => {
                        mist = false;
                        flood = false;
                        22
                    }
                    _ => return Err(st::UNSUPPORTED_COMMAND),
                };
                if groups & (1 << group) != 0 {
                    return Err(st::MODAL_GROUP_VIOLATION);
                }
                groups |= 1 << group;
            }
            _ => {
                let slot = match letter {
                    b'F' => &mut w.f,
                    b'I' => &mut w.ijk[0],
                    b'J' => &mut w.ijk[1],
                    b'K' => &mut w.ijk[2],
                    b'L' => &mut w.l,
                    b'N' => &mut w.n,
                    b'P' => &mut w.p,
                    b'R' => &mut w.r,
                    b'S' => &mut w.s,
                    b'T' => {
                        if value > 255.0 {
                            return Err(st::MAX_VALUE_EXCEEDED);
                        }
                        &mut w.t
                    }
                    b'X' => &mut w.xyz[0],
                    b'Y' => &mut w.xyz[1],
                    b'Z' => &mut w.xyz[2],
                    _ => return Err(st::UNSUPPORTED_COMMAND),
                };
                if slot.is_some() {
                    return Err(st::WORD_REPEATED);
                }
                if matches!(letter, b'F' | b'N' | b'P' | b'T' | b'S') && value < 0.0 {
                    return Err(st::NEGATIVE_VALUE);
                }
                *slot = Some(if letter == b'L' { f64::from(int_value) } else { value });
            }
        }
    }
    super::block::check_and_run(
        Parsed {
            w,
            motion,
            plane,
            inches,
            incremental,
            inverse_time,
            coord_select,
            spindle,
            mist,
            flood,
            flow,
            non_modal,
            axis_command,
            tool_length,
            scaling,
            retract_to_r,
        },
        gc,
        stored,
        arc_tolerance,
    )
}

/// A block after STEP 2: its words and the modes it asks for.
pub(crate) struct Parsed {
    pub(crate) w: Words,
    pub(crate) motion: u8,
    pub(crate) plane: u8,
    pub(crate) inches: bool,
    pub(crate) incremental: bool,
    pub(crate) inverse_time: bool,
    pub(crate) coord_select: Option<usize>,
    pub(crate) spindle: u8,
    pub(crate) mist: bool,
    pub(crate) flood: bool,
    pub(crate) flow: Option<u8>,
    pub(crate) non_modal: NonModal,
    pub(crate) axis_command: AxisCommand,
    /// `Some(true)`: G43.1, `Some(false)`: G49.
    pub(crate) tool_length: Option<bool>,
    /// `Some(true)`: G51, `Some(false)`: G50 (grblHAL).
    pub(crate) scaling: Option<bool>,
    /// `Some(true)`: G99, `Some(false)`: G98 (grblHAL).
    pub(crate) retract_to_r: Option<bool>,
}
