//! Small geometric types: a 3-axis triple, the arc planes and directions.

use std::ops::{Add, Mul, Neg, Sub};

use vision_math::{LengthUnit, Point2};

/// The largest magnitude of any coordinate, offset or length the interpreter lets reach the
/// machine (machine units): far beyond any machine, well within the range where lengths,
/// squares and sums stay finite. Axis words, moves, offsets and offset parameters beyond it are
/// refused ([`crate::RunProblem::BeyondRange`]); the path planner uses the same bound. One
/// bound for every crate: [`vision_math::bounds::MAX_COORDINATE`].
pub const MAX_COORDINATE: f64 = vision_math::bounds::MAX_COORDINATE;

/// X, Y and Z values of one thing (a position, an offset), in the unit its context names.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Xyz {
    /// X.
    pub x: f64,
    /// Y.
    pub y: f64,
    /// Z.
    pub z: f64,
}

// Small and called across crates in the path planner's inner loops: `#[inline]` lets them inline
// there as they did when the planner had its own vector type.
impl Xyz {
    /// All three zero.
    pub const ZERO: Xyz = Xyz { x: 0.0, y: 0.0, z: 0.0 };

    /// A triple.
    #[inline]
    #[must_use]
    pub const fn new(x: f64, y: f64, z: f64) -> Xyz {
        Xyz { x, y, z }
    }

    /// Every component multiplied by `k` (a unit conversion factor); the same as `self * k`.
    #[inline]
    #[must_use]
    pub fn scaled(self, k: f64) -> Xyz {
        self * k
    }

    /// Every component converted from `from` to `to` (exactly as [`LengthUnit::convert`]).
    #[inline]
    #[must_use]
    pub fn convert(self, from: LengthUnit, to: LengthUnit) -> Xyz {
        Xyz { x: from.convert(self.x, to), y: from.convert(self.y, to), z: from.convert(self.z, to) }
    }

    /// The X/Y part.
    #[inline]
    #[must_use]
    pub fn xy(self) -> Point2<f64> {
        Point2::new(self.x, self.y)
    }

    /// Component `axis` (0 = X, 1 = Y, 2 = Z).
    #[inline]
    #[must_use]
    pub fn axis(self, axis: usize) -> f64 {
        match axis {
            0 => self.x,
            1 => self.y,
            _ => self.z,
        }
    }

    /// Sets component `axis` (0 = X, 1 = Y, 2 = Z).
    #[inline]
    pub fn set_axis(&mut self, axis: usize, value: f64) {
        match axis {
            0 => self.x = value,
            1 => self.y = value,
            _ => self.z = value,
        }
    }

    /// True when all three components are finite.
    #[inline]
    #[must_use]
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }

    /// Euclidean length.
    #[inline]
    #[must_use]
    pub fn norm(self) -> f64 {
        self.dot(self).sqrt()
    }

    /// The dot product.
    #[inline]
    #[must_use]
    pub fn dot(self, o: Xyz) -> f64 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// The cross product `self × o`.
    #[inline]
    #[must_use]
    pub fn cross(self, o: Xyz) -> Xyz {
        Xyz::new(self.y * o.z - self.z * o.y, self.z * o.x - self.x * o.z, self.x * o.y - self.y * o.x)
    }

    /// The unit vector along `self`, or `None` for a (near-)zero or non-finite vector.
    #[inline]
    #[must_use]
    pub fn unit(self) -> Option<Xyz> {
        let n = self.norm();
        (n.is_finite() && n > 1e-300).then(|| self * (1.0 / n))
    }

    /// The largest absolute component (a length scale for relative tolerances).
    #[inline]
    #[must_use]
    pub fn max_abs(self) -> f64 {
        self.x.abs().max(self.y.abs()).max(self.z.abs())
    }

    /// The angle between two unit vectors, radians in `[0, π]` (accurate near 0 and π).
    #[inline]
    #[must_use]
    pub fn angle_to(self, o: Xyz) -> f64 {
        self.cross(o).norm().atan2(self.dot(o))
    }

    /// `[x, y, z]`.
    #[inline]
    #[must_use]
    pub const fn to_array(self) -> [f64; 3] {
        [self.x, self.y, self.z]
    }
}

