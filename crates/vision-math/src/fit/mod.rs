//! Least-squares transform fits from commanded points `nᵢ` to observed points `oᵢ`.
//!
//! Every model is solved in closed form from centred second moments (two passes over the
//! points, no SVD, no iteration, no trigonometry):
//!
//! | model | parameters | minimum points | function |
//! | --- | --- | --- | --- |
//! | rigid (Procrustes) | shift, rotation | 2 | [`fit_rigid`] |
//! | similarity | shift, rotation, uniform scale | 2 | [`fit_similarity`] |
//! | rectangle | shift, rotation, X and Y scale (no shear) | 3, not collinear | [`fit_rectangle`] |
//! | affine | shift, full 2×2 | 3, not collinear | [`fit_affine`] |
//!
//! All lengths are in whatever unit the points are given in (machine units); angles are radians
//! unless a name says degrees. The fitted map is `o ≈ L·(n − n̄) + ō` with `L = R(θ)·U`,
//! `U = [[sx, shear], [0, sy]]`.

mod affine;
mod linear;
mod partial;
mod rectangle;
mod rigid;
mod similarity;

pub use affine::fit_affine;
pub use linear::{solve_linear, LinearFit};
pub use partial::{fit_piece, PartialFit, Piece};
pub use rectangle::fit_rectangle;
pub use rigid::fit_rigid;
pub use similarity::fit_similarity;

use nalgebra::{Matrix2, Point2, UnitComplex, Vector2};

use crate::{AlignmentChain, MathError};

/// A transform model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Model {
    /// Shift and rotation (rigid Procrustes).
    Rigid,
    /// Shift, rotation, one uniform scale (M280 P3).
    Similarity,
    /// Shift, rotation, separate X and Y scale, no shear (M280 P4, the default).
    Rectangle,
    /// Shift and a full 2×2 matrix (rotation, two scales, shear).
    Affine,
}

impl Model {
    /// All models, in order of increasing freedom.
    pub const ALL: [Model; 4] = [Model::Rigid, Model::Similarity, Model::Rectangle, Model::Affine];

    /// The model's lower-case name (`rigid`, `similarity`, `rectangle`, `affine`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Model::Rigid => "rigid",
            Model::Similarity => "similarity",
            Model::Rectangle => "rectangle",
            Model::Affine => "affine",
        }
    }

    /// The model named `name` (case-insensitive), if any.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Model> {
        Model::ALL.into_iter().find(|m| m.name().eq_ignore_ascii_case(name))
    }

    /// The fewest points the model can be solved from.
    #[must_use]
    pub fn min_points(self) -> usize {
        match self {
            Model::Rigid | Model::Similarity => 2,
            Model::Rectangle | Model::Affine => 3,
        }
    }

    /// Solves this model from `commanded` to `observed`.
    ///
    /// # Errors
    /// As the model's own fit function.
    pub fn fit(self, commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> Result<Fit, MathError> {
        match self {
            Model::Rigid => fit_rigid(commanded, observed),
            Model::Similarity => fit_similarity(commanded, observed),
            Model::Rectangle => fit_rectangle(commanded, observed),
            Model::Affine => fit_affine(commanded, observed),
        }
    }
}

impl std::fmt::Display for Model {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A solved fit: parameters, quality, and the way back to the points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fit {
    /// Which model was solved.
    pub model: Model,
    /// Rotation `R(θ)`, counter-clockwise seen from +Z.
    pub rotation: UnitComplex<f64>,
    /// `(sx, sy)`: scale along the commanded X and Y axes (dimensionless; 1 = true size).
    pub scale: Vector2<f64>,
    /// Shear of `U = [[sx, shear], [0, sy]]` (dimensionless); 0 for every model but affine.
    pub shear: f64,
    /// Centroid of the commanded points, machine units.
    pub commanded_centroid: Point2<f64>,
    /// Centroid of the observed points, machine units.
    pub observed_centroid: Point2<f64>,
    /// Number of point pairs the fit used.
    pub len: usize,
    /// Root-mean-square residual length `sqrt(Σ‖rᵢ‖² / N)`, machine units.
    pub rms: f64,
    /// Largest residual length, machine units.
    pub max_residual: f64,
}

impl Fit {
    /// The linear part `L = R(θ)·[[sx, shear], [0, sy]]`.
    #[must_use]
    pub fn linear(&self) -> Matrix2<f64> {
        let (c, s) = (self.rotation.re, self.rotation.im);
        let u = Matrix2::new(self.scale.x, self.shear, 0.0, self.scale.y);
        Matrix2::new(c, -s, s, c) * u
    }

