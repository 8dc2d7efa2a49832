//! Finds a printed fiducial mark — a dot, a ring or a cross — in a grayscale image, to a
//! fraction of a pixel, so an ordinary camera can align a CNC job.
//!
//! Pure: no I/O, no threads, no crate of ours. The input is a borrowed 8- or 16-bit
//! [`GrayImage`] and a [`MarkSpec`] (kind, expected size in pixels with a tolerance, polarity);
//! the answer is a [`Located`]: the [`Mark`] found, or why none was (no candidate, several,
//! cut by the border, size out of range). It never guesses: with two marks in view it refuses.
//!
//! Pixel convention: (0, 0) is the centre of the top-left pixel, x to the right, y down.
//!
//! **Method.** (1) Coarse search: the image is block-averaged to about 8 blocks across the
//! smallest accepted mark, compared with its local mean (uneven light cancels), and cut at three
//! contrast levels into blobs; blobs of a plausible size are candidates. (2) Each candidate is
//! refined by a least-squares fit of a blurred-shape model with planar background and contrast
//! (a Gaussian-blurred disc, ring or cross, each pixel the average over its square) to the
//! pixels near its edges, by damped Gauss–Newton, coarse to fine — the maximum-likelihood centre under Gaussian noise. (3) A fit is a mark only when its contrast,
//! its polarity, its agreement with the pixels overall *and in each of eight sectors around it*
//! hold up; its size then decides between found and out of range.
//!
//! **Bounds.** The work grows with the pixels and the blobs, never with their square; the
//! memory is [`search_bytes`] (about 16 bytes per block of the coarse search), checked before
//! anything is allocated against [`MAX_SEARCH_BYTES`] ([`check_size`] lets a caller check an
//! image's size before decoding it); more than [`MAX_BLOBS`] mark-sized blobs are refused as
//! [`NotFoundReason::Cluttered`]; and [`locate_within`] stops at a [`Budget`]'s deadline
//! ([`LocateError::Deadline`]). None of them ever turns into a reported mark.
//!
//! `render` (the `render` feature) draws such marks with known truth (anti-aliased, blurred,
//! lit, noisy) for tests, benchmarks and the simulator; the finder does not need it.
//!
//! ```
//! use vision_locate::render::{render, Depth, PlacedMark, Scene, Shape};
//! use vision_locate::{locate, Located, MarkKind, MarkSpec, Polarity};
//!
//! let scene = Scene {
//!     marks: vec![PlacedMark { shape: Shape::Dot { diameter: 40.0 }, x: 161.3, y: 118.7, reflectance: 0.1 }],
//!     blur_sigma: 1.5,
//!     noise_sigma: 2.0,
//!     seed: 1,
//!     ..Scene::blank(320, 240, Depth::Eight)
//! };
//! let image = render(&scene)?;
//! let spec = MarkSpec::new(MarkKind::Dot, 40.0, 0.2, Polarity::DarkOnLight)?;
//! let Located::Found(mark) = locate(&image.view(), &spec)? else { panic!("the dot is in view") };
//! assert!((mark.x - 161.3).abs() < 0.02 && (mark.y - 118.7).abs() < 0.02);
//! assert!((mark.diameter - 40.0).abs() < 0.5);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod detect;
mod edge;
mod fit;
mod image;
#[cfg(any(test, feature = "render"))]
pub mod render;
mod spec;
mod special;

use std::fmt;
use std::time::Instant;

pub use detect::MAX_BLOBS;
pub use image::{GrayImage, ImageError, OwnedImage, OwnedPixels, Pixels};
pub use spec::{MarkKind, MarkSpec, Polarity, SpecError, UnknownMarkKind, MIN_DIAMETER_PX};

use detect::{block_factor, search, Cut};
use fit::{fit, Annulus, Cross, Disc, FitFailure, FitResult, Img};

/// A mark found in the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mark {
    /// Centre x, px (0 = centre of the left column).
    pub x: f64,
    /// Centre y, px (0 = centre of the top row, y down).
    pub y: f64,
    /// Measured size, px: a dot's or ring's outer diameter, a cross's tip-to-tip bar length.
    pub diameter: f64,
    /// A cross's bar direction, radians from +x towards +y, in [−π/4, π/4); `None` for round
    /// marks.
    pub angle: Option<f64>,
    /// Agreement of the fitted model with the pixels around the mark's edges: the coefficient
    /// of determination, 0 … 1 (1 = perfect; a mark is only reported above 0.8).
    pub score: f64,
}

