//! Where a fixture's marks really are.

use vision_core::cal_sheet;
use vision_math::{LengthUnit, Matrix2, Point2, Vector2};

use crate::world::Fixture;

/// Printed diameter of a part fiducial when the world does not say, inches.
const DEFAULT_MARK_DIAMETER_IN: f64 = 0.25;

/// One mark as it really lies on the table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrueMark {
    /// Nominal position, work coordinates, world unit.
    pub nominal: Point2<f64>,
    /// True position, work coordinates, world unit.
    pub position: Point2<f64>,
    /// True printed diameter, world unit (nominal diameter × the fixture's mean scale).
    pub diameter: f64,
    /// True orientation of the printed mark, degrees counter-clockwise.
    pub angle_deg: f64,
}

impl Fixture {
    /// The nominal marks, work coordinates, `unit` (the world's): the sheet's dots first, in
    /// walk order, then [`Fixture::marks`].
    #[must_use]
    pub fn nominal_marks(&self, unit: LengthUnit) -> Vec<Point2<f64>> {
        let mut out = self.sheet.and_then(cal_sheet).map(|s| s.dots(unit)).unwrap_or_default();
        out.extend(self.marks.iter().map(|m| Point2::new(m[0], m[1])));
        out
    }

    /// The pivot of the pose: [`Fixture::center`], else the sheet origin, else the centroid.
    #[must_use]
    pub fn pivot(&self, unit: LengthUnit) -> Point2<f64> {
        if let Some(c) = self.center {
            return Point2::new(c[0], c[1]);
        }
        if self.sheet.is_some() {
            return Point2::origin();
        }
        let marks = self.nominal_marks(unit);
        let n = marks.len().max(1) as f64;
        Point2::from(marks.iter().fold(Vector2::zeros(), |a, m| a + m.coords) / n)
    }

    /// Where nominal work point `p` of this fixture really is (work coordinates, world unit):
    /// `R(rotation)·diag(scale)·(p − pivot) + pivot + shift`.
    #[must_use]
    pub fn true_point(&self, p: Point2<f64>, unit: LengthUnit) -> Point2<f64> {
        let c = self.pivot(unit);
        let (sin, cos) = self.rotation_deg.to_radians().sin_cos();
        let l = Matrix2::new(cos, -sin, sin, cos) * Matrix2::new(self.scale[0], 0.0, 0.0, self.scale[1]);
        c + l * (p - c) + Vector2::from(self.shift)
    }

    /// Every mark as it really lies, in the order of [`Fixture::nominal_marks`].
    #[must_use]
    pub fn true_marks(&self, unit: LengthUnit) -> Vec<TrueMark> {
        let nominal_diameter = self.diameter.unwrap_or_else(|| {
            let inches = self.sheet.and_then(cal_sheet).map_or(DEFAULT_MARK_DIAMETER_IN, |s| s.mark_diameter_in);
            LengthUnit::Inch.convert(inches, unit)
        });
        let diameter = nominal_diameter * (self.scale[0] * self.scale[1]).sqrt();
        self.nominal_marks(unit)
            .into_iter()
            .map(|n| TrueMark {
                nominal: n,
                position: self.true_point(n, unit),
                diameter,
                angle_deg: self.rotation_deg,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::World;
    use approx::assert_relative_eq;

    #[test]
    fn the_demo_target_carries_sheet_one_then_the_example_marks() {
        let w = World::default_world();
        let f = &w.fixtures[0];
        let marks = f.true_marks(LengthUnit::Inch);
        assert_eq!(marks.len(), 15);
        assert_eq!(marks[0].nominal, Point2::new(-2.5, -4.0));
        assert_eq!(marks[4].nominal, Point2::origin());
        // The pivot is the sheet centre: dot 5 stays at work zero.
        assert_relative_eq!(marks[4].position, Point2::origin(), epsilon = 1e-15);
        // Every pair of marks is at least 1.4 in apart, so the nearest mark is never in doubt.
        for (i, a) in marks.iter().enumerate() {
            for b in &marks[i + 1..] {
                assert!((a.nominal - b.nominal).norm() >= 1.4, "{a:?} {b:?}");
            }
        }
    }

    #[test]
    fn pose_is_rotation_and_scale_about_the_pivot_then_shift() {
        let f = Fixture {
            name: "p".into(),
            sheet: None,
            marks: vec![[0.0, 0.0], [6.0, 0.0], [6.0, 4.0], [0.0, 4.0]],
            diameter: None,
            shift: [0.1, -0.2],
            rotation_deg: 90.0,
            scale: [2.0, 1.0],
            center: None,
            present: true,
        };
        // Pivot = centroid (3, 2); (6, 0) − pivot = (3, −2) → scaled (6, −2) → rotated (2, 6).
        let p = f.true_point(Point2::new(6.0, 0.0), LengthUnit::Inch);
        assert_relative_eq!(p, Point2::new(3.0 + 2.0 + 0.1, 2.0 + 6.0 - 0.2), epsilon = 1e-12);
        assert_relative_eq!(f.true_marks(LengthUnit::Millimetre)[0].diameter, 0.25 * 25.4 * 2f64.sqrt());
    }
}