    /// The translation `b` of `o = L·n + b`, machine units.
    #[must_use]
    pub fn offset(&self) -> Vector2<f64> {
        self.observed_centroid.coords - self.linear() * self.commanded_centroid.coords
    }

    /// Rotation θ in radians, in (−π, π].
    #[must_use]
    pub fn theta_rad(&self) -> f64 {
        self.rotation.im.atan2(self.rotation.re)
    }

    /// Rotation θ in degrees, in (−180, 180].
    #[must_use]
    pub fn theta_deg(&self) -> f64 {
        self.theta_rad().to_degrees()
    }

    /// Where the fit puts commanded point `n` (machine units).
    #[must_use]
    pub fn apply(&self, n: Point2<f64>) -> Point2<f64> {
        self.observed_centroid + self.linear() * (n - self.commanded_centroid)
    }

    /// Per-point residuals `apply(nᵢ) − oᵢ`, machine units, in input order.
    ///
    /// Pass the same slices the fit was solved from.
    #[must_use]
    pub fn residuals(&self, commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> Vec<Vector2<f64>> {
        let l = self.linear();
        commanded
            .iter()
            .zip(observed)
            .map(|(n, o)| l * (n - self.commanded_centroid) - (o - self.observed_centroid))
            .collect()
    }

    /// The G51 → G68 → G52 chain that executes this fit, rotating about the commanded centroid;
    /// `None` for an affine fit, whose shear those modals cannot express.
    #[must_use]
    pub fn chain(&self) -> Option<AlignmentChain> {
        if self.model == Model::Affine {
            return None;
        }
        Some(AlignmentChain::from_parts(
            self.scale,
            self.commanded_centroid,
            self.rotation,
            self.commanded_centroid,
            self.observed_centroid,
        ))
    }
}

/// Centred moments of a point-pair set: the only thing every closed form needs.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Moments {
    pub(crate) len: usize,
    /// Commanded centroid n̄.
    pub(crate) cn: Vector2<f64>,
    /// Observed centroid ō.
    pub(crate) co: Vector2<f64>,
    /// Σ aₓ², Σ aₓa_y, Σ a_y² with a = n − n̄.
    pub(crate) sxx: f64,
    pub(crate) sxy: f64,
    pub(crate) syy: f64,
    /// Σ aₓqₓ, Σ aₓq_y, Σ a_yqₓ, Σ a_yq_y with q = o − ō.
    pub(crate) pxx: f64,
    pub(crate) pxy: f64,
    pub(crate) pyx: f64,
    pub(crate) pyy: f64,
}

/// Points whose RMS spread is below this fraction of their magnitude count as coincident.
const COINCIDENT: f64 = 1e-10;
/// Second-moment eigenvalue ratio below which points count as collinear
/// (a thickness below 3·10⁻⁵ of the length).
const COLLINEAR: f64 = 1e-9;

impl Moments {
    /// Computes the moments, checking counts, lengths, finiteness and coincidence.
    pub(crate) fn new(model: Model, commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> Result<Self, MathError> {
        if commanded.len() != observed.len() {
            return Err(MathError::LengthMismatch { commanded: commanded.len(), observed: observed.len() });
        }
        let len = commanded.len();
        let needed = model.min_points();
        if len < needed {
            return Err(MathError::TooFewPoints { model: model.name(), needed, got: len });
        }
        let mut sn = Vector2::zeros();
        let mut so = Vector2::zeros();
        for (n, o) in commanded.iter().zip(observed) {
            sn += n.coords;
            so += o.coords;
        }
        #[allow(clippy::cast_precision_loss)] // point counts are far below 2^52
        let inv = 1.0 / len as f64;
        let cn = sn * inv;
        let co = so * inv;
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        let (mut pxx, mut pxy, mut pyx, mut pyy) = (0.0, 0.0, 0.0, 0.0);
        for (n, o) in commanded.iter().zip(observed) {
            let a = n.coords - cn;
            let q = o.coords - co;
            sxx += a.x * a.x;
            sxy += a.x * a.y;
            syy += a.y * a.y;
            pxx += a.x * q.x;
            pxy += a.x * q.y;
            pyx += a.y * q.x;
            pyy += a.y * q.y;
        }
        if !(cn.x.is_finite() && cn.y.is_finite() && sxx.is_finite() && syy.is_finite() && sxy.is_finite()) {
            return Err(MathError::NonFinite { what: "a commanded point" });
        }
        if !(co.x.is_finite()
            && co.y.is_finite()
            && pxx.is_finite()
            && pxy.is_finite()
            && pyx.is_finite()
            && pyy.is_finite())
        {
            return Err(MathError::NonFinite { what: "an observed point" });
        }
        let spread2 = (sxx + syy) * inv;
        let magnitude = cn.x.abs().max(cn.y.abs());
        if spread2 == 0.0 || spread2.sqrt() <= COINCIDENT * magnitude {
            return Err(MathError::CoincidentPoints);
        }
        Ok(Moments { len, cn, co, sxx, sxy, syy, pxx, pxy, pyx, pyy })
    }

    /// Refuses (nearly) collinear commanded points: the 2×2 second-moment matrix must have rank 2.
    pub(crate) fn require_area(&self, model: Model) -> Result<(), MathError> {
        let half_tr = 0.5 * (self.sxx + self.syy);
        let r = (0.25 * (self.sxx - self.syy) * (self.sxx - self.syy) + self.sxy * self.sxy).sqrt();
        let lmax = half_tr + r;
        // λmin = det / λmax, computed without the cancellation of half_tr − r.
        let lmin = (self.sxx * self.syy - self.sxy * self.sxy) / lmax;
        if lmin <= COLLINEAR * lmax {
            return Err(MathError::CollinearPoints { model: model.name() });
        }
        Ok(())
    }

    /// Builds the [`Fit`], with a second pass for the residuals.
    pub(crate) fn finish(
        &self,
        model: Model,
        rotation: UnitComplex<f64>,
        scale: Vector2<f64>,
        shear: f64,
        commanded: &[Point2<f64>],
        observed: &[Point2<f64>],
    ) -> Result<Fit, MathError> {
        if !(rotation.re.is_finite()
            && rotation.im.is_finite()
            && scale.x.is_finite()
            && scale.y.is_finite()
            && shear.is_finite())
        {
            return Err(MathError::DegenerateObserved);
        }
        let (c, s) = (rotation.re, rotation.im);
        let l = Matrix2::new(c, -s, s, c) * Matrix2::new(scale.x, shear, 0.0, scale.y);
        let mut sum2 = 0.0;
        let mut max2: f64 = 0.0;
        for (n, o) in commanded.iter().zip(observed) {
            let r = l * (n.coords - self.cn) - (o.coords - self.co);
            let r2 = r.norm_squared();
            sum2 += r2;
            max2 = max2.max(r2);
        }
        #[allow(clippy::cast_precision_loss)]
        let rms = (sum2 / self.len as f64).sqrt();
        Ok(Fit {
            model,
            rotation,
            scale,
            shear,
            commanded_centroid: Point2::from(self.cn),
            observed_centroid: Point2::from(self.co),
            len: self.len,
            rms,
            max_residual: max2.sqrt(),
        })
    }
}

/// A unit complex from an unnormalised `(re, im)`; `None` when it has no direction.
#[inline]
pub(crate) fn unit(re: f64, im: f64, reference: f64) -> Option<UnitComplex<f64>> {
    let h = (re * re + im * im).sqrt();
    if h.is_nan() || h <= 1e-14 * reference || !h.is_finite() {
        return None;
    }
    Some(UnitComplex::new_unchecked(nalgebra::Complex::new(re / h, im / h)))
}

#[cfg(test)]
#[allow(clippy::float_cmp)]
mod tests;