/// Why no mark is reported.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NotFoundReason {
    /// Nothing in view looks like the mark.
    NoCandidate,
    /// Nothing of the expected size looks like the mark, but a blob shaped like one, `about` px
    /// across (to the coarse search's block), is in view: the diameter given is likely wrong.
    OtherSize {
        /// The blob's size, px, to a block of the coarse search.
        about: f64,
        /// The smallest size accepted, px.
        min: f64,
        /// The largest size accepted, px.
        max: f64,
    },
    /// More than one mark in view (`count` of them); none is picked.
    SeveralCandidates {
        /// How many marks were found.
        count: usize,
    },
    /// A mark-like blob is cut by the image border.
    Clipped,
    /// A mark of the right kind is in view but its size, `diameter` px, is outside the spec's
    /// tolerance, `min` … `max` px.
    SizeOutOfRange {
        /// The measured size, px.
        diameter: f64,
        /// The smallest size accepted, px.
        min: f64,
        /// The largest size accepted, px.
        max: f64,
    },
    /// The search was cut off: more than `limit` ([`MAX_BLOBS`]) blobs of about the mark's size
    /// are in view, so it cannot show exactly one mark.
    Cluttered {
        /// The most blobs one search keeps.
        limit: usize,
    },
}

impl fmt::Display for NotFoundReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NotFoundReason::NoCandidate => write!(f, "no mark in view — check the position, focus and lighting"),
            NotFoundReason::OtherSize { about, min, max } => write!(
                f,
                "no mark of {min:.1}–{max:.1} px in view, but a blob about {about:.0} px across is — check the \
                 diameter setting (or the position, focus and lighting)"
            ),
            NotFoundReason::SeveralCandidates { count } => {
                write!(f, "{count} marks in view — move closer or mask the others; none was picked")
            }
            NotFoundReason::Clipped => write!(f, "the mark is cut by the image border — centre it in the view"),
            NotFoundReason::SizeOutOfRange { diameter, min, max } => write!(
                f,
                "a mark of {diameter:.1} px is in view, but {min:.1}–{max:.1} px was expected — check the diameter \
                 setting"
            ),
            NotFoundReason::Cluttered { limit } => write!(
                f,
                "the search was cut off: more than {limit} mark-sized blobs in view — check the diameter setting, \
                 or narrow the search to the mark"
            ),
        }
    }
}

/// The finder's judgment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Located {
    /// Exactly one mark of the right kind and size is in view.
    Found(Mark),
    /// No mark is reported, for this reason.
    NotFound(NotFoundReason),
}

/// Why the finder could not run at all (the input is unusable, as opposed to "no mark").
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum LocateError {
    /// The mark description is invalid.
    Spec(SpecError),
    /// Searching the image would take more memory than [`MAX_SEARCH_BYTES`] (see
    /// [`search_bytes`]); nothing was allocated.
    TooLarge {
        /// Image width, px.
        width: usize,
        /// Image height, px.
        height: usize,
        /// The coarse search's block size the spec implies, px.
        factor: usize,
        /// The memory the search would take, bytes.
        needed: u64,
        /// The limit, bytes.
        limit: u64,
        /// The smallest mark diameter, px, at the same tolerance, whose larger blocks bring the
        /// search under the limit.
        diameter_within: f64,
    },
    /// The search ran past [`Budget::deadline`] and was cut off; nothing is known of the mark.
    Deadline,
}

impl fmt::Display for LocateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LocateError::Spec(e) => e.fmt(f),
            LocateError::TooLarge { width, height, factor, needed, limit, diameter_within } => {
                let mb = |b: u64| b.div_ceil(1 << 20);
                write!(
                    f,
                    "searching a {width} × {height} image at blocks of {factor} px needs {} MiB, over the finder's {} \
                     MiB limit — crop the image around the mark, or give a mark diameter of at least {diameter_within:.0} \
                     px",
                    mb(*needed),
                    mb(*limit)
                )
            }
            LocateError::Deadline => {
                write!(f, "the search was cut off at its deadline before it finished; nothing is known of the mark")
            }
        }
    }
}

impl std::error::Error for LocateError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            LocateError::Spec(e) => Some(e),
            LocateError::TooLarge { .. } | LocateError::Deadline => None,
        }
    }
}

impl From<SpecError> for LocateError {
    fn from(e: SpecError) -> Self {
        LocateError::Spec(e)
    }
}

