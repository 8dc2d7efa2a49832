//! Speed and acceleration limits, the sampling period, and how a piece of path turns them
//! into a speed cap and a tangential acceleration.

use vision_gcode::Xyz;

use crate::PathError;

/// One axis's limits (those of the drive mapped to it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisLimits {
    /// Maximum speed, machine units per second.
    pub max_speed: f64,
    /// Maximum acceleration, machine units per second².
    pub max_accel: f64,
}

/// The limits a path obeys: the maximum path acceleration (seed 002's `maxPathAcceleration`)
/// and each axis's speed and acceleration.
///
/// Semantics: the full acceleration vector of the path (tangential + centripetal) never
/// exceeds `max_path_accel` in length, and its X, Y and Z components never exceed the
/// axes' `max_accel`; the velocity's components never exceed the axes' `max_speed`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Maximum length of the acceleration vector, machine units per second².
    pub max_path_accel: f64,
    /// X, Y, Z limits.
    pub axes: [AxisLimits; 3],
}

impl Limits {
    /// The speeds (axis maximum speeds and programmed feeds) the planner accepts, machine units
    /// per second.
    ///
    /// Decision: one range for millimetre and inch machines, wide enough for both. The lower
    /// end (0.006 units/min) is below any real drive's slowest useful speed; below it a 1-unit
    /// move would take days of setpoints and tiny values underflow the planner's arithmetic
    /// (1e-300 gave a cycle time of 0). The upper end (100 000 units/s) is far beyond any
    /// machine.
    pub const SPEED_RANGE: std::ops::RangeInclusive<f64> = 1e-4..=1e5;
    /// The accelerations (path and axes) the planner accepts, machine units per second².
    ///
    /// Decision: as [`Limits::SPEED_RANGE`]: from 0.001 units/s² (no real machine is slower)
    /// to 10⁷ units/s² (1 000 g on a millimetre machine).
    pub const ACCEL_RANGE: std::ops::RangeInclusive<f64> = 1e-3..=1e7;

    /// Limits with the same speed and acceleration on all three axes.
    pub fn uniform(max_path_accel: f64, axis_speed: f64, axis_accel: f64) -> Limits {
        let axis = AxisLimits { max_speed: axis_speed, max_accel: axis_accel };
        Limits { max_path_accel, axes: [axis; 3] }
    }

    /// Check every speed is within [`Limits::SPEED_RANGE`] and every acceleration within
    /// [`Limits::ACCEL_RANGE`].
    pub fn validate(&self) -> Result<(), PathError> {
        const ACCEL: &str = "must be between 0.001 and 10000000 units/s²";
        const SPEED: &str = "must be between 0.0001 and 100000 units/s";
        in_range("max path acceleration (units/s²)", self.max_path_accel, &Self::ACCEL_RANGE, ACCEL)?;
        for a in &self.axes {
            in_range("axis max speed (units/s)", a.max_speed, &Self::SPEED_RANGE, SPEED)?;
            in_range("axis max acceleration (units/s²)", a.max_accel, &Self::ACCEL_RANGE, ACCEL)?;
        }
        Ok(())
    }
}

/// How the planner samples and how far it looks ahead.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanConfig {
    /// The limits.
    pub limits: Limits,
    /// Setpoint period, seconds (1e-5 … 1; typically 0.001 … 0.010).
    pub period: f64,
    /// Most path pieces held in the look-ahead window (≥ 8). Memory is bounded by it; the
    /// window normally needs only the stopping distance at full speed, and a program of many
    /// tiny segments that fills it is slowed so it can always stop at the window's end.
    pub lookahead: usize,
    /// Where the machine is when the path starts, machine coordinates.
    pub start: Xyz,
    /// The most setpoints the stream delivers ([`PlanConfig::DEFAULT_MAX_SETPOINTS`] by
    /// default). A move or dwell that would end past it ends the stream with an error at its
    /// line as soon as it is planned, before any of its setpoints.
    pub max_setpoints: u64,
}

impl PlanConfig {
    /// The default look-ahead window, pieces.
    pub const DEFAULT_LOOKAHEAD: usize = 8192;

