//! The one error type of `vision-math`.

/// Why a computation was refused. Every variant says what to do about it.
///
/// No function of this crate returns NaN or infinity in place of an error.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MathError {
    /// Fewer points than the model needs.
    #[error("{model} fit needs at least {needed} points, got {got}; capture more marks")]
    TooFewPoints {
        /// The model's name.
        model: &'static str,
        /// The minimum number of points.
        needed: usize,
        /// The number given.
        got: usize,
    },
    /// The commanded and observed lists differ in length.
    #[error("{commanded} commanded points but {observed} observed points; every mark needs both")]
    LengthMismatch {
        /// Number of commanded points.
        commanded: usize,
        /// Number of observed points.
        observed: usize,
    },
    /// A coordinate or a matrix entry is NaN or infinite.
    #[error("{what} is not a finite number; check the input")]
    NonFinite {
        /// Which input held the bad value.
        what: &'static str,
    },
    /// The commanded points (nearly) coincide: no rotation or scale can be measured.
    #[error("the commanded points coincide; place the marks apart")]
    CoincidentPoints,
    /// The commanded points (nearly) lie on one line: the model's 2D part is undetermined.
    #[error("the commanded points are collinear; the {model} fit needs marks that span an area")]
    CollinearPoints {
        /// The model's name.
        model: &'static str,
    },
    /// The observed points carry no information about rotation (they collapse to a point).
    #[error("the observed points collapse to one point; the camera probably found the same mark every time")]
    DegenerateObserved,
    /// K is all zero: the camera has not been calibrated.
    #[error("K matrix is zero; run M283 to calibrate first")]
    NotCalibrated,
    /// K (or the remapped K) cannot be inverted.
    #[error("K matrix is singular; recalibrate (M283)")]
    SingularK,
    /// The image resolution is not a positive finite number of pixels.
    #[error("camera resolution {x} x {y} px is invalid; both must be positive")]
    BadResolution {
        /// Resolution in X, pixels.
        x: f64,
        /// Resolution in Y, pixels.
        y: f64,
    },
}
