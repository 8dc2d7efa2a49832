//! Calibration sheets (`CAL_SHEETS`): the printed dot layouts M283 C walks.
//!
//! Coordinates are inches in the sheet's own frame, whose origin is the point the operator
//! zeroes the work X/Y on **with the spindle** (for sheet 1: the centre dot). Dots are listed in
//! walk order. Add a sheet by appending to [`CAL_SHEETS`]; it needs at least three dots that
//! span an area.

use vision_math::{LengthUnit, Point2};

/// One printed calibration sheet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalSheet {
    /// The number `M283 Cn` selects.
    pub id: u32,
    /// Human-readable name.
    pub name: &'static str,
    /// Dot centres in walk order, inches, sheet frame (origin = spindle work zero).
    pub dots_in: &'static [(f64, f64)],
    /// Printed mark diameter, inches.
    pub mark_diameter_in: f64,
}

impl CalSheet {
    /// The dot centres converted to `unit`, walk order.
    #[must_use]
    pub fn dots(&self, unit: LengthUnit) -> Vec<Point2<f64>> {
        let f = LengthUnit::Inch.factor_to(unit);
        self.dots_in.iter().map(|(x, y)| Point2::new(x * f, y * f)).collect()
    }
}

/// The registry of known sheets.
pub const CAL_SHEETS: &[CalSheet] = &[CalSheet {
    id: 1,
    name: "MachMotion Vision Calibration Sheet (US Letter portrait, 5 x 8 in + centre)",
    // 1 start (lower left), 2 upper left, 3 upper right, 4 lower right, 5 end (centre).
    dots_in: &[(-2.5, -4.0), (-2.5, 4.0), (2.5, 4.0), (2.5, -4.0), (0.0, 0.0)],
    mark_diameter_in: 0.5,
}];

/// The sheet numbered `id`, if known.
#[must_use]
pub fn cal_sheet(id: u32) -> Option<&'static CalSheet> {
    CAL_SHEETS.iter().find(|s| s.id == id)
}

/// The known sheet numbers, comma-separated (for error messages).
#[must_use]
pub fn known_sheets() -> String {
    CAL_SHEETS.iter().map(|s| s.id.to_string()).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;
    use vision_math::fit_rectangle;

    #[test]
    fn sheet_one_is_the_manuals_layout_and_every_sheet_spans_an_area() {
        let s = cal_sheet(1).expect("sheet 1");
        assert_eq!(s.dots_in[0], (-2.5, -4.0));
        assert_eq!(s.dots_in[4], (0.0, 0.0));
        assert_eq!(s.mark_diameter_in, 0.5);
        assert_eq!(s.dots(LengthUnit::Millimetre)[2], Point2::new(63.5, 101.6));
        assert!(cal_sheet(99).is_none());
        assert_eq!(known_sheets(), "1");
        for sheet in CAL_SHEETS {
            let d = sheet.dots(LengthUnit::Inch);
            assert!(fit_rectangle(&d, &d).is_ok(), "sheet {} must span an area", sheet.id);
        }
    }
}