    /// The default bound on one stream's setpoints.
    ///
    /// Decision: the limits' ranges bound how slowly a move may go, not how long a program is
    /// (coordinates reach ±10⁹ units), so this bounds the run itself: 10⁹ setpoints are
    /// 11.6 days at 1 ms, longer than any real job, and about 20 s of planning.
    pub const DEFAULT_MAX_SETPOINTS: u64 = 1_000_000_000;

    /// A configuration with the default look-ahead and setpoint bound.
    pub fn new(limits: Limits, period: f64, start: Xyz) -> PlanConfig {
        PlanConfig {
            limits,
            period,
            lookahead: Self::DEFAULT_LOOKAHEAD,
            start,
            max_setpoints: Self::DEFAULT_MAX_SETPOINTS,
        }
    }

    /// Check the limits, the period, the window and the start position.
    pub fn validate(&self) -> Result<(), PathError> {
        self.limits.validate()?;
        if !(self.period >= 1e-5 && self.period <= 1.0) {
            return Err(PathError::InvalidConfig {
                what: "setpoint period (s)",
                value: self.period,
                reason: "must be between 0.00001 and 1 second",
            });
        }
        if self.lookahead < 8 {
            return Err(PathError::InvalidConfig {
                what: "look-ahead (pieces)",
                value: self.lookahead as f64,
                reason: "must be at least 8",
            });
        }
        for v in self.start.to_array() {
            if !v.is_finite() {
                return Err(PathError::InvalidConfig {
                    what: "start position (units)",
                    value: v,
                    reason: "must be finite",
                });
            }
        }
        Ok(())
    }
}

fn in_range(
    what: &'static str,
    value: f64,
    range: &std::ops::RangeInclusive<f64>,
    reason: &'static str,
) -> Result<(), PathError> {
    if range.contains(&value) {
        Ok(())
    } else {
        Err(PathError::InvalidConfig { what, value, reason })
    }
}

/// What a piece of path needs to know about its shape to be bounded, for a path parameter
/// `s` with `|dp/ds| ≤ 1` everywhere (arc length for lines, circles and helices):
///
/// * `c[i]` bounds `|dp_i/ds|` (how much of the path speed and tangential acceleration
///   reaches axis `i`);
/// * `q[i]` bounds `|d²p_i/ds²| / κ` (how much of the normal acceleration reaches axis `i`);
///   for a circle it is the length of axis `i`'s projection on the circle's plane;
/// * `kappa` bounds `|d²p/ds²|` (curvature);
/// * `cross` bounds the cosine between `dp/ds` and `d²p/ds²` (0 except for spirals);
/// * `circle`: a planar circle, whose whole acceleration vector lies in its plane, so axis
///   `i` sees at most `q[i]·|a|`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ShapeFactors {
    pub(crate) c: [f64; 3],
    pub(crate) q: [f64; 3],
    pub(crate) kappa: f64,
    pub(crate) cross: f64,
    pub(crate) circle: bool,
}

/// The fraction of the path acceleration a curve's centripetal part may use at its speed cap:
/// `√3/2`, which leaves `1/2` for the tangential part (LinuxCNC's split for arcs).
pub(crate) const NORMAL_SHARE: f64 = 0.866_025_403_784_438_6;
/// The same for one axis's acceleration on helices and spirals, where an axis may see the
/// normal and tangential parts added (not in quadrature): half for each.
const AXIS_NORMAL_SHARE: f64 = 0.5;

