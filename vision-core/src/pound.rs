//! The pound-variable output block (SPEC §5, manual "Pound-Variable Output").
//!
//! Base B, 5 slots × 8 fields: slot `s` field `f` is `#(B + 8s + f)`. Slot 0 mirrors the latest
//! capture; slots 1–4 hold a run's captures in order. Fields: 0 X, 1 Y (observed point, current
//! units), 2 width, 3 height (current units), 4 angle (degrees), 5 score, 6–7 reserved.
//!
//! Decision: the reserved fields 6 and 7 are never written, so a host or a later version may use
//! them without the module clobbering them.

use crate::error::VisionError;
use crate::machine::Machine;

/// Number of slots (0 = latest, 1–4 = run captures).
pub const SLOTS: u32 = 5;
/// Variables per slot.
pub const FIELDS: u32 = 8;
/// Variables in the block.
pub const BLOCK_LEN: u32 = SLOTS * FIELDS;
/// The lowest allowed base.
pub const MIN_BASE: i64 = 100;
/// The highest numbered variable a supported host has (`#1..#9999` in Mach4; LinuxCNC's rs274
/// stops at #5601, where M280 refuses a block past it): a block past #9999 can never run, so it
/// is refused with the profile, not at the first M280.
pub const MAX_END: i64 = 9999;
/// Ranges the block may not overlap (inclusive): probe results and fixture offsets.
pub const RESERVED: [(i64, i64); 2] = [(5061, 5081), (5201, 5500)];

/// Field 0: observed X, current units.
pub const FIELD_X: u32 = 0;
/// Field 1: observed Y, current units.
pub const FIELD_Y: u32 = 1;
/// Field 2: mark width, current units.
pub const FIELD_WIDTH: u32 = 2;
/// Field 3: mark height, current units.
pub const FIELD_HEIGHT: u32 = 3;
/// Field 4: mark angle, degrees.
pub const FIELD_ANGLE: u32 = 4;
/// Field 5: match score.
pub const FIELD_SCORE: u32 = 5;

/// A validated pound-variable block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PoundBlock {
    base: u32,
}

/// The values one capture writes into a slot (fields 0–5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlotValues {
    /// Observed X, current units.
    pub x: f64,
    /// Observed Y, current units.
    pub y: f64,
    /// Mark width, current units.
    pub width: f64,
    /// Mark height, current units.
    pub height: f64,
    /// Mark angle, degrees.
    pub angle_deg: f64,
    /// Match score.
    pub score: f64,
}

impl PoundBlock {
    /// Validates base `base`: ≥ 100, the 40-variable block `#base..#base+39` outside
    /// 5061..5081 and 5201..5500 and at or below [`MAX_END`].
    ///
    /// # Errors
    /// [`VisionError::PoundBaseReserved`].
    pub fn new(base: i64) -> Result<PoundBlock, VisionError> {
        let end = base.saturating_add(i64::from(BLOCK_LEN) - 1);
        let overlaps = RESERVED.iter().any(|(lo, hi)| base <= *hi && end >= *lo);
        match u32::try_from(base) {
            Ok(b) if base >= MIN_BASE && !overlaps && end <= MAX_END => Ok(PoundBlock { base: b }),
            _ => Err(VisionError::PoundBaseReserved { base, end }),
        }
    }

    /// [`PoundBlock::new`], then checks that the host has the block's first and last variable
    /// (a base that passes the range rules can still run past the end of a machine's variables).
    ///
    /// # Errors
    /// [`VisionError::PoundBaseReserved`], [`VisionError::PoundBlockMissing`].
    pub fn on_machine(base: i64, machine: &dyn Machine) -> Result<PoundBlock, VisionError> {
        let block = PoundBlock::new(base)?;
        let last = block.base + BLOCK_LEN - 1;
        for at in [block.base, last] {
            if let Err(e) = machine.pound(at) {
                return Err(VisionError::PoundBlockMissing {
                    base,
                    end: i64::from(last),
                    reason: e.get_ref().to_string(),
                });
            }
        }
        Ok(block)
    }

    /// The base B.
    #[must_use]
    pub fn base(self) -> u32 {
        self.base
    }

    /// Address of slot `slot` (0–4) field `field` (0–7): `B + 8·slot + field`; `None` when out
    /// of the block.
    #[must_use]
    pub fn address(self, slot: u32, field: u32) -> Option<u32> {
        (slot < SLOTS && field < FIELDS).then(|| self.base + FIELDS * slot + field)
    }

    /// The `(address, value)` writes that store `v` in slot `slot` (fields 0–5); empty when the
    /// slot is out of range.
    #[must_use]
    pub fn slot_writes(self, slot: u32, v: &SlotValues) -> Vec<(u32, f64)> {
        let fields = [
            (FIELD_X, v.x),
            (FIELD_Y, v.y),
            (FIELD_WIDTH, v.width),
            (FIELD_HEIGHT, v.height),
            (FIELD_ANGLE, v.angle_deg),
            (FIELD_SCORE, v.score),
        ];
        fields.iter().filter_map(|(f, val)| self.address(slot, *f).map(|a| (a, *val))).collect()
    }

    /// The whole block as `read` gives each variable now (e.g. `|a| machine.pound(a).ok()`); a
    /// variable it cannot read shows as 0.
    #[must_use]
    pub fn report(self, read: impl Fn(u32) -> Option<f64>) -> PoundReport {
        let slots = (0..SLOTS)
            .map(|s| {
                std::array::from_fn(|f| {
                    self.address(s, u32::try_from(f).unwrap_or(FIELDS)).and_then(&read).unwrap_or(0.0)
                })
            })
            .collect();
        PoundReport { base: self.base, slots }
    }
}

/// The pound-variable block as read back from the machine.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PoundReport {
    /// The base B (`VisionPoundVarBase`).
    pub base: u32,
    /// Slots 0–4, fields 0–7 each (X, Y, width, height, angle, score, reserved, reserved).
    pub slots: Vec<[f64; 8]>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses_follow_the_manual() {
        let b = PoundBlock::new(500).expect("default");
        assert_eq!(b.address(0, 0), Some(500));
        assert_eq!(b.address(1, 0), Some(508));
        assert_eq!(b.address(4, 7), Some(539));
        assert_eq!(b.address(5, 0), None);
        assert_eq!(b.address(0, 8), None);
        let w = b.slot_writes(2, &SlotValues { x: 1.0, y: 2.0, width: 3.0, height: 4.0, angle_deg: 5.0, score: 6.0 });
        assert_eq!(w, vec![(516, 1.0), (517, 2.0), (518, 3.0), (519, 4.0), (520, 5.0), (521, 6.0)]);
    }

    #[test]
    fn reserved_ranges_and_minimum() {
        assert!(PoundBlock::new(100).is_ok());
        assert!(PoundBlock::new(99).is_err());
        assert!(PoundBlock::new(-5).is_err());
        // Block 5021..5060 ends just below the probe range.
        assert!(PoundBlock::new(5021).is_ok());
        assert!(PoundBlock::new(5022).is_err());
        assert!(PoundBlock::new(5081).is_err());
        assert!(PoundBlock::new(5082).is_ok()); // 5082..5121
        assert!(PoundBlock::new(5162).is_err()); // 5162..5201
        assert!(PoundBlock::new(5161).is_ok());
        assert!(PoundBlock::new(5500).is_err());
        assert!(PoundBlock::new(5501).is_ok());
        assert!(PoundBlock::new(i64::MAX).is_err());
        assert_eq!(PoundBlock::new(5041), Err(VisionError::PoundBaseReserved { base: 5041, end: 5080 }));
    }
}
