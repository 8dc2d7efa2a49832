//! Mach4, the manual's controller.

use super::modal_controller;

/// Mach4: M282 aligns with `G51` scale, `G68` rotation about a centre and a `G52` shift; M280
/// cancels with `G69 G50 G52 X0 Y0`. Mach4 does not report the chain it has active, so the
/// module remembers its own M282's. The tool table holds the offset as the module does, and
/// `GcodeExecuteWait` returns after motion, so M281 may re-centre.
#[derive(Debug, Clone, Copy, Default)]
pub struct Mach4;

modal_controller!(Mach4, name = "mach4", title = "Mach4", dialect = "mach4");