impl From<[f64; 3]> for Xyz {
    #[inline]
    fn from([x, y, z]: [f64; 3]) -> Xyz {
        Xyz { x, y, z }
    }
}

impl From<Xyz> for [f64; 3] {
    #[inline]
    fn from(p: Xyz) -> [f64; 3] {
        p.to_array()
    }
}

impl Add for Xyz {
    type Output = Xyz;
    #[inline]
    fn add(self, o: Xyz) -> Xyz {
        Xyz { x: self.x + o.x, y: self.y + o.y, z: self.z + o.z }
    }
}

impl Sub for Xyz {
    type Output = Xyz;
    #[inline]
    fn sub(self, o: Xyz) -> Xyz {
        Xyz { x: self.x - o.x, y: self.y - o.y, z: self.z - o.z }
    }
}

impl Mul<f64> for Xyz {
    type Output = Xyz;
    #[inline]
    fn mul(self, k: f64) -> Xyz {
        Xyz { x: self.x * k, y: self.y * k, z: self.z * k }
    }
}

impl Neg for Xyz {
    type Output = Xyz;
    #[inline]
    fn neg(self) -> Xyz {
        Xyz { x: -self.x, y: -self.y, z: -self.z }
    }
}

/// The plane arcs are drawn in.
///
/// Each plane has a first and a second axis and a normal; "counter-clockwise" is the positive
/// rotation from the first axis towards the second, seen from the normal's positive side
/// (RS274/NGC): G17 X→Y seen from +Z, G18 Z→X seen from +Y, G19 Y→Z seen from +X.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Plane {
    /// G17: X and Y, normal Z.
    #[default]
    Xy,
    /// G18: Z and X, normal Y.
    Zx,
    /// G19: Y and Z, normal X.
    Yz,
}

impl Plane {
    /// Indices (0 = X, 1 = Y, 2 = Z) of the first axis, the second axis and the normal.
    #[must_use]
    pub fn axes(self) -> (usize, usize, usize) {
        match self {
            Plane::Xy => (0, 1, 2),
            Plane::Zx => (2, 0, 1),
            Plane::Yz => (1, 2, 0),
        }
    }

    /// The G-code that selects the plane.
    #[must_use]
    pub fn gcode(self) -> &'static str {
        match self {
            Plane::Xy => "G17",
            Plane::Zx => "G18",
            Plane::Yz => "G19",
        }
    }

    /// The centre-word letters of the first and second axis (I/J/K for X/Y/Z).
    #[must_use]
    pub fn centre_letters(self) -> (u8, u8) {
        let (a, b, _) = self.axes();
        (CENTRE_LETTERS[a], CENTRE_LETTERS[b])
    }

    /// The centre words as text, for messages (`I and J`).
    #[must_use]
    pub fn centre_words(self) -> &'static str {
        match self {
            Plane::Xy => "I and J",
            Plane::Zx => "K and I",
            Plane::Yz => "J and K",
        }
    }
}

/// The centre-word letter of each axis.
pub(crate) const CENTRE_LETTERS: [u8; 3] = [b'I', b'J', b'K'];

/// The axis letters.
pub(crate) const AXIS_LETTERS: [u8; 3] = [b'X', b'Y', b'Z'];

/// The sense of an arc in its plane.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArcDirection {
    /// G2.
    Clockwise,
    /// G3.
    CounterClockwise,
}

impl ArcDirection {
    /// The other direction (what a mirror does to an arc).
    #[must_use]
    pub fn reversed(self) -> ArcDirection {
        match self {
            ArcDirection::Clockwise => ArcDirection::CounterClockwise,
            ArcDirection::CounterClockwise => ArcDirection::Clockwise,
        }
    }

    /// +1 for counter-clockwise, −1 for clockwise.
    #[must_use]
    pub fn sign(self) -> f64 {
        match self {
            ArcDirection::Clockwise => -1.0,
            ArcDirection::CounterClockwise => 1.0,
        }
    }
}
