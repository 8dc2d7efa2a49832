//! Length units and their conversion.

/// Millimetres per inch, exactly.
pub const MM_PER_INCH: f64 = 25.4;

/// A machine length unit (G20 inch or G21 millimetre).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum LengthUnit {
    /// Inches (G20).
    #[default]
    Inch,
    /// Millimetres (G21).
    Millimetre,
}

impl LengthUnit {
    /// Factor that turns a length in `self` into a length in `to` (1, 25.4 or 1/25.4).
    #[must_use]
    pub fn factor_to(self, to: LengthUnit) -> f64 {
        match (self, to) {
            (LengthUnit::Inch, LengthUnit::Millimetre) => MM_PER_INCH,
            (LengthUnit::Millimetre, LengthUnit::Inch) => 1.0 / MM_PER_INCH,
            _ => 1.0,
        }
    }

    /// Converts `value` (a length in `self`) into `to`.
    #[must_use]
    pub fn convert(self, value: f64, to: LengthUnit) -> f64 {
        match (self, to) {
            (LengthUnit::Inch, LengthUnit::Millimetre) => value * MM_PER_INCH,
            (LengthUnit::Millimetre, LengthUnit::Inch) => value / MM_PER_INCH,
            _ => value,
        }
    }

    /// Short name: `in` or `mm` (the manual's `Cal_Units` values).
    #[must_use]
    pub fn short_name(self) -> &'static str {
        match self {
            LengthUnit::Inch => "in",
            LengthUnit::Millimetre => "mm",
        }
    }
}

/// Inches to millimetres.
#[must_use]
pub fn inch_to_mm(inches: f64) -> f64 {
    inches * MM_PER_INCH
}

/// Millimetres to inches.
#[must_use]
pub fn mm_to_inch(mm: f64) -> f64 {
    mm / MM_PER_INCH
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_factors() {
        assert_eq!(inch_to_mm(1.0), 25.4);
        assert!((mm_to_inch(inch_to_mm(0.123_456)) - 0.123_456).abs() < 1e-15);
        assert_eq!(LengthUnit::Inch.factor_to(LengthUnit::Millimetre), 25.4);
        assert_eq!(LengthUnit::Millimetre.convert(25.4, LengthUnit::Inch), 1.0);
        assert_eq!(LengthUnit::Inch.convert(2.0, LengthUnit::Inch), 2.0);
        assert_eq!(LengthUnit::Inch.short_name(), "in");
    }
}
