//! The codes that move the program frame, never the machine: G10, G92, G52, G68, G51.

use vision_math::Point2;

use super::line::{in_range, LineRun};
use super::modal::{system_rotation, work_offset_base, SYSTEMS};
use crate::error::RunProblem;
use crate::frame::{Placement, SystemRotation};
use crate::geom::{Xyz, AXIS_LETTERS};
use crate::params::work_rotation;
use crate::params::G92_OFFSET;
use crate::words::whole;

/// The largest G68 rotation, degrees: one turn. More says nothing a smaller angle does not, and
/// a huge angle (R1e300) has lost every digit that gave it a direction.
const MAX_ROTATION_DEGREES: f64 = 360.0;
/// The magnitudes a G51 factor may have: a factor of 1000 either way is far beyond any
/// alignment correction or drawing scale.
const SCALE_RANGE: std::ops::RangeInclusive<f64> = 1e-3..=1e3;

impl LineRun<'_> {
    /// Which axis words are on the line (without claiming them); at least one is required.
    pub(super) fn given_axes(&self, owner: &'static str) -> Result<[bool; 3], RunProblem> {
        let given = AXIS_LETTERS.map(|l| self.w.has(l));
        if given.iter().any(|g| *g) {
            Ok(given)
        } else if let Some(&letter) = b"ABCUVW".iter().find(|&&l| self.w.has(l)) {
            Err(RunProblem::AxisNotSupported { letter: char::from(letter) })
        } else {
            Err(RunProblem::NoAxisWords { code: owner })
        }
    }

    /// The given axis words (absolute, converted to machine units), with the current program
    /// coordinate for the others; and which were given.
    pub(super) fn absolute_point(&mut self, owner: &'static str) -> Result<(Xyz, [bool; 3]), RunProblem> {
        let given = self.given_axes(owner)?;
        let mut p = self.st.program;
        for (axis, &letter) in AXIS_LETTERS.iter().enumerate() {
            if let Some(v) = self.length(letter, owner)? {
                p.set_axis(axis, v);
            }
        }
        Ok((p, given))
    }

    #[expect(
        clippy::cast_possible_truncation,
        clippy::float_cmp,
        reason = "L words are whole numbers, exact in f64; an unchanged rotation is the same value"
    )]
    pub(super) fn g10(&mut self) -> Result<(), RunProblem> {
        let l = self.require(
            b'L',
            "G10",
            "L2 sets a coordinate system's origin, L20 makes the current point read the given values",
        )?;
        if l != 2.0 && l != 20.0 {
            return Err(RunProblem::G10Form { l });
        }
        let p = self.require(b'P', "G10", "the coordinate system, P1 (G54) to P6 (G59), or P0 for the active one")?;
        let mut system = whole(b'P', p)?;
        if system > SYSTEMS {
            return Err(RunProblem::OutOfRange {
                code: "G10",
                letter: 'P',
                value: p,
                hint: "P0 (active system) to P6 (G59); G59.1-G59.3 are not supported",
            });
        }
        if system == 0 {
            system = self.st.system;
        }
        let base = work_offset_base(system);
        let rotation = self.g10_rotation(l)?;
        let before = (self.placement(), self.st.rotation);
        let any_axis = AXIS_LETTERS.iter().any(|&l| self.w.has(l));
        // `G10 L2 P0 R30` (LinuxCNC) or `G10 L2 P1 R0` (the others) may come without origin words.
        if any_axis || rotation.is_none() {
            let (v, given) = self.absolute_point("G10")?;
            if l == 2.0 {
                for axis in (0..3).filter(|&a| given[a]) {
                    self.params.set(base + axis as u32, v.axis(axis));
                }
            } else if self.cfg.rules().carries_current_point {
                self.l20_origin(system, v, given)?;
                if system == self.st.system {
                    self.st.load_system(self.cfg, self.params);
                    self.st.program = self.rotated_current(before.0, before.1);
                }
                return Ok(());
            } else {
                let origin = self.origin_reading(v, system_rotation(self.cfg, self.params, system));
                for axis in (0..3).filter(|&a| given[a]) {
                    let value = in_range(origin.axis(axis), || {
                        format!("the G10 L20 origin's {}", char::from(AXIS_LETTERS[axis]))
                    })?;
                    self.params.set(base + axis as u32, value);
                }
            }
            if system == self.st.system && l == 20.0 {
                self.st.load_system(self.cfg, self.params);
                self.st.rederive_program(self.params);
                self.keep_given(v, given);
                return Ok(());
            }
        }
        if let Some(r) = rotation.filter(|_| self.cfg.rules().rotated_systems) {
            self.params.set(work_rotation(system), r);
        }
        if system == self.st.system {
            self.st.load_system(self.cfg, self.params);
            // rs274 moves its current point by the change (rotated_current) whether or not the
            // rotation changed; the others have no rotation and re-derive it.
            if self.st.rotation == before.1 && !self.cfg.rules().carries_current_point {
                self.st.rederive_program(self.params);
            } else {
                self.st.program = self.rotated_current(before.0, before.1);
            }
        }
        Ok(())
    }

    /// `G10 … R`: LinuxCNC's rotation of the system (degrees, counter-clockwise; L2 only).
    /// Mach4 and seed 002 rotate with G68: there only `R0` is accepted, and it does nothing.
    #[expect(clippy::float_cmp, reason = "L words are whole numbers, exact in f64")]
    fn g10_rotation(&mut self, l: f64) -> Result<Option<f64>, RunProblem> {
        let Some(r) = self.w.take(b'R', "G10")? else { return Ok(None) };
        if !self.cfg.rules().rotated_systems {
            if r != 0.0 {
                return Err(RunProblem::Unsupported {
                    code: "G10 L2 R".into(),
                    feature: "coordinate-system rotation (a LinuxCNC code; Mach4 rotates with G68)",
                });
            }
            return Ok(Some(r));
        }
        if l == 20.0 {
            return Err(RunProblem::G10RotationL20);
        }
        rotation_in_range("G10", r).map(Some)
    }

    /// The current point after a G10 changed the active system's rotation, as rs274 computes it
    /// (interp_convert.cc, `convert_setup`): the old point rotated by the old angle, moved by
    /// the change of origin and rotated back by the new angle, the G92 offset left out. That
    /// differs from the point the machine position reads when a G92/G52 offset is in force;
    /// the next moves go where LinuxCNC sends them.
    fn rotated_current(&self, before: Placement, old_degrees: f64) -> Xyz {
        // G10 changes the origin only: the difference of the summed offsets is the origin's.
        let (old, new) = (before.offset, self.placement().offset);
        let p = self.st.program;
        let turned = SystemRotation::turn(old_degrees, p.xy());
        let moved = Point2::new(turned.x + old.x - new.x, turned.y + old.y - new.y);
        let back = SystemRotation::turn(-self.st.rotation, moved);
        Xyz::new(back.x, back.y, p.z + old.z - new.z)
    }

    /// LinuxCNC's G10 L20 (interp_convert.cc, `convert_setup`): the new origin of `system`
    /// makes the current point, as read in that system, read `v` on the `given` axes. In a
    /// rotated system the wanted and the old point are both rotated into the unrotated frame
    /// first, so both X and Y of the origin change even when one word is given: the point then
    /// reads `v` in the rotated system (changing X alone would move its Y reading too).
    #[expect(clippy::cast_possible_truncation, reason = "axis indices are 0..3")]
    fn l20_origin(&mut self, system: u32, v: Xyz, given: [bool; 3]) -> Result<(), RunProblem> {
        let base = work_offset_base(system);
        let degrees = system_rotation(self.cfg, self.params, system);
        let [ox, oy, oz] = self.params.triple(base);
        let now = self.current_in_system(system);
        let mut wanted = now;
        for axis in (0..3).filter(|&a| given[a]) {
            wanted.set_axis(axis, v.axis(axis));
        }
        let old = SystemRotation::turn(degrees, now.xy());
        let new = SystemRotation::turn(degrees, wanted.xy());
        let origin = Xyz::new(old.x + ox - new.x, old.y + oy - new.y, now.z + oz - wanted.z);
        // Unrotated, an axis without a word keeps its origin exactly (rs274's arithmetic gives
        // it back up to rounding).
        let xy_moves = degrees != 0.0;
        for axis in (0..3).filter(|&a| given[a] || (a < 2 && xy_moves)) {
            let value =
                in_range(origin.axis(axis), || format!("the G10 L20 origin's {}", char::from(AXIS_LETTERS[axis])))?;
            self.params.set(base + axis as u32, value);
        }
        Ok(())
    }

    /// The current point as rs274 reads it in `system` (interp_find.cc,
    /// `find_current_in_system`): with the G92 offset, rotated by the active system's rotation,
    /// moved from the active origin to that system's, rotated back by its rotation, without
    /// the G92 offset.
    pub(super) fn current_in_system(&self, system: u32) -> Xyz {
        let (p, g92, active) = (self.st.program, self.g92_triple(), self.st.origin);
        let [ox, oy, oz] = self.params.triple(work_offset_base(system));
        let turned = SystemRotation::turn(self.st.rotation, Point2::new(p.x + g92.x, p.y + g92.y));
        let moved = Point2::new(turned.x + active.x - ox, turned.y + active.y - oy);
        let back = SystemRotation::turn(-system_rotation(self.cfg, self.params, system), moved);
        Xyz::new(back.x - g92.x, back.y - g92.y, p.z + g92.z + active.z - oz - g92.z)
    }

    /// The origin (G10 L20) that makes the current machine point read program point `v` in a
    /// system rotated by `degrees`, with the active G92 offset and tool.
    fn origin_reading(&self, v: Xyz, degrees: f64) -> Xyz {
        let w = self.placement().work_of(v);
        let g92 = self.g92_triple();
        let unrotated = Placement::offset_summand(self.st.machine - w, g92, self.st.tool_offset);
        match SystemRotation::new(degrees, Xyz::ZERO, g92, self.st.tool_offset) {
            None => unrotated,
            Some(r) => {
                let turned = r.apply(w.xy());
                Xyz::new(self.st.machine.x - turned.x, self.st.machine.y - turned.y, unrotated.z)
            }
        }
    }

    /// The G92 (and, under LinuxCNC, G52) offset, machine units.
    fn g92_triple(&self) -> Xyz {
        let [x, y, z] = self.params.triple(G92_OFFSET);
        Xyz::new(x, y, z)
    }

    /// After an offset was computed to make the current point read `v` on the given axes, take
    /// those coordinates exactly (the re-derived ones differ by rounding only).
    pub(super) fn keep_given(&mut self, v: Xyz, given: [bool; 3]) {
        for axis in (0..3).filter(|&a| given[a]) {
            self.st.program.set_axis(axis, v.axis(axis));
        }
    }

    #[expect(clippy::cast_possible_truncation, reason = "axis indices are 0..3")]
    pub(super) fn g92(&mut self) -> Result<(), RunProblem> {
        let given = self.given_axes("G92")?;
        // Seed 002: an axis without a word gets a zero G92 offset (Mach4 and LinuxCNC keep it).
        // Do that first, so the given axes are computed in the frame that will hold.
        if self.cfg.rules().g92_zeroes_unnamed_axes {
            for axis in (0..3).filter(|&a| !given[a]) {
                self.params.set(G92_OFFSET + axis as u32, 0.0);
            }
        }
        if self.cfg.rules().g52_shares_g92_offset {
            return self.shared_offset("G92");
        }
        self.st.rederive_program(self.params);
        let (v, given) = self.absolute_point("G92")?;
        let w = self.placement().work_of(v);
        let g92 = Placement::offset_summand(self.st.machine - w, self.st.origin, self.st.tool_offset);
        for axis in (0..3).filter(|&a| given[a]) {
            let value = in_range(g92.axis(axis), || format!("the G92 offset's {}", char::from(AXIS_LETTERS[axis])))?;
            self.params.set(G92_OFFSET + axis as u32, value);
        }
        self.st.rederive_program(self.params);
        self.keep_given(v, given);
        Ok(())
    }

    /// LinuxCNC's G92 and G52, which share one offset (#5211-#5213) added to the program point
    /// before the system's rotation (interp_convert.cc, `convert_axis_offsets`). Both work on
    /// the current point, never on the machine position: G92 makes it read the given values
    /// (offset = point + offset − value), G52 sets the offset to the given values (point +=
    /// old offset − value).
    #[expect(clippy::cast_possible_truncation, reason = "axis indices are 0..3")]
    fn shared_offset(&mut self, code: &'static str) -> Result<(), RunProblem> {
        let g52 = code == "G52";
        let (v, given) = self.absolute_point(code)?;
        let old = self.g92_triple();
        for axis in (0..3).filter(|&a| given[a]) {
            let name = || format!("the {code} offset's {}", char::from(AXIS_LETTERS[axis]));
            let p = self.st.program.axis(axis);
            let (offset, point) = if g52 {
                (v.axis(axis), p + old.axis(axis) - v.axis(axis))
            } else {
                (p + old.axis(axis) - v.axis(axis), v.axis(axis))
            };
            self.params.set(G92_OFFSET + axis as u32, in_range(offset, name)?);
            self.st.program.set_axis(axis, point);
        }
        Ok(())
    }

    /// G92.1 / G92.2: the G92 offset back to zero (the program point is re-derived).
    pub(super) fn g92_reset(&mut self) {
        if self.cfg.rules().carries_current_point {
            // rs274 (interp_convert.cc, `convert_axis_offsets`) adds the old offset to the
            // current point: the same as re-deriving it, except where the point no longer
            // reads the machine position (after a rotation change with a G92 offset in force).
            let g92 = self.g92_triple();
            self.st.program = self.st.program + g92;
            for axis in 0..3 {
                self.params.set(G92_OFFSET + axis, 0.0);
            }
            return;
        }
        for axis in 0..3 {
            self.params.set(G92_OFFSET + axis, 0.0);
        }
        self.st.rederive_program(self.params);
    }

    pub(super) fn g52(&mut self) -> Result<(), RunProblem> {
        if self.cfg.rules().g52_shares_g92_offset {
            return self.shared_offset("G52");
        }
        let (v, given) = self.absolute_point("G52")?;
        if given[0] {
            self.st.frame.chain.shift.x = v.x;
        }
        if given[1] {
            self.st.frame.chain.shift.y = v.y;
        }
        if given[2] {
            self.st.frame.local_z = v.z;
        }
        self.st.rederive_program(self.params);
        Ok(())
    }

    pub(super) fn g68(&mut self) -> Result<(), RunProblem> {
        let degrees = self.require(b'R', "G68", "the rotation in degrees, counter-clockwise, e.g. G68 X0 Y0 R30")?;
        let degrees = rotation_in_range("G68", degrees)?;
        // An omitted centre coordinate is the current point's (in the scaled frame), so the
        // machine does not jump.
        let scale = self.st.frame.chain.scale;
        let p = self.st.program;
        let cx = self.length(b'X', "G68")?.unwrap_or(scale.x * p.x);
        let cy = self.length(b'Y', "G68")?.unwrap_or(scale.y * p.y);
        self.st.frame.set_rotation(Point2::new(cx, cy), degrees);
        self.st.rederive_program(self.params);
        Ok(())
    }

    pub(super) fn g51(&mut self) -> Result<(), RunProblem> {
        if self.w.has(b'Z') {
            return Err(RunProblem::ScaleAxis { letter: 'Z' });
        }
        let sx = self.w.take(b'X', "G51")?;
        let sy = self.w.take(b'Y', "G51")?;
        if sx.is_none() && sy.is_none() {
            return Err(RunProblem::NoAxisWords { code: "G51" });
        }
        for (letter, factor) in [('X', sx), ('Y', sy)] {
            match factor {
                Some(0.0) => return Err(RunProblem::ZeroScale { letter }),
                Some(f) if !SCALE_RANGE.contains(&f.abs()) => {
                    return Err(RunProblem::OutOfRange {
                        code: "G51",
                        letter,
                        value: f,
                        hint: "a scale factor's magnitude is 0.001 to 1000 (negative mirrors)",
                    })
                }
                _ => {}
            }
        }
        let scale = &mut self.st.frame.chain.scale;
        scale.x = sx.unwrap_or(scale.x);
        scale.y = sy.unwrap_or(scale.y);
        self.st.rederive_program(self.params);
        Ok(())
    }
}

/// A rotation word (`R`, degrees) of `code` when it is at most one turn either way.
fn rotation_in_range(code: &'static str, degrees: f64) -> Result<f64, RunProblem> {
    if degrees.abs() > MAX_ROTATION_DEGREES {
        return Err(RunProblem::OutOfRange {
            code,
            letter: 'R',
            value: degrees,
            hint: "the rotation is at most one turn, -360 to 360 degrees",
        });
    }
    Ok(degrees)
}
