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
mod quality;
mod rectangle;
mod rigid;
mod similarity;

pub use affine::fit_affine;
pub use linear::{solve_linear, LinearFit};
pub use partial::{fit_piece, PartialFit, Piece};
pub use quality::{find_outlier, residual_sigma, Outlier, Prediction, Shared, MIN_MARKS_FOR_OUTLIERS};
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

    /// Solves this model from `commanded` to `observed`, with residuals.
    ///
    /// # Errors
    /// As the model's own fit function ([`fit_rectangle`], …).
    #[inline]
    pub fn fit(self, commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> Result<Fit, MathError> {
        // One function per model, each with a constant model, so that each keeps only the
        // moments its closed form reads. This dispatch is `#[inline]` so that a caller naming
        // the model (`fit_similarity`, `Model::Similarity.fit`) calls its function directly.
        #[inline(always)]
        fn fit_as(model: Model, commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> Result<Fit, MathError> {
            let m = Moments::new(model, commanded, observed)?;
            let p = model.solve(&m)?;
            m.finish(model, p, commanded, observed)
        }
        fn rigid(c: &[Point2<f64>], o: &[Point2<f64>]) -> Result<Fit, MathError> {
            fit_as(Model::Rigid, c, o)
        }
        fn similarity(c: &[Point2<f64>], o: &[Point2<f64>]) -> Result<Fit, MathError> {
            fit_as(Model::Similarity, c, o)
        }
        fn rectangle(c: &[Point2<f64>], o: &[Point2<f64>]) -> Result<Fit, MathError> {
            fit_as(Model::Rectangle, c, o)
        }
        fn affine(c: &[Point2<f64>], o: &[Point2<f64>]) -> Result<Fit, MathError> {
            fit_as(Model::Affine, c, o)
        }
        match self {
            Model::Rigid => rigid(commanded, observed),
            Model::Similarity => similarity(commanded, observed),
            Model::Rectangle => rectangle(commanded, observed),
            Model::Affine => affine(commanded, observed),
        }
    }

    /// Solves this model's parameters only: one pass over the points, no residual pass. For
    /// tight loops that do not need the RMS; [`Model::fit`] gives the same parameters.
    ///
    /// # Errors
    /// As [`Model::fit`].
    #[inline]
    pub fn transform(self, commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> Result<Transform, MathError> {
        // Dispatched as in `fit`.
        #[inline(always)]
        fn transform_as(
            model: Model,
            commanded: &[Point2<f64>],
            observed: &[Point2<f64>],
        ) -> Result<Transform, MathError> {
            let m = Moments::new(model, commanded, observed)?;
            let p = model.solve(&m)?;
            p.check(model)?;
            Ok(Transform {
                model,
                rotation: p.rotation,
                scale: p.scale,
                shear: p.shear,
                commanded_centroid: Point2::from(m.cn),
                observed_centroid: Point2::from(m.co),
            })
        }
        fn rigid(c: &[Point2<f64>], o: &[Point2<f64>]) -> Result<Transform, MathError> {
            transform_as(Model::Rigid, c, o)
        }
        fn similarity(c: &[Point2<f64>], o: &[Point2<f64>]) -> Result<Transform, MathError> {
            transform_as(Model::Similarity, c, o)
        }
        fn rectangle(c: &[Point2<f64>], o: &[Point2<f64>]) -> Result<Transform, MathError> {
            transform_as(Model::Rectangle, c, o)
        }
        fn affine(c: &[Point2<f64>], o: &[Point2<f64>]) -> Result<Transform, MathError> {
            transform_as(Model::Affine, c, o)
        }
        match self {
            Model::Rigid => rigid(commanded, observed),
            Model::Similarity => similarity(commanded, observed),
            Model::Rectangle => rectangle(commanded, observed),
            Model::Affine => affine(commanded, observed),
        }
    }

    #[inline(always)]
    fn solve(self, m: &Moments) -> Result<LinearPart, MathError> {
        match self {
            Model::Rigid => rigid::solve(m),
            Model::Similarity => similarity::solve(m),
            Model::Rectangle => rectangle::solve(m),
            Model::Affine => affine::solve(m),
        }
    }
}

impl std::fmt::Display for Model {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A model's parameters without residuals (from [`Model::transform`]): `o ≈ L·(n − n̄) + ō`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transform {
    /// Which model was solved.
    pub model: Model,
    /// Rotation `R(θ)`, counter-clockwise seen from +Z.
    pub rotation: UnitComplex<f64>,
    /// `(sx, sy)`: scale along the commanded X and Y axes (dimensionless; 1 = true size).
    pub scale: Vector2<f64>,
    /// Shear of `U = [[sx, shear], [0, sy]]` (dimensionless); 0 for every model but affine.
    pub shear: f64,
    /// Centroid `n̄` of the commanded points, machine units.
    pub commanded_centroid: Point2<f64>,
    /// Centroid `ō` of the observed points, machine units.
    pub observed_centroid: Point2<f64>,
}

/// The model-specific part of a solution: the linear part of the fitted map, as rotation, scales
/// and shear and as the matrix `L`.
///
/// `linear` is `L = R(θ)·[[sx, shear], [0, sy]]` as the residual pass needs it. A model may fill
/// it straight from the moments (similarity does, with no square root), so the residual pass
/// need not wait for the square root and divisions that split `L` into rotation and scales.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LinearPart {
    rotation: UnitComplex<f64>,
    scale: Vector2<f64>,
    shear: f64,
    linear: Matrix2<f64>,
}

impl LinearPart {
    /// Parameters whose `L` is built from the rotation and `U = [[sx, shear], [0, sy]]`.
    #[inline(always)]
    fn from_parts(rotation: UnitComplex<f64>, scale: Vector2<f64>, shear: f64) -> LinearPart {
        let (c, s) = (rotation.re, rotation.im);
        let linear = Matrix2::new(c * scale.x, c * shear - s * scale.y, s * scale.x, s * shear + c * scale.y);
        LinearPart { rotation, scale, shear, linear }
    }

    /// Refuses parameters no alignment can use: non-finite, or a scale outside
    /// `MIN_SCALE..1/MIN_SCALE`.
    ///
    /// A scale in range is finite, and for every model but affine finite scales imply finite
    /// parameters (the rotation comes from [`unit`], which only returns finite directions, and
    /// `L` and the shear are products of those), so the common case is two range tests; the
    /// full finiteness test runs for the affine model and, to pick the error, on failure.
    #[inline(always)]
    fn check(&self, model: Model) -> Result<(), MathError> {
        let in_range = LinearPart::scale_in_range;
        if in_range(self.scale.x) && in_range(self.scale.y) && (model != Model::Affine || self.is_finite()) {
            Ok(())
        } else {
            Err(self.refusal())
        }
    }

    /// Whether a scale's magnitude is within `MIN_SCALE..=1/MIN_SCALE` (so also finite).
    #[inline(always)]
    fn scale_in_range(s: f64) -> bool {
        (MIN_SCALE..=1.0 / MIN_SCALE).contains(&s.abs())
    }

    /// The error for parameters [`LinearPart::check`] refuses. By value, so that the common
    /// path need not store the parameters for it.
    #[cold]
    #[inline(never)]
    fn refusal(self) -> MathError {
        if !self.is_finite() {
            return MathError::DegenerateObserved;
        }
        MathError::DegenerateScale {
            scale_x: self.scale.x,
            scale_y: self.scale.y,
            min: MIN_SCALE,
            max: 1.0 / MIN_SCALE,
        }
    }

    fn is_finite(&self) -> bool {
        self.rotation.re.is_finite()
            && self.rotation.im.is_finite()
            && self.scale.x.is_finite()
            && self.scale.y.is_finite()
            && self.shear.is_finite()
            && self.linear.iter().all(|v| v.is_finite())
    }
}

/// A solved fit: the parameters, their quality, and the way back to the points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fit {
    /// The solved parameters (what [`Model::transform`] gives without the residual pass).
    pub transform: Transform,
    /// Number of point pairs the fit used.
    pub len: usize,
    /// Root-mean-square residual length `sqrt(Σ‖rᵢ‖² / N)`, machine units.
    pub rms: f64,
    /// Largest residual length, machine units.
    pub max_residual: f64,
}