/// The most memory one search may take, bytes ([`search_bytes`]): 1 GiB. A larger search is
/// refused before anything is allocated ([`LocateError::TooLarge`]).
pub const MAX_SEARCH_BYTES: u64 = 1 << 30;

/// The most heap memory, bytes, the search of a `width` × `height` image for `spec` takes at
/// once, beyond the image itself: about 16 bytes per block of the coarse search (a block is
/// [`MarkSpec::min_diameter`]` / 6` px square, at least 1 px: a small diameter on a large image
/// is what costs) and a few MiB for the kept blobs ([`MAX_BLOBS`]).
pub fn search_bytes(width: usize, height: usize, spec: &MarkSpec) -> u64 {
    detect::search_bytes(width, height, spec)
}

/// Checks that searching a `width` × `height` image for `spec` stays within
/// [`MAX_SEARCH_BYTES`], before any pixel is decoded or searched: a caller that reads an
/// image's size from its header can refuse it unread.
///
/// # Errors
/// [`LocateError::Spec`] for an invalid spec, [`LocateError::TooLarge`] over the limit.
pub fn check_size(width: usize, height: usize, spec: &MarkSpec) -> Result<(), LocateError> {
    spec.validate()?;
    let needed = search_bytes(width, height, spec);
    if needed <= MAX_SEARCH_BYTES {
        return Ok(());
    }
    // Blocks of k px need a smallest diameter of at least 6k − 3 px (the block size rounds); at
    // blocks as large as the image the search is tiny, so one k always fits.
    let diameter = |k: usize| ((6 * k - 3) as f64 / (1.0 - spec.tolerance)).ceil();
    let largest = width.max(height);
    let diameter_within = (block_factor(spec) + 1..=largest)
        .map(diameter)
        .find(|&d| search_bytes(width, height, &spec.with_diameter(d)) <= MAX_SEARCH_BYTES)
        .unwrap_or_else(|| diameter(largest));
    Err(LocateError::TooLarge {
        width,
        height,
        factor: block_factor(spec),
        needed,
        limit: MAX_SEARCH_BYTES,
        diameter_within,
    })
}

/// Bounds on one search beyond the fixed ones ([`MAX_BLOBS`], [`MAX_SEARCH_BYTES`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Budget {
    /// Once this instant has passed, the search stops and answers [`LocateError::Deadline`]
    /// (it looks at the clock between its stages, every 65 536 pixels of its labelling and
    /// before each candidate's fit); `None`: no deadline.
    pub deadline: Option<Instant>,
}

impl Budget {
    /// A budget that ends at `deadline`.
    pub fn until(deadline: Instant) -> Budget {
        Budget { deadline: Some(deadline) }
    }

    /// Whether the deadline has passed.
    pub(crate) fn passed(&self) -> bool {
        self.deadline.is_some_and(|d| Instant::now() >= d)
    }
}

/// Finds the one mark described by `spec` in `image` (see the crate docs for the method), with
/// no deadline: [`locate_within`] with the default [`Budget`].
///
/// # Errors
/// As [`locate_within`].
pub fn locate(image: &GrayImage<'_>, spec: &MarkSpec) -> Result<Located, LocateError> {
    locate_within(image, spec, &Budget::default())
}

/// Finds the one mark described by `spec` in `image` within `budget`. Its work grows with the
/// image's pixels and blobs (never with their square), its memory is [`search_bytes`], at
/// most [`MAX_SEARCH_BYTES`], and it keeps at most [`MAX_BLOBS`] mark-sized blobs
/// ([`NotFoundReason::Cluttered`] beyond).
///
/// # Errors
/// [`LocateError::Spec`] for an invalid spec, [`LocateError::TooLarge`] for an image whose
/// search would take more than [`MAX_SEARCH_BYTES`], [`LocateError::Deadline`] when the budget's
/// deadline passed before the search ended.
pub fn locate_within(image: &GrayImage<'_>, spec: &MarkSpec, budget: &Budget) -> Result<Located, LocateError> {
    check_size(image.width(), image.height(), spec)?;
    match image.pixels() {
        Pixels::Gray8(d) => locate_in(&Img { w: image.width(), h: image.height(), data: d }, spec, 255.0, budget),
        Pixels::Gray16(d) => locate_in(&Img { w: image.width(), h: image.height(), data: d }, spec, 65535.0, budget),
    }
}

/// A verified fit: the mark and its size judgement.
struct Verified {
    mark: Mark,
}

