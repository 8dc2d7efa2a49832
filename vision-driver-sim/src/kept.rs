//! [`KeptState`]: what a controller keeps between sessions, so a simulated machine started
//! again is the machine that was left.
//!
//! A real controller keeps its tool table (Mach4's tool table, LinuxCNC's `tool.tbl`) and its
//! stored positions and work offsets (Mach4's fixture table, LinuxCNC's var file): a camera
//! offset written by M283 C1 is still there in the next session, and the calibration made with
//! it stays right. Kept here: every tool's X/Y offset and length, the G28 and G30 positions
//! (`#5161`–`#5163`, `#5181`–`#5183`) and the origins and XY rotations of G54–G59 (`#5221`…).
//! Decision: the G92 offset is not kept (Mach4 clears it; LinuxCNC keeps it only by a setting,
//! and a program that relies on G92 sets it), nor is anything modal.
//!
//! Lengths are in the machine unit `unit`; a kept state of another unit is converted.

use serde::{Deserialize, Serialize};
use vision_gcode::params::{G28_POSITION, G30_POSITION, WORK_OFFSET_BASE, WORK_OFFSET_STRIDE, WORK_ROTATION};
use vision_gcode::{Tool, Xyz};
use vision_math::LengthUnit;

use crate::error::SimError;
use crate::machine::SimMachine;

/// The largest kept file read, bytes (a tool table of thousands of tools fits many times).
pub const MAX_KEPT_BYTES: usize = 1 << 20;

/// One kept tool: its number and its table entry (X/Y offset, Z length), machine units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeptTool {
    /// Tool number, 1 or more.
    pub number: u32,
    /// X/Y offset and Z length as the table holds them, `unit`.
    pub offset: [f64; 3],
}

/// One kept parameter: its number and value (lengths in `unit`, rotations in degrees).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeptParameter {
    /// The parameter's number (`#5221`).
    pub number: u32,
    /// Its value.
    pub value: f64,
}

/// What a controller keeps between sessions (see the module doc).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeptState {
    /// The unit of every length: `in` or `mm`.
    pub unit: String,
    /// The tool table.
    #[serde(default, rename = "tool")]
    pub tools: Vec<KeptTool>,
    /// The stored positions and work offsets.
    #[serde(default, rename = "parameter")]
    pub parameters: Vec<KeptParameter>,
}

/// The kept parameters' numbers, and whether each is a length (else an angle in degrees).
fn kept_numbers() -> impl Iterator<Item = (u32, bool)> {
    let positions = [G28_POSITION, G30_POSITION].into_iter().flat_map(|base| (base..base + 3).map(|n| (n, true)));
    let systems = (0..6u32).flat_map(|i| {
        let base = WORK_OFFSET_BASE + WORK_OFFSET_STRIDE * i;
        (base..base + 3).map(|n| (n, true)).chain(std::iter::once((WORK_ROTATION + WORK_OFFSET_STRIDE * i, false)))
    });
    positions.chain(systems)
}

fn unit_named(name: &str) -> Result<LengthUnit, SimError> {
    match name {
        "in" => Ok(LengthUnit::Inch),
        "mm" => Ok(LengthUnit::Millimetre),
        other => Err(SimError::Kept { reason: format!("unit must be \"in\" or \"mm\", not {other:?}") }),
    }
}

impl KeptState {
    /// Reads a kept state from TOML text.
    ///
    /// # Errors
    /// [`SimError::Kept`] for text that is not such a file, an unknown unit, tool 0, a
    /// parameter that is not kept, or a non-finite number.
    pub fn from_toml(text: &str) -> Result<KeptState, SimError> {
        if text.len() > MAX_KEPT_BYTES {
            return Err(SimError::Kept { reason: format!("the file is over {MAX_KEPT_BYTES} bytes") });
        }
        let kept: KeptState = toml::from_str(text).map_err(|e| SimError::Kept { reason: e.to_string() })?;
        unit_named(&kept.unit)?;
        for t in &kept.tools {
            if t.number == 0 || !t.offset.iter().all(|v| v.is_finite() && v.abs() <= vision_gcode::MAX_COORDINATE) {
                return Err(SimError::Kept {
                    reason: format!(
                        "tool {} must be a tool number of 1 or more with finite offsets within the machine's range",
                        t.number
                    ),
                });
            }
        }
        for p in &kept.parameters {
            if !kept_numbers().any(|(n, _)| n == p.number) || !p.value.is_finite() {
                return Err(SimError::Kept {
                    reason: format!(
                        "parameter {} is not a kept parameter (G28/G30 positions, G54–G59 origins and rotations) \
                         or not finite",
                        p.number
                    ),
                });
            }
        }
        Ok(kept)
    }

    /// The TOML text of this state, with a comment saying what it is.
    ///
    /// # Errors
    /// [`SimError::Kept`] if it cannot be serialized (it always can).
    pub fn to_toml(&self) -> Result<String, SimError> {
        let body = toml::to_string(self).map_err(|e| SimError::Kept { reason: e.to_string() })?;
        Ok(format!(
            "# mach-vision: the simulated machine's kept state (its tool table and stored offsets), \
             kept beside the profile as a controller keeps them between sessions.\n{body}"
        ))
    }
}

impl SimMachine {
    /// What this machine's controller would keep now (see [`KeptState`]).
    #[must_use]
    pub fn kept_state(&self) -> KeptState {
        let interp = self.interpreter();
        let tools = interp
            .tools()
            .numbers()
            .filter_map(|n| {
                interp.tools().get(n).map(|t| KeptTool { number: n, offset: [t.offset.x, t.offset.y, t.offset.z] })
            })
            .collect();
        let parameters = kept_numbers().map(|(n, _)| KeptParameter { number: n, value: interp.param(n) }).collect();
        KeptState { unit: interp.machine_unit().short_name().to_string(), tools, parameters }
    }

