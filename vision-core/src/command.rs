//! What the Vision module asks the machine to do, as typed commands, not G-code text.
//!
//! The [`crate::Controller`] decides *which* commands an M-code needs (Mach4 cancels and sets
//! the G51/G68/G52 modals; LinuxCNC rotates its work offset and shifts); the machine's bridge
//! runs them, and `vision-mcode` writes each controller's G-code text for them
//! ([`crate::Machine::gcode`]). Every length is in the machine's current units, every angle in
//! degrees counter-clockwise seen from +Z, in the program frame unless a variant says otherwise.

use vision_math::{AlignmentChain, Point2, Vector2};

/// One thing the Vision module asks the machine to do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MachineCommand {
    /// Cancels the whole alignment a controller with scale, rotation and shift modals keeps:
    /// the scale, the rotation and the local shift at once.
    CancelAlignment,
    /// Clears the local shift (sets it to zero on both axes).
    ClearShift,
    /// Sets the local shift added to every programmed point (replaces the one before).
    SetShift(Vector2<f64>),
    /// Sets the rotation modal: `deg` about `centre` (replaces the one before).
    SetRotation {
        /// The centre of rotation, program frame.
        centre: Point2<f64>,
        /// Degrees counter-clockwise.
        deg: f64,
    },
    /// Sets the per-axis scale modal about the program origin (dimensionless factors).
    SetScale(Vector2<f64>),
    /// Sets the active work offset's XY rotation about its origin, degrees counter-clockwise
    /// (a controller without a rotation modal rotates its work offset instead).
    SetWorkRotation {
        /// Degrees counter-clockwise: the rotation the work offset has after the command.
        deg: f64,
    },
    /// A rapid to `target` (program frame, absolute); the distance mode is absolute after it.
    MoveTo(Point2<f64>),
    /// A rapid by `delta` in X/Y (program frame, relative); the distance mode is absolute
    /// after it, as the Vision M-codes expect of a program.
    MoveBy(Vector2<f64>),
    /// A rapid along machine Z by `dz` (relative); the distance mode is absolute after it.
    MoveZBy(f64),
    /// Maps every later move of the program through the chain (program frame → work frame;
    /// replaces the one before), applied by the host that runs the program, not by G-code:
    /// a controller with no alignment modals (Grbl).
    AlignMoves(AlignmentChain),
    /// Stops mapping the program's moves ([`MachineCommand::AlignMoves`] undone).
    CancelMoveAlignment,
}

impl MachineCommand {
    /// The command's name in messages (`SetShift`, …).
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self {
            MachineCommand::CancelAlignment => "CancelAlignment",
            MachineCommand::ClearShift => "ClearShift",
            MachineCommand::SetShift(_) => "SetShift",
            MachineCommand::SetRotation { .. } => "SetRotation",
            MachineCommand::SetScale(_) => "SetScale",
            MachineCommand::SetWorkRotation { .. } => "SetWorkRotation",
            MachineCommand::MoveTo(_) => "MoveTo",
            MachineCommand::MoveBy(_) => "MoveBy",
            MachineCommand::MoveZBy(_) => "MoveZBy",
            MachineCommand::AlignMoves(_) => "AlignMoves",
            MachineCommand::CancelMoveAlignment => "CancelMoveAlignment",
        }
    }

    /// True when every number the command carries is finite (a writer refuses the others).
    #[must_use]
    pub fn is_finite(&self) -> bool {
        let finite = |v: &[f64]| v.iter().all(|v| v.is_finite());
        match *self {
            MachineCommand::CancelAlignment | MachineCommand::ClearShift | MachineCommand::CancelMoveAlignment => true,
            MachineCommand::SetShift(v) | MachineCommand::SetScale(v) | MachineCommand::MoveBy(v) => {
                finite(&[v.x, v.y])
            }
            MachineCommand::SetRotation { centre, deg } => finite(&[centre.x, centre.y, deg]),
            MachineCommand::SetWorkRotation { deg } | MachineCommand::MoveZBy(deg) => deg.is_finite(),
            MachineCommand::MoveTo(p) => finite(&[p.x, p.y]),
            MachineCommand::AlignMoves(c) => {
                finite(&[c.scale.x, c.scale.y, c.center.x, c.center.y, c.rotation_deg, c.shift.x, c.shift.y])
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_command_with_a_non_finite_number_says_so() {
        assert!(MachineCommand::CancelAlignment.is_finite());
        assert!(MachineCommand::MoveBy(Vector2::new(1.0, -2.0)).is_finite());
        assert!(!MachineCommand::MoveTo(Point2::new(0.0, f64::NAN)).is_finite());
        assert!(!MachineCommand::SetRotation { centre: Point2::origin(), deg: f64::INFINITY }.is_finite());
        assert!(!MachineCommand::MoveZBy(f64::NEG_INFINITY).is_finite());
        assert_eq!(MachineCommand::SetWorkRotation { deg: 1.0 }.name(), "SetWorkRotation");
        let mut chain = AlignmentChain::IDENTITY;
        assert!(MachineCommand::AlignMoves(chain).is_finite());
        chain.rotation_deg = f64::NAN;
        assert!(!MachineCommand::AlignMoves(chain).is_finite());
    }
}
