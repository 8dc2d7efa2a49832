//! The tool table: offsets and the digital outputs a tool is wired to (seed 002).

use std::collections::BTreeMap;

use crate::event::{OutputWrite, SpindleCommand};
use crate::geom::Xyz;

/// One digital output and the level that means "active" (seed 002's `DIGITAL_OUTPUT_STATE`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct DigitalOutput {
    /// Digital I/O module device id.
    pub device: u32,
    /// Port on the device.
    pub port: u32,
    /// Level written to activate it (`true` = high); the opposite level deactivates it.
    pub active_high: bool,
}

impl DigitalOutput {
    /// The write that drives this output active (`true`) or inactive (`false`).
    #[must_use]
    pub fn write(self, active: bool) -> OutputWrite {
        OutputWrite { device: self.device, port: self.port, high: active == self.active_high }
    }
}

/// The outputs that turn a tool clockwise and counter-clockwise (seed 002's `TOOL`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ToolOutputs {
    /// Activated by M3.
    pub clockwise: DigitalOutput,
    /// Activated by M4.
    pub counter_clockwise: DigitalOutput,
}

impl ToolOutputs {
    /// The writes `command` makes, in order. M3/M4 first release the other direction, then
    /// drive the requested one, so both are never active together; M5 releases both.
    #[must_use]
    pub fn writes(self, command: SpindleCommand) -> [OutputWrite; 2] {
        let (cw, ccw) = (self.clockwise, self.counter_clockwise);
        match command {
            SpindleCommand::Clockwise => [ccw.write(false), cw.write(true)],
            SpindleCommand::CounterClockwise => [cw.write(false), ccw.write(true)],
            SpindleCommand::Stop => [cw.write(false), ccw.write(false)],
        }
    }
}

/// One tool-table entry.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Tool {
    /// `x`, `y`: where the tool's point is relative to the spindle, machine units (commanding P
    /// puts the tool at P and the spindle at P − (x, y)); `z`: the tool length, machine units,
    /// positive for a tip below the spindle's gauge line (commanding Z puts the tip at Z and the
    /// spindle at Z + length).
    pub offset: Xyz,
    /// Outputs driven by M3/M4/M5; `None` when the tool is not wired to outputs.
    pub outputs: Option<ToolOutputs>,
}

/// The tool table. Tool 0 means "no tool" and is always present with zero offsets.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ToolTable {
    tools: BTreeMap<u32, Tool>,
}

impl ToolTable {
    /// An empty table (only tool 0).
    #[must_use]
    pub fn new() -> ToolTable {
        ToolTable::default()
    }

    /// Tools `first..=last` with zero offsets and no outputs.
    #[must_use]
    pub fn numbered(first: u32, last: u32) -> ToolTable {
        ToolTable { tools: (first..=last).map(|n| (n, Tool::default())).collect() }
    }

    /// Adds or replaces tool `number` (tool 0 cannot be replaced).
    pub fn insert(&mut self, number: u32, tool: Tool) {
        if number != 0 {
            self.tools.insert(number, tool);
        }
    }

    /// Builder form of [`ToolTable::insert`].
    #[must_use]
    pub fn with(mut self, number: u32, tool: Tool) -> ToolTable {
        self.insert(number, tool);
        self
    }

    /// Tool `number`, if it is in the table.
    #[must_use]
    pub fn get(&self, number: u32) -> Option<Tool> {
        if number == 0 {
            Some(Tool::default())
        } else {
            self.tools.get(&number).copied()
        }
    }

    /// Mutable access to tool `number` (not tool 0).
    pub(crate) fn get_mut(&mut self, number: u32) -> Option<&mut Tool> {
        self.tools.get_mut(&number)
    }

    /// The defined tool numbers (without 0), ascending.
    pub fn numbers(&self) -> impl Iterator<Item = u32> + '_ {
        self.tools.keys().copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn w(device: u32, port: u32, high: bool) -> OutputWrite {
        OutputWrite { device, port, high }
    }

    #[test]
    fn m3_m4_m5_release_the_other_direction_first_and_honour_active_low() {
        // Seed 002: clockwise = DIGITAL_OUTPUT_STATE(1, 0, 1), counterClockwise = (1, 1, 1).
        let out = |port, active_high| DigitalOutput { device: 1, port, active_high };
        let seed = ToolOutputs { clockwise: out(0, true), counter_clockwise: out(1, true) };
        assert_eq!(seed.writes(SpindleCommand::Clockwise), [w(1, 1, false), w(1, 0, true)]);
        assert_eq!(seed.writes(SpindleCommand::CounterClockwise), [w(1, 0, false), w(1, 1, true)]);
        assert_eq!(seed.writes(SpindleCommand::Stop), [w(1, 0, false), w(1, 1, false)]);
        // Active low: driven low to switch on, high to switch off.
        let low = ToolOutputs { clockwise: out(0, false), counter_clockwise: out(1, false) };
        assert_eq!(low.writes(SpindleCommand::Clockwise), [w(1, 1, true), w(1, 0, false)]);
        assert_eq!(low.writes(SpindleCommand::Stop), [w(1, 0, true), w(1, 1, true)]);
    }
}
