//! Tools on digital outputs (seed 002's `DIGITAL_OUTPUT_STATE` and `TOOL`), and how M3/M4/M5
//! become output writes.

use std::collections::BTreeMap;

use crate::input::{OutputCommand, ToolState};
use crate::PathError;

/// One digital output and the value that means "active" (seed: `DIGITAL_OUTPUT_STATE`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct DigitalOutput {
    /// Digital I/O module device ID.
    pub device: u32,
    /// Port on the module.
    pub port: u32,
    /// The level that drives the tool (`true` = high, 24 V).
    pub value: bool,
}

/// A tool: the outputs for clockwise (M3) and counter-clockwise (M4) rotation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tool {
    /// Pulled active by M3.
    pub clockwise: DigitalOutput,
    /// Pulled active by M4.
    pub counter_clockwise: DigitalOutput,
}

/// One write to a digital output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct OutputWrite {
    /// Digital I/O module device ID.
    pub device: u32,
    /// Port on the module.
    pub port: u32,
    /// The level to drive (`true` = high).
    pub level: bool,
}

impl DigitalOutput {
    fn write(self, active: bool) -> OutputWrite {
        OutputWrite { device: self.device, port: self.port, level: if active { self.value } else { !self.value } }
    }
}

/// The tool table: tool number → its outputs. Each number appears once.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ToolTable {
    tools: BTreeMap<u32, Tool>,
}

impl ToolTable {
    /// An empty table.
    pub fn new() -> ToolTable {
        ToolTable::default()
    }

    /// Add tool `number`; a number already defined is refused.
    pub fn insert(&mut self, number: u32, tool: Tool) -> Result<(), PathError> {
        if self.tools.contains_key(&number) {
            return Err(PathError::BadMapping(format!(
                "tool {number} is defined twice; each tool needs a unique number"
            )));
        }
        self.tools.insert(number, tool);
        Ok(())
    }

    /// The tool with this number.
    pub fn get(&self, number: u32) -> Option<&Tool> {
        self.tools.get(&number)
    }

    /// Every tool's outputs (clockwise, then counter-clockwise, by tool number).
    pub fn outputs(&self) -> impl Iterator<Item = DigitalOutput> + '_ {
        self.tools.values().flat_map(|t| [t.clockwise, t.counter_clockwise])
    }

    /// The writes an output command makes, in order, with `selected` the tool chosen by the
    /// last `T… M6` (what a bare M3/M4/M5 controls; `M3 $n` does not change it). Switching a
    /// tool on first drives its other direction inactive, so both are never active together.
    pub fn resolve(
        &self,
        line: usize,
        selected: Option<u32>,
        command: OutputCommand,
    ) -> Result<Vec<OutputWrite>, PathError> {
        match command {
            OutputCommand::Port { device, port, state } => {
                Ok(vec![OutputWrite { device, port, level: state != ToolState::Off }])
            }
            OutputCommand::Tool { tool, state } => {
                let number = tool.or(selected).ok_or(PathError::NoToolSelected { line })?;
                let t = self.get(number).ok_or(PathError::UnknownTool { line, tool: number })?;
                Ok(match state {
                    ToolState::Clockwise => vec![t.counter_clockwise.write(false), t.clockwise.write(true)],
                    ToolState::CounterClockwise => vec![t.clockwise.write(false), t.counter_clockwise.write(true)],
                    ToolState::Off => vec![t.clockwise.write(false), t.counter_clockwise.write(false)],
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seed_tool() -> ToolTable {
        // clockwise = DIGITAL_OUTPUT_STATE(deviceId=1, port=0, value=1)
        // counterClockwise = DIGITAL_OUTPUT_STATE(1, 1, 1); tool1 = TOOL(1, clockwise, counterClockwise)
        let mut t = ToolTable::new();
        t.insert(
            1,
            Tool {
                clockwise: DigitalOutput { device: 1, port: 0, value: true },
                counter_clockwise: DigitalOutput { device: 1, port: 1, value: true },
            },
        )
        .unwrap();
        t
    }

    fn w(device: u32, port: u32, level: bool) -> OutputWrite {
        OutputWrite { device, port, level }
    }

    #[test]
    fn m3_m4_m5_drive_the_seed_tool_like_the_manual_says() {
        let t = seed_tool();
        let m3 = OutputCommand::Tool { tool: Some(1), state: ToolState::Clockwise };
        assert_eq!(t.resolve(5, None, m3).unwrap(), vec![w(1, 1, false), w(1, 0, true)]);
        let m4 = OutputCommand::Tool { tool: None, state: ToolState::CounterClockwise };
        assert_eq!(t.resolve(6, Some(1), m4).unwrap(), vec![w(1, 0, false), w(1, 1, true)]);
        let m5 = OutputCommand::Tool { tool: None, state: ToolState::Off };
        assert_eq!(t.resolve(7, Some(1), m5).unwrap(), vec![w(1, 0, false), w(1, 1, false)]);
        let explicit = |state| OutputCommand::Port { device: 2, port: 7, state };
        assert_eq!(t.resolve(8, None, explicit(ToolState::Off)).unwrap(), vec![w(2, 7, false)]);
        assert_eq!(t.resolve(8, None, explicit(ToolState::CounterClockwise)).unwrap(), vec![w(2, 7, true)]);
    }

    #[test]
    fn an_active_low_output_is_driven_low_to_switch_on() {
        let mut t = ToolTable::new();
        let out = |port| DigitalOutput { device: 3, port, value: false };
        t.insert(2, Tool { clockwise: out(0), counter_clockwise: out(1) }).unwrap();
        let m3 = OutputCommand::Tool { tool: Some(2), state: ToolState::Clockwise };
        assert_eq!(t.resolve(1, None, m3).unwrap(), vec![w(3, 1, true), w(3, 0, false)]);
    }

    #[test]
    fn unknown_and_unselected_tools_and_duplicates_are_refused() {
        let mut t = seed_tool();
        let m3 = |tool| OutputCommand::Tool { tool, state: ToolState::Clockwise };
        assert_eq!(t.resolve(4, None, m3(None)), Err(PathError::NoToolSelected { line: 4 }));
        assert_eq!(t.resolve(4, None, m3(Some(9))), Err(PathError::UnknownTool { line: 4, tool: 9 }));
        let tool = *t.get(1).unwrap();
        assert!(t.insert(1, tool).is_err());
    }
}