impl Transform {
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

    /// Where the transform puts commanded point `n` (machine units).
    #[must_use]
    pub fn apply(&self, n: Point2<f64>) -> Point2<f64> {
        self.observed_centroid + self.linear() * (n - self.commanded_centroid)
    }

    /// The G51 → G68 → G52 chain that executes this transform, rotating about the commanded
    /// centroid; `None` for an affine fit, whose shear those modals cannot express.
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

impl Fit {
    /// Per-point residuals `apply(nᵢ) − oᵢ`, machine units, in input order.
    ///
    /// Pass the same slices the fit was solved from.
    #[must_use]
    pub fn residuals(&self, commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> Vec<Vector2<f64>> {
        let t = &self.transform;
        let l = t.linear();
        commanded
            .iter()
            .zip(observed)
            .map(|(n, o)| l * (n - t.commanded_centroid) - (o - t.observed_centroid))
            .collect()
    }
}

/// Centred moments of a point-pair set: the only thing every closed form needs.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Moments {
    pub(crate) len: usize,
    /// `1 / len`.
    pub(crate) inv_len: f64,
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
/// Points whose RMS spread is below this, machine units, count as coincident whatever their
/// magnitude (10⁻⁹ in or mm is far below any machine's resolution).
pub const MIN_SPREAD: f64 = 1e-9;
/// The largest coordinate magnitude a fit accepts, machine units: [`crate::bounds`]' (the fit's
/// squared sums stay far from overflow).
pub use crate::bounds::MAX_COORDINATE;
/// A fitted scale magnitude outside `MIN_SCALE..1/MIN_SCALE` is refused: it means collapsed or
/// collinear observed points, and G51 with 10 decimals would print it as 0.
pub const MIN_SCALE: f64 = 1e-6;
/// Second-moment eigenvalue ratio below which points count as collinear
/// (a thickness below 3·10⁻⁵ of the length).
const COLLINEAR: f64 = 1e-9;

impl Moments {
    /// Computes the moments, checking counts, lengths, finiteness and coincidence.
    #[inline(always)]
    pub(crate) fn new(model: Model, commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> Result<Self, MathError> {
        if commanded.len() != observed.len() {
            return Err(MathError::LengthMismatch { commanded: commanded.len(), observed: observed.len() });
        }
        let len = commanded.len();
        let needed = model.min_points();
        if len < needed {
            return Err(MathError::TooFewPoints { model: model.name(), needed, got: len });
        }
        if let (Ok(n), Ok(o)) = (<&[Point2<f64>; 4]>::try_from(commanded), <&[Point2<f64>; 4]>::try_from(observed)) {
            if let Some(m) = Self::of_four(n, o) {
                return m.spread_checked();
            }
        }
        // One pass over the points, with sums taken relative to the first pair: as exact as a
        // two-pass centring (the reference lies inside the cloud, so nothing cancels beyond the
        // spread itself) but half the memory traffic.
        let (n0, o0) = (commanded[0].coords, observed[0].coords);
        let (mut sax, mut say, mut sqx, mut sqy) = (0.0, 0.0, 0.0, 0.0);
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        let (mut pxx, mut pxy, mut pyx, mut pyy) = (0.0, 0.0, 0.0, 0.0);
        // The largest coordinate magnitude, per axis, commanded and observed together (which
        // side it was on is only looked up when it is too large). `if a > b { a } else { b }`
        // is one `maxsd`/`maxpd`, where `f64::max` adds a NaN test; a NaN coordinate is caught
        // through the centroids instead.
        let (mut mag_x, mut mag_y): (f64, f64) = (0.0, 0.0);
        for (n, o) in commanded.iter().zip(observed) {
            mag_x = fast_max(mag_x, fast_max(n.x.abs(), o.x.abs()));
            mag_y = fast_max(mag_y, fast_max(n.y.abs(), o.y.abs()));
            let (ax, ay) = (n.x - n0.x, n.y - n0.y);
            let (qx, qy) = (o.x - o0.x, o.y - o0.y);
            sax += ax;
            say += ay;
            sqx += qx;
            sqy += qy;
            sxx += ax * ax;
            sxy += ax * ay;
            syy += ay * ay;
            pxx += ax * qx;
            pxy += ax * qy;
            pyx += ay * qx;
            pyy += ay * qy;
        }
        let inv = 1.0 / len as f64;
        let (mx, my, mqx, mqy) = (sax * inv, say * inv, sqx * inv, sqy * inv);
        let cn = Vector2::new(n0.x + mx, n0.y + my);
        let co = Vector2::new(o0.x + mqx, o0.y + mqy);
        sxx -= sax * mx;
        sxy -= sax * my;
        syy -= say * my;
        pxx -= sax * mqx;
        pxy -= sax * mqy;
        pyx -= say * mqx;
        pyy -= say * mqy;
        // Any NaN or infinite coordinate reaches the centroids (NaN and ∞ survive addition), so
        // their sum is finite only if every coordinate is (a finite sum that overflows falls to
        // the exact test below); overflow of the products is caught on the result in `finish`.
        // One test for the common case; `refuse_input` picks the error in the order the checks
        // are documented: non-finite commanded, non-finite observed, then too large.
        if !((cn.x + cn.y + co.x + co.y).is_finite() && fast_max(mag_x, mag_y) <= MAX_COORDINATE) {
            if let Some(e) = refuse_input(commanded, observed) {
                return Err(e);
            }
        }
        Moments { len, inv_len: inv, cn, co, sxx, sxy, syy, pxx, pxy, pyx, pyy }.spread_checked()
    }

    /// The moments of exactly four pairs, the usual alignment (four marks), in straight-line
    /// code: no loop and no division by the count. `None` when the points are not cleared by
    /// its quick input test; [`Moments::new`] then takes the general pass, whose exact checks
    /// pick the error (or accept the points). The spread check is left to the caller.
    ///
    /// The centring is the exact two-pass one (the centroids first, then the sums of the
    /// centred products), which a fixed count makes as cheap as the general path's one pass.
    /// The input test uses those sums instead of a per-coordinate maximum: every coordinate is
    /// its centroid plus its deviation, the centroid's is at most `|n̄ₓ| + |n̄_y| + |ōₓ| + |ō_y|`
    /// and the deviation at most the root of the sum of all squared deviations, commanded and
    /// observed; when both are at most `MAX_COORDINATE / 2` (the second less 1 % for
    /// rounding), no coordinate is beyond the bound. A NaN or infinite coordinate makes a
    /// centroid NaN or infinite, which fails the test too. So the points it does not clear are
    /// the bad ones and those within about a factor of two of the bound.
    #[inline(always)]
    fn of_four(n: &[Point2<f64>; 4], o: &[Point2<f64>; 4]) -> Option<Self> {
        /// The bound on the centroids' magnitudes, and on the root of the squared deviations.
        const HALF: f64 = 0.5 * MAX_COORDINATE;
        const SPREAD: f64 = 0.99 * HALF;
        let inv = 0.25;
        let cn = sum_of_four(n.map(|p| p.coords)) * inv;
        let co = sum_of_four(o.map(|p| p.coords)) * inv;
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        let (mut pxx, mut pxy, mut pyx, mut pyy) = (0.0, 0.0, 0.0, 0.0);
        let (mut qxx, mut qyy) = (0.0, 0.0);
        // A loop over arrays, which the compiler unrolls and pairs into SSE2 products; written
        // as `Vector2` products instead, it paired lanes across points and came out longer.
        for (n, o) in n.iter().zip(o) {
            let (ax, ay) = (n.x - cn.x, n.y - cn.y);
            let (qx, qy) = (o.x - co.x, o.y - co.y);
            sxx += ax * ax;
            syy += ay * ay;
            sxy += ax * ay;
            pxx += ax * qx;
            pyy += ay * qy;
            pxy += ax * qy;
            pyx += ay * qx;
            qxx += qx * qx;
            qyy += qy * qy;
        }
        let centroids = (cn.x.abs() + cn.y.abs()) + (co.x.abs() + co.y.abs());
        let deviations = (sxx + syy) + (qxx + qyy);
        if !(centroids <= HALF && deviations <= SPREAD * SPREAD) {
            return None;
        }
        Some(Moments { len: 4, inv_len: inv, cn, co, sxx, sxy, syy, pxx, pxy, pyx, pyy })
    }

    /// Refuses coincident commanded points: an RMS spread below [`MIN_SPREAD`] or below
    /// [`COINCIDENT`] times the centroid's magnitude. The input checks have passed, so the
    /// centroid is finite.
    #[inline(always)]
    fn spread_checked(self) -> Result<Self, MathError> {
        let spread2 = (self.sxx + self.syy) * self.inv_len;
        // The centroid is finite here, so `fast_max` needs no NaN test; `floor` ≥ MIN_SPREAD > 0,
        // so a zero spread is refused too.
        let magnitude = fast_max(self.cn.x.abs(), self.cn.y.abs());
        let floor = fast_max(COINCIDENT * magnitude, MIN_SPREAD);
        if spread2 <= floor * floor {
            return Err(MathError::CoincidentPoints);
        }
        Ok(self)
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
    #[inline(always)]
    pub(crate) fn finish(
        &self,
        model: Model,
        p: LinearPart,
        commanded: &[Point2<f64>],
        observed: &[Point2<f64>],
    ) -> Result<Fit, MathError> {
        p.check(model)?;
        let LinearPart { rotation, scale, shear, linear } = p;
        // L spelled out so the loop below stays in registers.
        let (l11, l12, l21, l22) = (linear[(0, 0)], linear[(0, 1)], linear[(1, 0)], linear[(1, 1)]);
        let (cnx, cny, cox, coy) = (self.cn.x, self.cn.y, self.co.x, self.co.y);
        // The sum and the largest of the squared residuals. A few points (the four marks) take
        // this plain loop; more take `residual_sums`, out of line so that its registers cost
        // the few-point path nothing (inline, it added ten instructions to the 4-point fit).
        let (sum2, max2) = if commanded.len() < 8 {
            let mut sum2 = 0.0;
            let mut max2: f64 = 0.0;
            for (n, o) in commanded.iter().zip(observed) {
                let (ax, ay) = (n.x - cnx, n.y - cny);
                let rx = l11 * ax + l12 * ay - (o.x - cox);
                let ry = l21 * ax + l22 * ay - (o.y - coy);
                let r2 = rx * rx + ry * ry;
                sum2 += r2;
                if r2 > max2 {
                    max2 = r2;
                }
            }
            (sum2, max2)
        } else {
            residual_sums([l11, l12, l21, l22], [cnx, cny, cox, coy], commanded, observed)
        };
        let rms = (sum2 * self.inv_len).sqrt();
        if !rms.is_finite() {
            return Err(MathError::NonFinite { what: "a residual (coordinates too large)" });
        }
        Ok(Fit {
            transform: Transform {
                model,
                rotation,
                scale,
                shear,
                commanded_centroid: Point2::from(self.cn),
                observed_centroid: Point2::from(self.co),
            },
            len: self.len,
            rms,
            max_residual: max2.sqrt(),
        })
    }
}

/// The sum and the largest of the squared residuals `‖L·(n − n̄) − (o − ō)‖²` (the loop in
/// [`Moments::finish`], `l = [L₁₁, L₁₂, L₂₁, L₂₂]`, `c = [n̄ₓ, n̄_y, ōₓ, ō_y]`), two points per
/// step, one in each SSE2 lane, summed and maximised in two independent chains: one point per
/// step spent four shuffles a point and waited on a single chain of additions (1.5 against
/// 1.1 ns a point). The maximum is `if r2 > max { r2 } else { max }` as in the plain loop: a NaN
/// residual never becomes it, and the sum carries it to the error in [`Moments::finish`].
#[inline(never)]
fn residual_sums(l: [f64; 4], c: [f64; 4], commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> (f64, f64) {
    let [l11, l12, l21, l22] = l;
    let [cnx, cny, cox, coy] = c;
    let residual2 = |n: &Point2<f64>, o: &Point2<f64>| {
        let (ax, ay) = (n.x - cnx, n.y - cny);
        let rx = l11 * ax + l12 * ay - (o.x - cox);
        let ry = l21 * ax + l22 * ay - (o.y - coy);
        rx * rx + ry * ry
    };
    let (mut sum2, mut max2) = ([0.0; 2], [0.0; 2]);
    let (pairs_n, pairs_o) = (commanded.chunks_exact(2), observed.chunks_exact(2));
    let last = pairs_n.remainder().first().zip(pairs_o.remainder().first());
    for (n, o) in pairs_n.zip(pairs_o) {
        let r2 = [residual2(&n[0], &o[0]), residual2(&n[1], &o[1])];
        for k in 0..2 {
            sum2[k] += r2[k];
            max2[k] = fast_max(r2[k], max2[k]);
        }
    }
    if let Some((n, o)) = last {
        let r2 = residual2(n, o);
        sum2[0] += r2;
        max2[0] = fast_max(r2, max2[0]);
    }
    (sum2[0] + sum2[1], fast_max(max2[0], max2[1]))
}

/// `(v₀ + v₁) + (v₂ + v₃)`.
#[inline(always)]
fn sum_of_four<T: std::ops::Add<Output = T> + Copy>(v: [T; 4]) -> T {
    (v[0] + v[1]) + (v[2] + v[3])
}

/// `a` if `a > b`, else `b`: one `maxsd` (no NaN handling, unlike `f64::max`).
#[inline(always)]
fn fast_max(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

/// The error for points whose centroids are not finite or with a coordinate beyond
/// [`MAX_COORDINATE`], in that order, commanded before observed; `None` if there is none (the
/// fast test in [`Moments::new`] only said there might be).
#[cold]
#[inline(never)]
fn refuse_input(commanded: &[Point2<f64>], observed: &[Point2<f64>]) -> Option<MathError> {
    // The points themselves, not the centroids: a sum of finite values near 1e308 overflows,
    // and such a point is too large, not "not a finite number".
    let non_finite = |points: &[Point2<f64>]| points.iter().any(|p| !(p.x.is_finite() && p.y.is_finite()));
    if non_finite(commanded) {
        return Some(MathError::NonFinite { what: "a commanded point" });
    }
    if non_finite(observed) {
        return Some(MathError::NonFinite { what: "an observed point" });
    }
    for (what, points) in [("a commanded point", commanded), ("an observed point", observed)] {
        let value = points.iter().fold(0.0, |m: f64, p| m.max(p.x.abs()).max(p.y.abs()));
        if value > MAX_COORDINATE {
            return Some(MathError::CoordinateTooLarge { what, value, limit: MAX_COORDINATE });
        }
    }
    None
}

/// A unit complex from an unnormalised `(re, im)`, with the length it had; `None` when it has
/// no direction.
#[inline]
pub(crate) fn unit(re: f64, im: f64, reference: f64) -> Option<(UnitComplex<f64>, f64)> {
    let h = (re * re + im * im).sqrt();
    if h.is_nan() || h <= 1e-14 * reference || !h.is_finite() {
        return None;
    }
    let inv = 1.0 / h;
    Some((UnitComplex::new_unchecked(nalgebra::Complex::new(re * inv, im * inv)), h))
}

#[cfg(test)]
mod tests;
