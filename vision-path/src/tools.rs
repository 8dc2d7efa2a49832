//! The follower's tool table (seed 002's `TOOL`s given to `configPathMode`), and how M3/M4/M5
//! become output writes. The outputs and writes are the interpreter's types
//! ([`ToolOutputs`], [`DigitalOutput`], [`OutputWrite`]), and so is the rule for the writes
//! ([`ToolOutputs::writes`]).

use std::collections::BTreeMap;

use vision_gcode::{DigitalOutput, OutputWrite, ToolOutputs};

use crate::input::OutputCommand;
use crate::PathError;

/// The follower's tool table: tool number → the outputs wired to it. Each number appears
/// once (seed 002: "provided each tool has a unique tool number").
///
/// Unlike the interpreter's `vision_gcode::ToolTable` it holds only the wiring (no offsets)
/// and refuses a number given twice; it is what resolves the planner's output events, for
/// segment input and G-code alike.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ToolTable {
    tools: BTreeMap<u32, ToolOutputs>,
}

impl ToolTable {
    /// An empty table.
    pub fn new() -> ToolTable {
        ToolTable::default()
    }

    /// Add tool `number` wired to `outputs`; a number already defined is refused.
    pub fn insert(&mut self, number: u32, outputs: ToolOutputs) -> Result<(), PathError> {
        if self.tools.contains_key(&number) {
            return Err(PathError::BadMapping(format!(
                "tool {number} is defined twice; each tool needs a unique number"
            )));
        }
        self.tools.insert(number, outputs);
        Ok(())
    }

    /// The outputs of tool `number`.
    pub fn get(&self, number: u32) -> Option<&ToolOutputs> {
        self.tools.get(&number)
    }

    /// Every tool's outputs (clockwise, then counter-clockwise, by tool number).
    pub fn outputs(&self) -> impl Iterator<Item = DigitalOutput> + '_ {
        self.tools.values().flat_map(|t| [t.clockwise, t.counter_clockwise])
    }

    /// The writes an output command makes, in order, with `selected` the tool chosen by the
    /// last `T… M6` (what a bare M3/M4/M5 controls; `M3 $n` does not change it). A tool's
    /// writes are [`ToolOutputs::writes`]; an explicit port is driven high by M3/M4 and low
    /// by M5.
    pub fn resolve(
        &self,
        line: usize,
        selected: Option<u32>,
        command: OutputCommand,
    ) -> Result<Vec<OutputWrite>, PathError> {
        match command {
            OutputCommand::Port { device, port, command } => {
                Ok(vec![OutputWrite { device, port, high: command.is_on() }])
            }
            OutputCommand::Tool { tool, command } => {
                let number = tool.or(selected).ok_or(PathError::NoToolSelected { line })?;
                let t = self.get(number).ok_or(PathError::UnknownTool { line, tool: number })?;
                Ok(t.writes(command).to_vec())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use vision_gcode::SpindleCommand;

    use super::*;

    fn seed_tool() -> ToolTable {
        // clockwise = DIGITAL_OUTPUT_STATE(deviceId=1, port=0, value=1)
        // counterClockwise = DIGITAL_OUTPUT_STATE(1, 1, 1); tool1 = TOOL(1, clockwise, counterClockwise)
        let mut t = ToolTable::new();
        let out = |port| DigitalOutput { device: 1, port, active_high: true };
        t.insert(1, ToolOutputs { clockwise: out(0), counter_clockwise: out(1) }).unwrap();
        t
    }

    fn w(device: u32, port: u32, high: bool) -> OutputWrite {
        OutputWrite { device, port, high }
    }

    #[test]
    fn m3_m4_m5_drive_the_seed_tool_like_the_manual_says() {
        let t = seed_tool();
        let m3 = OutputCommand::Tool { tool: Some(1), command: SpindleCommand::Clockwise };
        assert_eq!(t.resolve(5, None, m3).unwrap(), vec![w(1, 1, false), w(1, 0, true)]);
        let m4 = OutputCommand::Tool { tool: None, command: SpindleCommand::CounterClockwise };
        assert_eq!(t.resolve(6, Some(1), m4).unwrap(), vec![w(1, 0, false), w(1, 1, true)]);
        let m5 = OutputCommand::Tool { tool: None, command: SpindleCommand::Stop };
        assert_eq!(t.resolve(7, Some(1), m5).unwrap(), vec![w(1, 0, false), w(1, 1, false)]);
        let explicit = |command| OutputCommand::Port { device: 2, port: 7, command };
        assert_eq!(t.resolve(8, None, explicit(SpindleCommand::Stop)).unwrap(), vec![w(2, 7, false)]);
        assert_eq!(t.resolve(8, None, explicit(SpindleCommand::CounterClockwise)).unwrap(), vec![w(2, 7, true)]);
    }

    #[test]
    fn unknown_and_unselected_tools_and_duplicates_are_refused() {
        let mut t = seed_tool();
        let m3 = |tool| OutputCommand::Tool { tool, command: SpindleCommand::Clockwise };
        assert_eq!(t.resolve(4, None, m3(None)), Err(PathError::NoToolSelected { line: 4 }));
        assert_eq!(t.resolve(4, None, m3(Some(9))), Err(PathError::UnknownTool { line: 4, tool: 9 }));
        let tool = *t.get(1).unwrap();
        assert!(t.insert(1, tool).is_err());
    }
}