/// The speed cap (units/s, of `ṡ`) and the tangential acceleration (units/s², of `s̈`) of a
/// piece with these factors, asked to move at `requested` (units/s, `INFINITY` for rapid).
///
/// With `ṡ ≤ v_cap` and `|s̈| ≤ a_t`: `|v| ≤ ṡ`, `|v_i| ≤ c_i ṡ ≤ max_speed_i`,
/// `|a|² ≤ κ²ṡ⁴ + s̈² + 2·cross·κṡ²|s̈| ≤ A²`, and per axis either `|a_i| ≤ q_i·|a|` (circles)
/// or `|a_i| ≤ q_i κ ṡ² + c_i |s̈|` (lines, helices, spirals), `≤ max_accel_i`.
pub(crate) fn speed_and_accel(f: &ShapeFactors, requested: f64, limits: &Limits) -> (f64, f64) {
    let mut a_path = limits.max_path_accel;
    if f.circle {
        for (i, axis) in limits.axes.iter().enumerate() {
            if f.q[i] > 0.0 {
                a_path = a_path.min(axis.max_accel / f.q[i]);
            }
        }
    }
    let mut v = requested;
    for (i, axis) in limits.axes.iter().enumerate() {
        if f.c[i] > 0.0 {
            v = v.min(axis.max_speed / f.c[i]);
        }
    }
    if f.kappa > 0.0 {
        v = v.min((NORMAL_SHARE * a_path / f.kappa).sqrt());
        if !f.circle {
            for (i, axis) in limits.axes.iter().enumerate() {
                if f.q[i] > 0.0 {
                    v = v.min((AXIS_NORMAL_SHARE * axis.max_accel / (f.q[i] * f.kappa)).sqrt());
                }
            }
        }
    }
    let a_n = f.kappa * v * v;
    let mut a_t = -f.cross * a_n + (a_path * a_path - a_n * a_n * (1.0 - f.cross * f.cross)).max(0.0).sqrt();
    if !f.circle {
        for (i, axis) in limits.axes.iter().enumerate() {
            if f.c[i] > 0.0 {
                a_t = a_t.min((axis.max_accel - f.q[i] * a_n) / f.c[i]);
            }
        }
    }
    (v, a_t)
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;

    fn line_factors(dir: [f64; 3]) -> ShapeFactors {
        ShapeFactors { c: dir.map(f64::abs), q: [0.0; 3], kappa: 0.0, cross: 0.0, circle: false }
    }

    #[test]
    fn a_line_is_capped_by_its_feed_and_the_projected_axis_limits() {
        let mut limits = Limits::uniform(1000.0, 500.0, 2000.0);
        limits.axes[0].max_speed = 100.0;
        // Along X only: X's 100 units/s binds; path accel 1000 binds before X's 2000.
        assert_eq!(speed_and_accel(&line_factors([1.0, 0.0, 0.0]), f64::INFINITY, &limits), (100.0, 1000.0));
        // A 45° diagonal in XY: X sees v/√2, so v ≤ 100·√2.
        let d = std::f64::consts::FRAC_1_SQRT_2;
        let (v, a) = speed_and_accel(&line_factors([d, d, 0.0]), f64::INFINITY, &limits);
        assert!((v - 100.0 * 2f64.sqrt()).abs() < 1e-9);
        assert_eq!(a, 1000.0);
        // A feed below every cap wins.
        assert_eq!(speed_and_accel(&line_factors([1.0, 0.0, 0.0]), 10.0, &limits).0, 10.0);
    }

    #[test]
    fn a_circle_at_its_cap_splits_the_path_acceleration_between_normal_and_tangential() {
        let limits = Limits::uniform(1000.0, 1e6, 1e6);
        let r = 10.0;
        let f = ShapeFactors { c: [1.0, 1.0, 0.0], q: [1.0, 1.0, 0.0], kappa: 1.0 / r, cross: 0.0, circle: true };
        let (v, a_t) = speed_and_accel(&f, f64::INFINITY, &limits);
        let a_n = v * v / r;
        assert!((a_n - 1000.0 * NORMAL_SHARE).abs() < 1e-9);
        assert!(((a_n * a_n + a_t * a_t).sqrt() - 1000.0).abs() < 1e-9);
    }

    #[test]
    fn bad_numbers_are_refused_with_the_setting_named() {
        let err = Limits::uniform(0.0, 1.0, 1.0).validate().unwrap_err();
        assert!(err.to_string().contains("max path acceleration"), "{err}");
        let err = Limits::uniform(1.0, f64::NAN, 1.0).validate().unwrap_err();
        assert!(err.to_string().contains("axis max speed"), "{err}");
        let mut c = PlanConfig::new(Limits::uniform(1.0, 1.0, 1.0), 0.0, [0.0; 3].into());
        assert!(matches!(c.validate(), Err(PathError::InvalidConfig { what: "setpoint period (s)", .. })));
        c.period = 0.001;
        c.lookahead = 2;
        assert!(c.validate().is_err());
        c.lookahead = 8;
        c.start = [0.0, f64::INFINITY, 0.0].into();
        assert!(c.validate().is_err());
    }
}
