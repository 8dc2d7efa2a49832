//! How the follower's M3/M4/M5 become output writes. The tool table is the interpreter's
//! ([`ToolTable`]: seed 002's `TOOL`s given to `configPathMode`, one table for the interpreter
//! and the follower); so are the outputs and writes ([`ToolOutputs`], [`DigitalOutput`],
//! [`OutputWrite`]) and the rule for the writes ([`ToolOutputs::writes`]).

#[cfg(doc)]
use vision_gcode::ToolOutputs;
use vision_gcode::{DigitalOutput, OutputWrite, ToolTable};

use crate::input::OutputCommand;
use crate::PathError;

/// Every wired tool's outputs (clockwise, then counter-clockwise, by tool number).
pub(crate) fn outputs(tools: &ToolTable) -> impl Iterator<Item = DigitalOutput> + '_ {
    tools.numbers().filter_map(|n| tools.get(n)?.outputs).flat_map(|t| [t.clockwise, t.counter_clockwise])
}

/// The writes an output command makes, in order, with `selected` the tool chosen by the last
/// `T… M6` (what a bare M3/M4/M5 controls; `M3 $n` does not change it). A tool's writes are
/// [`ToolOutputs::writes`], none for a tool wired to no outputs (as the interpreter does); an
/// explicit port is driven high by M3/M4 and low by M5.
pub(crate) fn resolve(
    tools: &ToolTable,
    line: usize,
    selected: Option<u32>,
    command: OutputCommand,
) -> Result<Vec<OutputWrite>, PathError> {
    match command {
        OutputCommand::Port { device, port, command } => Ok(vec![OutputWrite { device, port, high: command.is_on() }]),
        OutputCommand::Tool { tool, command } => {
            let number = tool.or(selected).ok_or(PathError::NoToolSelected { line })?;
            let t = tools.get(number).ok_or(PathError::UnknownTool { line, tool: number })?;
            Ok(t.outputs.map(|o| o.writes(command).to_vec()).unwrap_or_default())
        }
    }
}

#[cfg(test)]
mod tests {
    use vision_gcode::{SpindleCommand, Tool, ToolOutputs};

    use super::*;

    fn seed_tool() -> ToolTable {
        // clockwise = DIGITAL_OUTPUT_STATE(deviceId=1, port=0, value=1)
        // counterClockwise = DIGITAL_OUTPUT_STATE(1, 1, 1); tool1 = TOOL(1, clockwise, counterClockwise)
        let out = |port| DigitalOutput { device: 1, port, active_high: true };
        let outputs = ToolOutputs { clockwise: out(0), counter_clockwise: out(1) };
        ToolTable::new().with(1, Tool { outputs: Some(outputs), ..Tool::default() })
    }

    fn w(device: u32, port: u32, high: bool) -> OutputWrite {
        OutputWrite { device, port, high }
    }

    #[test]
    fn m3_m4_m5_drive_the_seed_tool_like_the_manual_says() {
        let t = seed_tool();
        let m3 = OutputCommand::Tool { tool: Some(1), command: SpindleCommand::Clockwise };
        assert_eq!(resolve(&t, 5, None, m3).unwrap(), vec![w(1, 1, false), w(1, 0, true)]);
        let m4 = OutputCommand::Tool { tool: None, command: SpindleCommand::CounterClockwise };
        assert_eq!(resolve(&t, 6, Some(1), m4).unwrap(), vec![w(1, 0, false), w(1, 1, true)]);
        let m5 = OutputCommand::Tool { tool: None, command: SpindleCommand::Stop };
        assert_eq!(resolve(&t, 7, Some(1), m5).unwrap(), vec![w(1, 0, false), w(1, 1, false)]);
        let explicit = |command| OutputCommand::Port { device: 2, port: 7, command };
        assert_eq!(resolve(&t, 8, None, explicit(SpindleCommand::Stop)).unwrap(), vec![w(2, 7, false)]);
        assert_eq!(resolve(&t, 8, None, explicit(SpindleCommand::CounterClockwise)).unwrap(), vec![w(2, 7, true)]);
    }

    #[test]
    fn unknown_and_unselected_tools_are_refused_and_an_unwired_tool_writes_nothing() {
        let t = seed_tool().with(2, Tool::default());
        let m3 = |tool| OutputCommand::Tool { tool, command: SpindleCommand::Clockwise };
        assert_eq!(resolve(&t, 4, None, m3(None)), Err(PathError::NoToolSelected { line: 4 }));
        assert_eq!(resolve(&t, 4, None, m3(Some(9))), Err(PathError::UnknownTool { line: 4, tool: 9 }));
        assert_eq!(resolve(&t, 4, None, m3(Some(2))), Ok(Vec::new()));
    }
}
