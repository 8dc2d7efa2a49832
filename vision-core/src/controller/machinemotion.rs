//! Seed 002's MachineMotion path interface.

use super::modal_controller;

/// Seed 002's MachineMotion control, with the G-code the vision programs use on it (SPEC §6):
/// the alignment as on Mach4 (`G51`/`G68`/`G52` modals, cancelled by `G69 G50 G52 X0 Y0`,
/// remembered by the module), the tool table holding the module's offset, and moves that finish
/// before the next line, so M281 may re-centre. Its interpreter's rules differ from Mach4's
/// (`G92`, tool offsets from `M6`, nested comments).
#[derive(Debug, Clone, Copy, Default)]
pub struct MachineMotion;

modal_controller!(MachineMotion, name = "machinemotion", title = "MachineMotion", dialect = "machinemotion");
