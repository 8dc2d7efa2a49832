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
    /// A coordinate beyond [`crate::fit::MAX_COORDINATE`]: no machine travels that far, and the
    /// fit's sums would overflow.
    #[error("{what} has a coordinate of {}, beyond ±{} (no machine travels that far); check the input's units", crate::show::number(*value), crate::show::number(*limit))]
    CoordinateTooLarge {
        /// Which set: "a commanded point" or "an observed point".
        what: &'static str,
        /// The largest coordinate magnitude found.
        value: f64,
        /// The bound, machine units.
        limit: f64,
    },
    /// A value beyond its bound in [`crate::bounds`] (a position, an offset, a rotation): an
    /// error of units or input, which G-code with fixed decimals would print as hundreds of
    /// digits.
    #[error("{what} is {}, beyond ±{} ({unit}); check the controller's value and units", crate::show::number(*value), crate::show::number(*limit))]
    BeyondBound {
        /// What the value is ("the G5x rotation before the alignment").
        what: &'static str,
        /// The value.
        value: f64,
        /// The bound.
        limit: f64,
        /// The bound's unit ("degrees", "machine units").
        unit: &'static str,
    },
    /// The fitted scale is near zero or huge: the observed points are collinear or collapse
    /// while the commanded ones span an area.
    #[error(
        "the fit scales the part by X {scale_x:e} / Y {scale_y:e}, outside {min:e}..{max:e}: the observed \
         points are collinear or collapse; check that each observed point is its own mark"
    )]
    DegenerateScale {
        /// The fit's X scale (dimensionless).
        scale_x: f64,
        /// The fit's Y scale (dimensionless).
        scale_y: f64,
        /// The smallest allowed scale magnitude.
        min: f64,
        /// The largest allowed scale magnitude.
        max: f64,
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
    /// The fit scales the part by more than the scale gate, and the host cannot scale (LinuxCNC
    /// has no G51).
    #[error(
        "LinuxCNC cannot scale: the fit's scale X {scale_x:.6} / Y {scale_y:.6} deviates {dev_pct:.4} % from 1, \
         more than the scale gate of {max_dev_pct} %; check that the part matches the program, or align \
         without scale (M282 P1 shift only, P2 rotation only)"
    )]
    ScaleNotExpressible {
        /// The fit's X scale (dimensionless).
        scale_x: f64,
        /// The fit's Y scale (dimensionless).
        scale_y: f64,
        /// The larger deviation of the two from 1, percent.
        dev_pct: f64,
        /// The gate, percent.
        max_dev_pct: f64,
    },
    /// Two sets of readings meant to differ in image scale (a calibration lift) do not: the
    /// height change did not reach the camera's image, or was lost in the noise.
    #[error(
        "the image scale did not change measurably between the two heights (ratio {ratio:.5} ± {sigma:.5}); \
         check that the lift moves the camera (VisionCalibrationLift) and that the camera moves with the head"
    )]
    NoScaleChange {
        /// The measured scale ratio (second height over first), dimensionless.
        ratio: f64,
        /// Its 1σ, dimensionless.
        sigma: f64,
    },
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
    /// The lens distortion folds the image, or bends it beyond what the chain undoes to its
    /// tolerance, within the camera's field.
    #[error(
        "the lens distortion cannot be undone at centred pixel ({x:.0}, {y:.0}): it folds the image there, or \
         bends it too far to undo; check VisionLensK1/K2/P1/P2 and VisionLensFocalPx, or re-run M283 C"
    )]
    LensFolds {
        /// Centred pixel x where it fails, pixels.
        x: f64,
        /// Centred pixel y, pixels.
        y: f64,
    },
}
