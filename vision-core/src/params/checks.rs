//! The range checks of the parameter tables and of the drivers' settings: each names the values
//! it accepts ([`Check::range`], which the refusal and the parameter reference both quote), so
//! what is checked and what is documented cannot differ. A numeric range is data
//! ([`Check::within`]), the one helper every interval is checked with.

use std::mem::ManuallyDrop;
use std::ops::{Bound, RangeBounds};

use crate::pound::PoundBlock;

/// A value a [`Check::within`] can bound: ordered, and for a float a number (NaN and ±∞ are
/// outside every range).
pub trait Ordered: PartialOrd + Copy + 'static {
    /// Whether `self` lies between `lo` and `hi`.
    fn within(&self, lo: &Bound<Self>, hi: &Bound<Self>) -> bool;
}

impl Ordered for f64 {
    fn within(&self, lo: &Bound<f64>, hi: &Bound<f64>) -> bool {
        self.is_finite() && (lo.as_ref(), hi.as_ref()).contains(self)
    }
}

impl Ordered for i64 {
    fn within(&self, lo: &Bound<i64>, hi: &Bound<i64>) -> bool {
        (lo.as_ref(), hi.as_ref()).contains(self)
    }
}

/// A range check of a parameter's or a driver setting's values.
#[derive(Debug)]
pub struct Check<T: 'static> {
    /// The values accepted, worded to follow "must be" ("between 0 and 60 seconds"); empty:
    /// every value of the parameter's type.
    pub range: &'static str,
    rule: Rule<T>,
}

/// How a [`Check`] decides.
#[derive(Debug)]
enum Rule<T: 'static> {
    /// Every value.
    Any,
    /// Between two bounds; the function is [`Ordered::within`]. The bounds are `Copy`
    /// ([`Ordered`]): `ManuallyDrop` only tells the compiler that a `Check<String>` in a constant
    /// has nothing to drop.
    Within(ManuallyDrop<Bound<T>>, ManuallyDrop<Bound<T>>, fn(&T, &Bound<T>, &Bound<T>) -> bool),
    /// A rule the range words describe.
    Test(fn(&T) -> bool),
    /// A rule that says itself why a value is refused (the pound block names the variables it
    /// would clash with).
    Explained(fn(&T) -> Result<(), String>),
}

impl<T> Check<T> {
    /// Every value of the type.
    pub const ANY: Check<T> = Check { range: "", rule: Rule::Any };

    /// The values `accepts` says yes to, which `range` describes.
    #[must_use]
    pub const fn test(range: &'static str, accepts: fn(&T) -> bool) -> Check<T> {
        Check { range, rule: Rule::Test(accepts) }
    }

    /// The values `explain` says yes to; its `Err` is the refusal, more specific than "must be
    /// {range}".
    #[must_use]
    pub const fn explained(range: &'static str, explain: fn(&T) -> Result<(), String>) -> Check<T> {
        Check { range, rule: Rule::Explained(explain) }
    }

    /// Whether `v` is accepted.
    #[must_use]
    pub fn accepts(&self, v: &T) -> bool {
        self.check(v).is_ok()
    }

    /// `Err` says what the value must be.
    ///
    /// # Errors
    /// "must be {range}", or the explained rule's own words.
    pub fn check(&self, v: &T) -> Result<(), String> {
        let ok = match &self.rule {
            Rule::Any => true,
            Rule::Within(lo, hi, within) => within(v, lo, hi),
            Rule::Test(accepts) => accepts(v),
            Rule::Explained(explain) => return explain(v),
        };
        if ok {
            Ok(())
        } else {
            Err(format!("must be {}", self.range))
        }
    }
}

impl<T: Ordered> Check<T> {
    /// The values between `lo` and `hi` (a float also finite), which `range` describes.
    #[must_use]
    pub const fn within(range: &'static str, lo: Bound<T>, hi: Bound<T>) -> Check<T> {
        Check { range, rule: Rule::Within(ManuallyDrop::new(lo), ManuallyDrop::new(hi), T::within) }
    }

    /// The values from `lo` to `hi`, both included.
    #[must_use]
    pub const fn closed(range: &'static str, lo: T, hi: T) -> Check<T> {
        Check::within(range, Bound::Included(lo), Bound::Included(hi))
    }
}

pub(super) const FINITE: Check<f64> = Check::within("a finite number", Bound::Unbounded, Bound::Unbounded);
pub(super) const NON_NEGATIVE: Check<f64> =
    Check::within("a finite number ≥ 0 (0 disables)", Bound::Included(0.0), Bound::Unbounded);
pub(super) const SECONDS_60: Check<f64> = Check::closed("between 0 and 60 seconds", 0.0, 60.0);
pub(super) const PIXEL_OFFSET: Check<f64> =
    Check::closed("a finite number of pixels (|v| ≤ 100000)", -100_000.0, 100_000.0);