    /// Puts `kept` back: each kept tool's offsets (tools only in the world keep the world's),
    /// and the kept parameters. The machine stays where it is.
    ///
    /// # Errors
    /// [`SimError::Kept`] for an unknown unit; [`SimError::Machine`] when the interpreter
    /// refuses a value (the machine may then hold part of it: build a new one).
    pub fn restore(&mut self, kept: &KeptState) -> Result<(), SimError> {
        let factor = unit_named(&kept.unit)?.factor_to(self.interpreter().machine_unit());
        let interp = self.interpreter_mut();
        for t in &kept.tools {
            let outputs = interp.tools().get(t.number).and_then(|old| old.outputs);
            let offset = Xyz::new(t.offset[0] * factor, t.offset[1] * factor, t.offset[2] * factor);
            interp.set_tool(t.number, Tool { offset, outputs });
        }
        for p in &kept.parameters {
            let length = kept_numbers().any(|(n, is_length)| n == p.number && is_length);
            let value = if length { p.value * factor } else { p.value };
            interp.set_param(p.number, value).map_err(|e| SimError::Machine { reason: e.to_string() })?;
        }
        Ok(())
    }
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;
    use crate::{Sim, World};

    fn machine() -> SimMachine {
        SimMachine::new(&Sim::new(World::default_world()).expect("sim")).expect("machine")
    }

    #[test]
    fn a_kept_state_round_trips_through_toml_and_restores_the_tool_table_and_offsets() {
        let mut m = machine();
        m.interpreter_mut().set_tool_offset(98, -3.1, 1.9).expect("tool");
        m.interpreter_mut().set_param(WORK_OFFSET_BASE + WORK_OFFSET_STRIDE, 4.5).expect("G55 X");
        let text = m.kept_state().to_toml().expect("toml");
        let kept = KeptState::from_toml(&text).expect("parse");
        assert_eq!(kept, m.kept_state());

        let mut fresh = machine();
        assert_ne!(fresh.interpreter().tool_offset(98), m.interpreter().tool_offset(98));
        fresh.restore(&kept).expect("restore");
        assert_eq!(fresh.interpreter().tool_offset(98), m.interpreter().tool_offset(98));
        assert_eq!(fresh.interpreter().param(WORK_OFFSET_BASE + WORK_OFFSET_STRIDE), 4.5);
        assert_eq!(fresh.kept_state(), m.kept_state());
    }

    #[test]
    fn a_kept_state_in_millimetres_is_converted_to_the_machines_inches() {
        let kept = KeptState {
            unit: "mm".into(),
            tools: vec![KeptTool { number: 98, offset: [25.4, -50.8, 0.0] }],
            parameters: vec![KeptParameter { number: WORK_OFFSET_BASE, value: 254.0 }],
        };
        let mut m = machine();
        m.restore(&kept).expect("restore");
        let t = m.interpreter().tools().get(98).expect("tool 98");
        assert!((t.offset.x - 1.0).abs() < 1e-12 && (t.offset.y + 2.0).abs() < 1e-12);
        assert!((m.interpreter().param(WORK_OFFSET_BASE) - 10.0).abs() < 1e-12);
    }

    #[test]
    fn bad_kept_files_are_refused_with_what_is_wrong() {
        let cases = [
            ("unit = \"ft\"\n", "unit"),
            ("unit = \"in\"\n[[tool]]\nnumber = 0\noffset = [0.0, 0.0, 0.0]\n", "tool 0"),
            ("unit = \"in\"\n[[tool]]\nnumber = 3\noffset = [nan, 0.0, 0.0]\n", "tool 3"),
            ("unit = \"in\"\n[[parameter]]\nnumber = 5400\nvalue = 1.0\n", "parameter 5400"),
            ("unit = \"in\"\nextra = 1\n", "unknown field"),
            ("not toml", "kept machine state"),
        ];
        for (text, what) in cases {
            let e = KeptState::from_toml(text).expect_err(text).to_string();
            assert!(e.contains(what), "{text:?}: {e}");
        }
        let huge = "#".repeat(MAX_KEPT_BYTES + 1);
        assert!(KeptState::from_toml(&huge).is_err());
    }

    #[test]
    fn the_kept_parameters_are_the_stored_positions_and_the_six_systems() {
        let numbers: Vec<u32> = kept_numbers().map(|(n, _)| n).collect();
        let mut want = vec![5161, 5162, 5163, 5181, 5182, 5183];
        for i in 0..6 {
            want.extend([5221 + 20 * i, 5222 + 20 * i, 5223 + 20 * i, 5230 + 20 * i]);
        }
        assert_eq!(numbers, want);
        assert!(kept_numbers().all(|(n, length)| length == (n % 20 != 10)), "rotations are angles");
    }

    #[test]
    fn a_kept_file_of_exactly_the_bound_is_read_and_an_offset_beyond_the_machines_range_refused() {
        let body = "unit = \"in\"\n";
        let padded = format!("{body}#{}\n", "x".repeat(MAX_KEPT_BYTES - body.len() - 2));
        assert_eq!(padded.len(), MAX_KEPT_BYTES);
        KeptState::from_toml(&padded).expect("at the bound");
        let far = "unit = \"in\"\n[[tool]]\nnumber = 3\noffset = [1e300, 0.0, 0.0]\n";
        assert!(KeptState::from_toml(far).expect_err("beyond").to_string().contains("tool 3"));
    }
}
