//! grblHAL's drilling cycles G81 and G82 (gcode.c, `MotionMode_DrillChipBreak` and friends),
//! kept to what a drilling program needs: R and Z sticky between holes, G98 returns to the
//! starting Z (or R if that is higher), G99 to R. Absolute coordinates only: in G91 the R and
//! Z words are taken as offsets from the starting Z, not LinuxCNC's chain of offsets.

use super::gcode::Op;
use super::status as st;

/// The retract plane and depth of a cycle (mm, machine).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Cycle {
    pub(crate) r: f64,
    pub(crate) z: f64,
}

/// Resolves R and Z: given in the block (`r_word`, machine Z already offset) or kept from the
/// last cycle. `Err` is the status code.
pub(crate) fn resolve(r_word: Option<f64>, z_word: Option<f64>, kept: (Option<f64>, Option<f64>)) -> Result<Cycle, u8> {
    match (r_word.or(kept.0), z_word.or(kept.1)) {
        (Some(r), Some(z)) => Ok(Cycle { r, z }),
        _ => Err(st::VALUE_WORD_MISSING),
    }
}

/// The moves of one hole at (`x`, `y`) from `position`; returns them and where the tool ends.
pub(crate) fn hole(
    cycle: Cycle,
    position: [f64; 3],
    xy: (f64, f64),
    feed: f64,
    dwell: Option<f64>,
    retract_to_r: bool,
) -> (Vec<Op>, [f64; 3]) {
    let clear = if retract_to_r { cycle.r } else { position[2].max(cycle.r) };
    let mut ops = Vec::new();
    let mut p = position;
    if p[2] < cycle.r {
        p[2] = cycle.r;
        ops.push(Op::Line(p, None));
    }
    p[0] = xy.0;
    p[1] = xy.1;
    ops.push(Op::Line(p, None));
    p[2] = cycle.r;
    ops.push(Op::Line(p, None));
    p[2] = cycle.z;
    ops.push(Op::Line(p, Some(feed)));
    if let Some(d) = dwell {
        ops.extend([Op::Sync, Op::Dwell(d)]);
    }
    p[2] = clear;
    ops.push(Op::Line(p, None));
    (ops, p)
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;

    #[test]
    fn a_hole_goes_down_at_the_feed_and_back_to_the_clearance() {
        let cycle = resolve(Some(1.0), Some(-3.0), (None, None)).expect("cycle");
        let (ops, end) = hole(cycle, [0.0, 0.0, 5.0], (10.0, 20.0), 100.0, Some(0.5), false);
        assert_eq!(end, [10.0, 20.0, 5.0]);
        assert_eq!(ops[0], Op::Line([10.0, 20.0, 5.0], None));
        assert_eq!(ops[2], Op::Line([10.0, 20.0, -3.0], Some(100.0)));
        assert_eq!(ops[4], Op::Dwell(0.5));
        let (_, end) = hole(cycle, end, (0.0, 0.0), 100.0, None, true);
        assert_eq!(end[2], 1.0, "G99 stays at R");
        assert_eq!(resolve(None, Some(1.0), (None, None)).err(), Some(st::VALUE_WORD_MISSING));
    }
}
