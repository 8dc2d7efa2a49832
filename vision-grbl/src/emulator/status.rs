//! Grbl's status codes (report.h, `STATUS_*`), the `N` of `error:N`.

pub(crate) const EXPECTED_COMMAND_LETTER: u8 = 1;
pub(crate) const BAD_NUMBER_FORMAT: u8 = 2;
pub(crate) const INVALID_STATEMENT: u8 = 3;
pub(crate) const NEGATIVE_VALUE: u8 = 4;
pub(crate) const SETTING_DISABLED: u8 = 5;
pub(crate) const SETTING_STEP_PULSE_MIN: u8 = 6;
pub(crate) const IDLE_ERROR: u8 = 8;
pub(crate) const SYSTEM_GC_LOCK: u8 = 9;
pub(crate) const OVERFLOW: u8 = 11;
pub(crate) const UNSUPPORTED_COMMAND: u8 = 20;
pub(crate) const MODAL_GROUP_VIOLATION: u8 = 21;
pub(crate) const UNDEFINED_FEED_RATE: u8 = 22;
pub(crate) const COMMAND_VALUE_NOT_INTEGER: u8 = 23;
pub(crate) const AXIS_COMMAND_CONFLICT: u8 = 24;
pub(crate) const WORD_REPEATED: u8 = 25;
pub(crate) const NO_AXIS_WORDS: u8 = 26;
pub(crate) const INVALID_LINE_NUMBER: u8 = 27;
pub(crate) const VALUE_WORD_MISSING: u8 = 28;
pub(crate) const UNSUPPORTED_COORD_SYS: u8 = 29;
pub(crate) const G53_INVALID_MOTION_MODE: u8 = 30;
pub(crate) const AXIS_WORDS_EXIST: u8 = 31;
pub(crate) const NO_AXIS_WORDS_IN_PLANE: u8 = 32;
pub(crate) const INVALID_TARGET: u8 = 33;
pub(crate) const ARC_RADIUS_ERROR: u8 = 34;
pub(crate) const NO_OFFSETS_IN_PLANE: u8 = 35;
pub(crate) const UNUSED_WORDS: u8 = 36;
pub(crate) const G43_DYNAMIC_AXIS_ERROR: u8 = 37;
pub(crate) const MAX_VALUE_EXCEEDED: u8 = 38;

/// Grbl's alarm for a reset while in motion (`EXEC_ALARM_ABORT_CYCLE`).
pub(crate) const ALARM_ABORT_CYCLE: u8 = 3;
