//! Before the first line: the controller's state read and mirrored into the host's interpreter
//! (machine position, G54–G59, G92, G28/G30, the active work system), and the firmware's parser
//! put in the modes the emitted lines assume.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use vision_gcode::params::{G28_POSITION, G30_POSITION, G92_OFFSET, WORK_OFFSET_BASE, WORK_OFFSET_STRIDE};
use vision_gcode::Xyz;
use vision_grbl::codes::describe_alarm;
use vision_grbl::emit::{Emitter, Frame};
use vision_grbl::response::MachineState;
use vision_grbl::stream::Sender;
use vision_math::LengthUnit;

use super::link::{report_unit_mm, stop_tolerance, Link, Units};
use crate::run::Runner;
use crate::Failure;

/// Reads the controller behind `sender`, mirrors it into `session`'s interpreter and returns
/// the link that streams to it.
///
/// # Errors
/// [`Failure::Input`] when the controller cannot run a job now (alarm, busy), holds a tool
/// length offset the host cannot mirror, or does not answer.
pub(crate) fn connect(
    mut sender: Sender,
    port: &str,
    session: &mut Runner,
    interrupted: Arc<AtomicBool>,
) -> Result<Link, Failure> {
    let refused = |what: &str, e: &dyn std::fmt::Display| Failure::Input(format!("{port}: {what}: {e}"));
    let status = sender.status().map_err(|e| refused("no status report", &e))?;
    match status.state {
        Some(MachineState::Idle) => {}
        Some(MachineState::Alarm) => {
            return Err(Failure::Input(format!(
                "{port}: the controller is in alarm{}: home it ($H) or unlock it ($X), then send again",
                sender.last_alarm().map_or_else(String::new, |c| format!(" ({})", describe_alarm(c)))
            )))
        }
        other => {
            return Err(Failure::Input(format!(
                "{port}: the controller is busy ({other:?}): wait until it is Idle, then send again"
            )))
        }
    }
    let settings = sender.settings().map_err(|e| refused("cannot read the settings ($$)", &e))?;
    let mm_per_report_unit = report_unit_mm(&settings);
    let tolerance = stop_tolerance(&settings);
    let offsets = sender.offsets().map_err(|e| refused("cannot read the offsets ($#)", &e))?;
    let parser = sender.parser_state().map_err(|e| refused("cannot read the parser state ($G)", &e))?;
    if offsets.tlo != 0.0 {
        return Err(Failure::Input(format!(
            "{port}: the controller has a tool length offset (G43.1 Z{}): mach-vision applies tool lengths from \
             the host's tool table, so cancel it first (send G49)",
            offsets.tlo
        )));
    }
    let mm = |v: f64| v * mm_per_report_unit;
    let mm_per_unit = session.sim.unit().factor_to(LengthUnit::Millimetre);
    let unit = |v: f64| mm(v) / mm_per_unit;
    let system = parser.work_system.clamp(1, 6);
    // The work offset, report units: the active system's origin plus G92 (no G43.1, refused).
    let active = offsets.work[usize::from(system - 1)];
    let wco_report: [f64; 3] = std::array::from_fn(|i| active[i] + offsets.g92[i]);
    let machine = &mut session.machine;
    let mut mirror = || -> Result<(), vision_driver_sim::SimError> {
        for (s, offset) in (0u32..).zip(offsets.work.iter()) {
            for (axis, v) in (0u32..).zip(offset) {
                machine.set_param(WORK_OFFSET_BASE + WORK_OFFSET_STRIDE * s + axis, unit(*v))?;
            }
        }
        for axis in 0..3 {
            let i = axis as usize;
            machine.set_param(G92_OFFSET + axis, unit(offsets.g92[i]))?;
            machine.set_param(G28_POSITION + axis, unit(offsets.g28[i]))?;
            machine.set_param(G30_POSITION + axis, unit(offsets.g30[i]))?;
        }
        // `$10=0` reports WPos: the machine is there plus the work offset.
        let mpos = status.mpos.unwrap_or_else(|| {
            let w = status.wpos.unwrap_or_default();
            std::array::from_fn(|i| w[i] + wco_report[i])
        });
        machine.set_machine_position(Xyz::new(unit(mpos[0]), unit(mpos[1]), unit(mpos[2])))?;
        let mut ignore = |_: &vision_gcode::Event| {};
        machine
            .context(&mut ignore)
            .execute(&format!("G{}", 53 + u32::from(system)))
            .map_err(|e| vision_driver_sim::SimError::Machine { reason: e.to_string() })
    };
    mirror().map_err(|e| Failure::Input(format!("{port}: the controller's state cannot be mirrored: {e}")))?;
    let wco = wco_report.map(mm);
    let start = session.machine.interpreter().machine_position();
    let frame = Frame { mm_per_unit, wco, work_system: system };
    let emitter = Emitter::new(frame, start).map_err(|e| refused("the machine's position cannot be sent", &e))?;
    let preamble = emitter.preamble();
    let units = Units { mm_per_unit, mm_per_report_unit, tolerance };
    let mut link = Link::new(sender, emitter, units, session.sim.clone(), port.to_string(), interrupted);
    for line in preamble {
        link.push(&line, 0);
    }
    Ok(link)
}