fn locate_in<T: Copy + Into<f64> + Into<u32>>(
    img: &Img<'_, T>,
    spec: &MarkSpec,
    full_scale: f64,
    budget: &Budget,
) -> Result<Located, LocateError> {
    let found = match search(img, spec, full_scale, budget) {
        Ok(found) => found,
        Err(Cut::Deadline) => return Err(LocateError::Deadline),
        Err(Cut::Cluttered) => return Ok(Located::NotFound(NotFoundReason::Cluttered { limit: MAX_BLOBS })),
    };
    let deadline = || if budget.passed() { Err(LocateError::Deadline) } else { Ok(()) };
    let mut marks: Vec<Verified> = Vec::new();
    let mut clipped = false;
    for c in &found.candidates {
        // A blob that may be part of the mark falls back on the same mark's fuller blobs.
        deadline()?;
        let mut rr = refine(img, spec, c, found.noise, found.factor, full_scale);
        for alt in &c.alternates {
            if !matches!(rr, Ok(None) | Err(FitFailure::Diverged)) {
                break;
            }
            deadline()?;
            rr = refine(img, spec, alt, found.noise, found.factor, full_scale);
        }
        match rr {
            Ok(Some(v)) => {
                // The same mark reached from two blobs counts once.
                let r = v.mark.diameter / 4.0;
                if !marks.iter().any(|m| (m.mark.x - v.mark.x).hypot(m.mark.y - v.mark.y) < r) {
                    marks.push(v);
                }
            }
            // A blob at the border that does not fit as a whole mark is a cut one.
            Ok(None) | Err(FitFailure::Diverged) => clipped |= c.at_border,
            Err(FitFailure::Clipped) => clipped = true,
        }
    }
    let (dmin, dmax) = (spec.min_diameter(), spec.max_diameter());
    let (good, wrong): (Vec<&Verified>, Vec<&Verified>) =
        marks.iter().partition(|v| (dmin..=dmax).contains(&v.mark.diameter));
    Ok(match good.len() {
        1 => Located::Found(good[0].mark),
        0 => Located::NotFound(match (wrong.first(), found.other_size) {
            (Some(v), _) => NotFoundReason::SizeOutOfRange { diameter: v.mark.diameter, min: dmin, max: dmax },
            (None, _) if clipped => NotFoundReason::Clipped,
            (None, Some(about)) => NotFoundReason::OtherSize { about, min: dmin, max: dmax },
            (None, None) => NotFoundReason::NoCandidate,
        }),
        count => Located::NotFound(NotFoundReason::SeveralCandidates { count }),
    })
}

/// Least score (R² over all fitted pixels) of a reported mark.
const MIN_SCORE: f64 = 0.8;
/// Least R² in every one of the eight sectors: the edge must be there all round.
const MIN_SECTOR_SCORE: f64 = 0.5;

