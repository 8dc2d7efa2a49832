//! The range checks of the parameter tables: each names the values it accepts ([`Check::range`],
//! which the refusal and the parameter reference both quote), so what is checked and what is
//! documented cannot differ.

use crate::pound::PoundBlock;

/// A range check of a parameter's values.
#[derive(Debug)]
pub(crate) struct Check<T: 'static> {
    /// The values accepted, worded to follow "must be" ("between 0 and 60 seconds"); empty:
    /// every value of the parameter's type.
    pub(crate) range: &'static str,
    /// Whether `v` is accepted.
    accepts: fn(&T) -> bool,
    /// The refusal when it is more specific than "must be {range}" (the pound block names the
    /// variables it would clash with).
    refusal: Option<fn(&T) -> String>,
}

impl<T> Check<T> {
    /// Every value of the type.
    pub(crate) const ANY: Check<T> = Check { range: "", accepts: |_| true, refusal: None };

    /// `Err` says what the value must be.
    pub(crate) fn check(&self, v: &T) -> Result<(), String> {
        if (self.accepts)(v) {
            Ok(())
        } else {
            Err(self.refusal.map_or_else(|| format!("must be {}", self.range), |r| r(v)))
        }
    }
}

pub(super) const FINITE: Check<f64> = Check { range: "a finite number", accepts: |v| v.is_finite(), refusal: None };
pub(super) const NON_NEGATIVE: Check<f64> =
    Check { range: "a finite number ≥ 0 (0 disables)", accepts: |v| v.is_finite() && *v >= 0.0, refusal: None };
pub(super) const SECONDS_60: Check<f64> =
    Check { range: "between 0 and 60 seconds", accepts: |v| v.is_finite() && (0.0..=60.0).contains(v), refusal: None };
pub(super) const PIXEL_OFFSET: Check<f64> = Check {
    range: "a finite number of pixels (|v| ≤ 100000)",
    accepts: |v| v.is_finite() && v.abs() <= 100_000.0,
    refusal: None,
};
pub(super) const NOISE_PX: Check<f64> =
    Check { range: "between 0 and 10 pixels", accepts: |v| v.is_finite() && (0.0..=10.0).contains(v), refusal: None };
pub(super) const NOISE_PX_WIDE: Check<f64> = Check {
    range: "between 0 and 1000 pixels",
    accepts: |v| v.is_finite() && (0.0..=1000.0).contains(v),
    refusal: None,
};
pub(super) const LIFT_IN: Check<f64> = Check {
    range: "between 0 and 2 inches (0 = calibrate at one height)",
    accepts: |v| v.is_finite() && (0.0..=2.0).contains(v),
    refusal: None,
};
pub(super) const PASSES: Check<i64> =
    Check { range: "0..10 passes (0 reads in one shot)", accepts: |v| (0..=10).contains(v), refusal: None };
pub(super) const JOB: Check<i64> = Check {
    range: "a camera job 0..999 (0 = leave the camera's job)",
    accepts: |v| (0..=999).contains(v),
    refusal: None,
};
pub(super) const RESOLUTION: Check<i64> =
    Check { range: "an image size of 2..100000 pixels", accepts: |v| (2..=100_000).contains(v), refusal: None };
pub(super) const RESOLUTION_RECORD: Check<i64> = Check {
    range: "an image size of 2..100000 pixels (0 = not recorded)",
    accepts: |v| *v == 0 || (2..=100_000).contains(v),
    refusal: None,
};
pub(super) const TOOL: Check<i64> = Check {
    range: "a tool number ≥ 0 (0 disables the camera-tool check)",
    accepts: |v| (0..=i64::from(u32::MAX)).contains(v),
    refusal: None,
};
pub(super) const POUND_BASE: Check<i64> = Check {
    range: "an integer B ≥ 100 whose 40-variable block #B..#B+39 ends at or below #9999 and stays outside \
            #5061..#5081 and #5201..#5500",
    accepts: |v| PoundBlock::new(*v).is_ok(),
    refusal: Some(|v| PoundBlock::new(*v).err().map(|e| e.to_string()).unwrap_or_default()),
};
pub(super) const DRIVER_NAME: Check<String> = Check {
    range: "a driver name (letters, digits, _ or -), e.g. Keyence",
    accepts: |v| is_driver_name(v),
    refusal: None,
};
pub(super) const DRIVER_RECORD: Check<String> = Check {
    range: "a driver name (letters, digits, _ or -), or empty (not recorded)",
    accepts: |v| v.is_empty() || is_driver_name(v),
    refusal: None,
};
pub(super) const SHORT_TEXT: Check<String> =
    Check { range: "text of at most 4096 bytes", accepts: |v| v.len() <= 4096 && !v.contains('\0'), refusal: None };

fn is_driver_name(v: &str) -> bool {
    !v.is_empty() && v.len() <= 64 && v.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_refusal_quotes_the_range_the_reference_shows() {
        assert_eq!(SECONDS_60.check(&61.0), Err("must be between 0 and 60 seconds".into()));
        assert_eq!(NON_NEGATIVE.check(&f64::NAN), Err(format!("must be {}", NON_NEGATIVE.range)));
        assert_eq!(Check::<f64>::ANY.check(&f64::NAN), Ok(()));
        // The pound block says which variables clash; its range covers the same rule.
        let e = POUND_BASE.check(&5050).expect_err("reserved");
        assert!(e.contains("5061..5081"), "{e}");
        for ok in [100, 500, 5020, 5501, 9960] {
            assert_eq!(POUND_BASE.check(&ok), Ok(()), "{ok}");
        }
        for bad in [99, 5030, 5500, 9961] {
            assert!(POUND_BASE.check(&bad).is_err(), "{bad}");
        }
    }
}
