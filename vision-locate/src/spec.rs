//! What mark to look for.

use std::fmt;

/// The shape of the printed mark: the one type the finder, the camera driver's
/// `VisionCameraMark`, the simulator's world file and the CLI's `--mark` share. Written as its
/// lower-case word (`dot`, `ring`, `cross`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize), serde(rename_all = "lowercase"))]
pub enum MarkKind {
    /// A filled disc; `diameter_px` is its diameter.
    #[default]
    Dot,
    /// A circular ring of any line width; `diameter_px` is its outer diameter.
    Ring,
    /// Two equal perpendicular bars crossing at their middles, any bar width and rotation;
    /// `diameter_px` is the tip-to-tip length of a bar.
    Cross,
}

impl MarkKind {
    /// Every kind, in the order they are listed.
    pub const ALL: [MarkKind; 3] = [MarkKind::Dot, MarkKind::Ring, MarkKind::Cross];
    /// Their words, in the same order.
    pub const NAMES: &'static [&'static str] = &["dot", "ring", "cross"];

    /// The kind's word: `dot`, `ring` or `cross`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            MarkKind::Dot => "dot",
            MarkKind::Ring => "ring",
            MarkKind::Cross => "cross",
        }
    }
}

impl fmt::Display for MarkKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A word that names no [`MarkKind`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownMarkKind(pub String);

impl fmt::Display for UnknownMarkKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} is not dot, ring or cross", self.0)
    }
}

impl std::error::Error for UnknownMarkKind {}

impl std::str::FromStr for MarkKind {
    type Err = UnknownMarkKind;

    /// Reads `dot`, `ring` or `cross`, in any case.
    fn from_str(s: &str) -> Result<MarkKind, UnknownMarkKind> {
        MarkKind::ALL
            .into_iter()
            .find(|k| k.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| UnknownMarkKind(s.to_string()))
    }
}

/// Which way the mark differs from its surround.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Polarity {
    /// A dark mark on a lighter ground (black ink on white paper).
    DarkOnLight,
    /// A light mark on a darker ground (a bright dot on a dark part).
    LightOnDark,
}

/// A description of the mark to find.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarkSpec {
    /// Shape.
    pub kind: MarkKind,
    /// Expected size in image pixels (see [`MarkKind`] for what is measured); finite, > 0.
    pub diameter_px: f64,
    /// Allowed relative deviation of the measured size, as a fraction in (0, 1): 0.25 accepts
    /// 0.75 … 1.25 × `diameter_px`.
    pub tolerance: f64,
    /// Dark on light or light on dark.
    pub polarity: Polarity,
}

/// Why a [`MarkSpec`] cannot be searched for.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum SpecError {
    /// The diameter is NaN, infinite or not positive.
    Diameter(f64),
    /// The diameter is finite and positive but too small to measure (under 4 px).
    DiameterTooSmall(f64),
    /// The tolerance is NaN or outside (0, 1).
    Tolerance(f64),
}

impl fmt::Display for SpecError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SpecError::Diameter(d) => write!(f, "mark diameter {d} px is not a positive number — give it in image pixels"),
            SpecError::DiameterTooSmall(d) => write!(
                f,
                "mark diameter {d} px is below the {MIN_DIAMETER_PX} px the finder can measure — zoom in or print a larger mark"
            ),
            SpecError::Tolerance(t) => {
                write!(f, "size tolerance {t} is not a fraction between 0 and 1 (exclusive) — e.g. 0.25 for ±25 %")
            }
        }
    }
}

impl std::error::Error for SpecError {}

/// The smallest mark diameter, in pixels, the finder accepts.
pub const MIN_DIAMETER_PX: f64 = 4.0;

impl MarkSpec {
    /// A checked spec; `diameter_px` in pixels, `tolerance` a fraction.
    pub fn new(kind: MarkKind, diameter_px: f64, tolerance: f64, polarity: Polarity) -> Result<Self, SpecError> {
        let spec = MarkSpec { kind, diameter_px, tolerance, polarity };
        spec.validate()?;
        Ok(spec)
    }

    /// Checks the fields (the finder calls this too).
    pub fn validate(&self) -> Result<(), SpecError> {
        if !(self.diameter_px > 0.0) || !self.diameter_px.is_finite() {
            return Err(SpecError::Diameter(self.diameter_px));
        }
        if self.diameter_px < MIN_DIAMETER_PX {
            return Err(SpecError::DiameterTooSmall(self.diameter_px));
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(SpecError::Tolerance(self.tolerance));
        }
        Ok(())
    }

    /// The same spec for another diameter, px (unchecked: for sizing, not searching).
    pub(crate) fn with_diameter(&self, diameter_px: f64) -> MarkSpec {
        MarkSpec { diameter_px, ..*self }
    }

    /// Smallest accepted size in pixels.
    pub fn min_diameter(&self) -> f64 {
        self.diameter_px * (1.0 - self.tolerance)
    }

    /// Largest accepted size in pixels.
    pub fn max_diameter(&self) -> f64 {
        self.diameter_px * (1.0 + self.tolerance)
    }
}