pub(super) const NOISE_PX: Check<f64> = Check::closed("between 0 and 10 pixels", 0.0, 10.0);
pub(super) const NOISE_PX_WIDE: Check<f64> = Check::closed("between 0 and 1000 pixels", 0.0, 1000.0);
pub(super) const LIFT_IN: Check<f64> = Check::closed("between 0 and 2 inches (0 = calibrate at one height)", 0.0, 2.0);
pub(super) const LENS_RADIAL: Check<f64> = Check::closed("between -10 and 10", -10.0, 10.0);
pub(super) const LENS_TANGENTIAL: Check<f64> = Check::closed("between -1 and 1", -1.0, 1.0);
pub(super) const LENS_GRID: Check<i64> = Check::closed("0..15 positions per axis (0 = no lens grid)", 0, 15);
pub(super) const PASSES: Check<i64> = Check::closed("0..10 passes (0 reads in one shot)", 0, 10);
pub(super) const JOB: Check<i64> = Check::closed("a camera job 0..999 (0 = leave the camera's job)", 0, 999);
pub(super) const RESOLUTION: Check<i64> = Check::closed("an image size of 2..100000 pixels", 2, 100_000);
pub(super) const RESOLUTION_RECORD: Check<i64> =
    Check::test("an image size of 2..100000 pixels (0 = not recorded)", |v| *v == 0 || RESOLUTION.accepts(v));
pub(super) const TOOL: Check<i64> =
    Check::closed("a tool number ≥ 0 (0 disables the camera-tool check)", 0, u32::MAX as i64);
pub(super) const POUND_BASE: Check<i64> = Check::explained(
    "an integer B ≥ 100 whose 40-variable block #B..#B+39 ends at or below #9999 and stays outside \
     #5061..#5081 and #5201..#5500",
    |v| PoundBlock::new(*v).map(|_| ()).map_err(|e| e.to_string()),
);
pub(super) const DRIVER_NAME: Check<String> =
    Check::test("a driver name (letters, digits, _ or -), e.g. Keyence", |v| is_driver_name(v));
pub(super) const DRIVER_RECORD: Check<String> =
    Check::test("a driver name (letters, digits, _ or -), or empty (not recorded)", |v| {
        v.is_empty() || is_driver_name(v)
    });
pub(super) const SHORT_TEXT: Check<String> =
    Check::test("text of at most 4096 bytes", |v| v.len() <= 4096 && !v.contains('\0'));

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

    #[test]
    fn a_driver_name_and_a_short_text_are_bounded_and_plain() {
        let longest = "k".repeat(64);
        for ok in ["Keyence", "my-cam_2", longest.as_str()] {
            assert!(DRIVER_NAME.accepts(&ok.to_string()) && DRIVER_RECORD.accepts(&ok.to_string()), "{ok}");
        }
        let too_long = "k".repeat(65);
        for bad in ["", "Key ence", "cam/1", "kéyence", too_long.as_str()] {
            assert!(!DRIVER_NAME.accepts(&bad.to_string()), "{bad:?}");
        }
        assert!(DRIVER_RECORD.accepts(&String::new()), "empty: not recorded");
        assert!(!DRIVER_RECORD.accepts(&"Key ence".to_string()));
        let longest = "a".repeat(4096);
        assert!(SHORT_TEXT.accepts(&longest) && SHORT_TEXT.accepts(&String::new()));
        assert!(!SHORT_TEXT.accepts(&"a".repeat(4097)) && !SHORT_TEXT.accepts(&"a\0b".to_string()));
    }

    #[test]
    fn a_range_keeps_its_ends_open_or_closed_and_refuses_what_is_not_a_number() {
        let open = Check::within("more than 0 and less than 1", Bound::Excluded(0.0), Bound::Excluded(1.0));
        assert!(!open.accepts(&0.0) && open.accepts(&1e-12) && open.accepts(&(1.0 - 1e-12)) && !open.accepts(&1.0));
        let closed = Check::closed("0 to 1", 0.0, 1.0);
        assert!(closed.accepts(&0.0) && closed.accepts(&1.0) && !closed.accepts(&-1e-12) && !closed.accepts(&1.1));
        for not_a_number in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert!(!FINITE.accepts(&not_a_number) && !NON_NEGATIVE.accepts(&not_a_number), "{not_a_number}");
        }
        assert!(FINITE.accepts(&-1e300) && NON_NEGATIVE.accepts(&1e300));
        assert!(TOOL.accepts(&i64::from(u32::MAX)) && !TOOL.accepts(&(i64::from(u32::MAX) + 1)) && !TOOL.accepts(&-1));
        assert!(RESOLUTION_RECORD.accepts(&0) && !RESOLUTION_RECORD.accepts(&1) && RESOLUTION_RECORD.accepts(&2));
    }
}