fn refine<T: Copy + Into<f64>>(
    img: &Img<'_, T>,
    spec: &MarkSpec,
    c: &detect::Candidate,
    noise: f64,
    factor: usize,
    full_scale: f64,
) -> Result<Option<Verified>, FitFailure> {
    let s0 = (0.4 * factor as f64).max(1.0);
    let (lo, hi) = (0.25 * spec.min_diameter(), 0.75 * spec.max_diameter());
    let r_area = (c.area / std::f64::consts::PI).sqrt();
    let scale = spec.diameter_px / 2.0;
    let (res, diameter, angle) = match spec.kind {
        MarkKind::Dot => {
            let r0 = r_area.clamp(lo, hi);
            let res = fit::<_, _, 10>(img, &Disc, &[c.x, c.y, r0, s0], scale)?;
            if !check_shape(&res, res.g[3] <= 0.35 * res.g[2]) {
                return Ok(None);
            }
            let d = 2.0 * res.g[2];
            (res, d, None)
        }
        MarkKind::Ring => {
            // An annulus has mean r² = (Ro² + Ri²)/2 and area π(Ro² − Ri²).
            let half = c.area / (2.0 * std::f64::consts::PI);
            let ro = (c.mean_r2 + half).sqrt().clamp(lo, hi);
            let ri = (c.mean_r2 - half).max(0.0).sqrt().clamp(0.2 * ro, ro - 1.0);
            // A wide start blur would wash a thin line out: start below its width.
            let s0 = s0.min(0.25 * (ro - ri)).max(0.5);
            let res = fit::<_, _, 11>(img, &Annulus, &[c.x, c.y, ro, ri, s0], scale)?;
            let (ro, ri, s) = (res.g[2], res.g[3], res.g[4]);
            if !check_shape(&res, ri >= 0.15 * ro && ro - ri >= 1.0 && s <= 0.35 * ro && s <= ro - ri) {
                return Ok(None);
            }
            (res, 2.0 * ro, None)
        }
        MarkKind::Cross => {
            let a0 = c.half_length.clamp(lo, hi);
            let w0 = (c.area / (8.0 * a0)).clamp(1.0, 0.4 * a0);
            let s0 = s0.min(0.5 * w0).max(0.5);
            let res = fit::<_, _, 12>(img, &Cross, &[c.x, c.y, c.angle, a0, w0, s0], scale)?;
            let (a, w, s) = (res.g[3], res.g[4], res.g[5]);
            if !check_shape(&res, w <= 0.45 * a && w >= 0.4 && s <= 0.5 * a) {
                return Ok(None);
            }
            let quarter = std::f64::consts::FRAC_PI_2;
            let angle = (res.g[2] + quarter / 2.0).rem_euclid(quarter) - quarter / 2.0;
            (res, 2.0 * a, Some(angle))
        }
    };
    // The pixels must agree: polarity, enough contrast over the noise, and the edge all round.
    let contrast = res.lin[3];
    let sign_ok = match spec.polarity {
        Polarity::DarkOnLight => contrast < 0.0,
        Polarity::LightOnDark => contrast > 0.0,
    };
    let enough = contrast.abs() >= (8.0 * noise).max(4.0 * full_scale / 255.0);
    let inside = (c.bbox[0] - factor as f64..=c.bbox[2] + factor as f64).contains(&res.g[0])
        && (c.bbox[1] - factor as f64..=c.bbox[3] + factor as f64).contains(&res.g[1]);
    if !(res.converged && sign_ok && enough && inside && res.r2 >= MIN_SCORE && res.min_sector_r2 >= MIN_SECTOR_SCORE) {
        return Ok(None);
    }
    Ok(Some(Verified { mark: Mark { x: res.g[0], y: res.g[1], diameter, angle, score: res.r2 } }))
}

fn check_shape(res: &FitResult, ok: bool) -> bool {
    ok && res.g.iter().all(|v| v.is_finite())
}

/// The Cramér–Rao bound (px) on the centre's x and y of a dot of `diameter` px, Gaussian blur
/// `blur_sigma` px (defocus; 0 = sharp), background `background` and contrast `contrast` grey
/// levels, under white noise of `noise` grey levels, all parameters unknown (centre, radius,
/// blur, background and contrast planes: those the finder fits), over the pixels the finder fits
/// on. The model is the finder's: each pixel the exact average over its square of the blurred
/// disc (edges taken as locally straight), which is how [`render`] draws a dot. `None` when the
/// information matrix is singular. For benchmarks: the best any unbiased finder can do on such
/// an image.
pub fn dot_crb(diameter: f64, blur_sigma: f64, background: f64, contrast: f64, noise: f64) -> Option<(f64, f64)> {
    let g = [0.0, 0.0, diameter / 2.0, blur_sigma.max(edge::S_MIN)];
    fit::crb(&Disc, &g, &[background, 0.0, 0.0, contrast, 0.0, 0.0], diameter / 2.0, noise)
}

#[cfg(test)]
#[expect(clippy::cast_possible_truncation, clippy::cast_sign_loss, reason = "test values are small and whole")]
mod tests {
    use super::*;
    use crate::fit::{band, solve, MAXP};
    use crate::render::{radiance, Clutter, Depth, PlacedMark, Scene, Shape};

    /// The finder's edge model is what the renderer draws: a straight edge rendered at several
    /// angles agrees with the model pixel by pixel — exactly when sharp; when blurred, as
    /// closely as the renderer's blur, a Gaussian sampled at whole pixels and applied to the
    /// pixels' coverage (a Riemann sum of the continuous blur the model has), allows: along an
    /// axis it is off by up to 0.6 % of the contrast at σ = 1 px, 0.04 % at 2.5 px.
    #[test]
    fn the_edge_model_is_the_rendered_edge() {
        let (bg, ink, level) = (0.8, 0.1, 0.95);
        let (b0, a0) = (255.0 * level * bg, 255.0 * level * (ink - bg));
        for (blur, tol) in [(0.0, 1e-4), (1.0, 7e-3), (1.5, 2.5e-3), (2.5, 5e-4)] {
            for phi in [0.0, 0.3, std::f64::consts::FRAC_PI_4, 1.1, 2.5, -2.0] {
                let (x0, y0) = (31.7, 32.2);
                let image = radiance(&Scene {
                    clutter: vec![Clutter::Edge { x: x0, y: y0, angle: phi, reflectance: ink }],
                    blur_sigma: blur,
                    background: bg,
                    ..Scene::blank(64, 64, Depth::Eight)
                })
                .unwrap();
                let (ny, nx) = phi.sin_cos();
                let profile = edge::Blur::new(blur.max(edge::S_MIN));
                let mut worst: f64 = 0.0;
                for yi in 12..52 {
                    for xi in 12..52 {
                        let t = (xi as f64 - x0) * nx + (yi as f64 - y0) * ny;
                        let m = profile.profile(nx, ny).at(t).m;
                        worst = worst.max(((image[yi * 64 + xi] - b0) / a0 - m).abs());
                    }
                }
                assert!(worst < tol, "blur {blur} φ {phi}: {worst} of the contrast");
            }
        }
    }

    /// The bound `dot_crb` computes is the rendered images' own: the Fisher information of the
    /// renderer's pixels (exact coverage, blur, light), differentiated numerically in the centre,
    /// the radius and the blur, with the same light planes, over the same pixels, agrees.
    #[test]
    fn the_bound_is_that_of_the_rendered_images() {
        let (bg, ink, level, noise) = (0.8, 0.1, 0.95, 2.0);
        let (b0, a0) = (255.0 * level * bg, 255.0 * level * (ink - bg));
        for (d, blur, cx, cy) in [(30.0, 0.0, 35.37, 34.81), (60.0, 0.0, 50.12, 49.55), (30.0, 1.0, 35.7, 35.2)] {
            let size = (d as usize) + 40;
            let image = |x: f64, y: f64, d: f64, blur: f64| {
                radiance(&Scene {
                    marks: vec![PlacedMark { shape: Shape::Dot { diameter: d }, x, y, reflectance: ink }],
                    blur_sigma: blur,
                    background: bg,
                    ..Scene::blank(size, size, Depth::Eight)
                })
                .unwrap()
            };
            let e = 1e-3;
            let slope = |p: Vec<f64>, m: Vec<f64>| p.iter().zip(&m).map(|(p, m)| (p - m) / (2.0 * e)).collect();
            let mut columns: Vec<Vec<f64>> = vec![
                slope(image(cx + e, cy, d, blur), image(cx - e, cy, d, blur)),
                slope(image(cx, cy + e, d, blur), image(cx, cy - e, d, blur)),
                slope(image(cx, cy, d + 2.0 * e, blur), image(cx, cy, d - 2.0 * e, blur)),
            ];
            // The blur is known at 0 (no image is sharper); elsewhere it is unknown, as in the fit.
            if blur > 0.0 {
                columns.push(slope(image(cx, cy, d, blur + e), image(cx, cy, d, blur - e)));
            }
            let ng = columns.len();
            let base = image(cx, cy, d, blur);
            let (r, s) = (d / 2.0, blur.max(edge::S_MIN));
            let mut h = [[0.0; MAXP]; MAXP];
            for yi in 0..size {
                for xi in 0..size {
                    let (x, y) = (xi as f64, yi as f64);
                    if ((x - cx).hypot(y - cy) - r).abs() > band(s) {
                        continue;
                    }
                    let k = yi * size + xi;
                    let (u, v, m) = ((x - cx) / r, (y - cy) / r, (base[k] - b0) / a0);
                    let mut j: Vec<f64> = columns.iter().map(|c| c[k]).collect();
                    j.extend([1.0, u, v, m, m * u, m * v]);
                    for a in 0..j.len() {
                        for c in 0..j.len() {
                            h[a][c] += j[a] * j[c] / (noise * noise);
                        }
                    }
                }
            }
            let all: Vec<usize> = (0..ng + 6).collect();
            let mut unit = [0.0; MAXP];
            unit[0] = 1.0;
            let rendered = solve(&h, &unit, &all).unwrap()[0].sqrt();
            let (model, _) = fit::crb(&Disc, &[cx, cy, r, s], &[b0, 0.0, 0.0, a0, 0.0, 0.0], r, noise).unwrap();
            let ratio = model / rendered;
            assert!((ratio - 1.0).abs() < 0.01, "d {d} blur {blur}: model {model} vs rendered {rendered}");
        }
    }
}
