//! Draws marks with known truth (the `render` feature): what a camera sees of a printed dot,
//! ring or cross, for the simulator's frames and the finder's tests and benchmarks.
//!
//! In order, each step exact or controlled: (1) **reflectance** (0 black, 1 white): the
//! background, an optional [`Texture`], the [`Clutter`], then the marks, each a signed distance
//! function whose pixels get their exact covered area (8 × 8 sub-squares, each cut by the
//! shape's local tangent line, so an edge costs no sampling bias); (2) **defocus**, a Gaussian
//! blur of [`Scene::blur_sigma`] px; (3) **light**, a planar [`Lighting`]; (4) **noise**,
//! Gaussian of [`Scene::noise_sigma`] grey levels from a seeded [`SplitMix64`], then rounded
//! and clamped to the output depth.
//!
//! Pixels as in [`GrayImage`](crate::GrayImage): (0, 0) is the top-left pixel's centre, x
//! right, y down; lengths in pixels, angles in radians from +x towards +y. An example:
//! [`render`].

use std::f64::consts::PI;
use std::fmt;

use crate::image::{OwnedImage, OwnedPixels};

/// A shape, sized in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A filled disc of this diameter (px).
    Dot {
        /// Diameter, px.
        diameter: f64,
    },
    /// A ring: outer `diameter` (px) and radial `line_width` (px).
    Ring {
        /// Outer diameter, px.
        diameter: f64,
        /// Radial width of the line, px.
        line_width: f64,
    },
    /// A cross of two equal perpendicular bars: tip-to-tip `length` (px), `bar_width` (px),
    /// the first bar at `angle` radians from +x towards +y.
    Cross {
        /// Tip-to-tip length of each bar, px.
        length: f64,
        /// Width of each bar, px.
        bar_width: f64,
        /// Direction of the first bar, radians.
        angle: f64,
    },
}

/// A mark placed in the scene, centred at (`x`, `y`) pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacedMark {
    /// The shape.
    pub shape: Shape,
    /// Centre x, px.
    pub x: f64,
    /// Centre y, px.
    pub y: f64,
    /// Reflectance of the ink, 0 (black) … 1 (white).
    pub reflectance: f64,
}

/// Things in view that are not the mark.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Clutter {
    /// A straight scratch or line from (`x0`, `y0`) to (`x1`, `y1`) px, `width` px wide.
    Line {
        /// Start x, px.
        x0: f64,
        /// Start y, px.
        y0: f64,
        /// End x, px.
        x1: f64,
        /// End y, px.
        y1: f64,
        /// Width, px.
        width: f64,
        /// Reflectance, 0 … 1.
        reflectance: f64,
    },
    /// A part edge: everything on the far side of the line through (`x`, `y`) px whose normal
    /// points at `angle` radians takes `reflectance`.
    Edge {
        /// A point on the edge, x px.
        x: f64,
        /// A point on the edge, y px.
        y: f64,
        /// Direction of the normal into the covered side, radians.
        angle: f64,
        /// Reflectance of the covered side, 0 … 1.
        reflectance: f64,
    },
    /// A small round speck of dirt or a drilled hole: a disc of `diameter` px.
    Speck {
        /// Centre x, px.
        x: f64,
        /// Centre y, px.
        y: f64,
        /// Diameter, px.
        diameter: f64,
        /// Reflectance, 0 … 1.
        reflectance: f64,
    },
}

/// A machined-surface texture added to the background reflectance: tool marks as parallel
/// streaks (`arc_radius` = `None`, milling across) or arcs of that radius (face milling), with a
/// random depth per mark.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Texture {
    /// Peak reflectance change, 0 … 1.
    pub amplitude: f64,
    /// Spacing of the tool marks, px.
    pub period: f64,
    /// Direction across the streaks, radians.
    pub angle: f64,
    /// Radius of the arcs, px (`None`: straight streaks).
    pub arc_radius: Option<f64>,
}

/// Illumination: `level` × (1 + `gradient` × t), where t runs from −½ to +½ across the image
/// along `angle`, so `gradient` = 0.3 is a 30 % change from one side to the other.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting {
    /// Output value, as a fraction of full scale, of reflectance 1 at the image centre.
    pub level: f64,
    /// Relative change of the illumination across the image (fraction).
    pub gradient: f64,
    /// Direction in which the light grows, radians.
    pub angle: f64,
}

/// Output bit depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Depth {
    /// 8 bits, 0 … 255.
    Eight,
    /// 16 bits, 0 … 65535.
    Sixteen,
}

/// Everything the renderer needs.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Width, px.
    pub width: usize,
    /// Height, px.
    pub height: usize,
    /// Output bit depth.
    pub depth: Depth,
    /// Background reflectance, 0 … 1.
    pub background: f64,
    /// Optional machined-surface texture.
    pub texture: Option<Texture>,
    /// Clutter, painted over the background in order.
    pub clutter: Vec<Clutter>,
    /// Marks, painted last.
    pub marks: Vec<PlacedMark>,
    /// Gaussian defocus blur, standard deviation in px (0 = sharp).
    pub blur_sigma: f64,
    /// Illumination.
    pub lighting: Lighting,
    /// Additive Gaussian noise, standard deviation in grey levels of the output depth.
    pub noise_sigma: f64,
    /// Seed of the noise and of the texture's random depths.
    pub seed: u64,
}

impl Scene {
    /// A `size` × `size` 8-bit frame tiled with dark dots of `diameter` px every `pitch` px
    /// (blur 0.8 px, noise 1 grey level, seed 3): the hostile field the search bounds are
    /// measured on.
    #[must_use]
    pub fn dot_field(size: usize, diameter: f64, pitch: f64) -> Scene {
        #[expect(
            clippy::cast_possible_truncation,
            clippy::cast_sign_loss,
            reason = "a count, floored and non-negative"
        )]
        let n = ((size as f64 - pitch) / pitch).floor().max(0.0) as usize;
        let marks = (0..n * n)
            .map(|k| PlacedMark {
                shape: Shape::Dot { diameter },
                x: pitch * (1 + k % n) as f64,
                y: pitch * (1 + k / n) as f64,
                reflectance: 0.1,
            })
            .collect();
        Scene { marks, blur_sigma: 0.8, noise_sigma: 1.0, seed: 3, ..Scene::blank(size, size, Depth::Eight) }
    }

    /// A blank, sharp, noise-free scene: background 0.8, even light at 0.95 of full scale.
    pub fn blank(width: usize, height: usize, depth: Depth) -> Scene {
        Scene {
            width,
            height,
            depth,
            background: 0.8,
            texture: None,
            clutter: Vec::new(),
            marks: Vec::new(),
            blur_sigma: 0.0,
            lighting: Lighting { level: 0.95, gradient: 0.0, angle: 0.0 },
            noise_sigma: 0.0,
            seed: 0,
        }
    }
}

/// Why a scene cannot be rendered.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum RenderError {
    /// Width or height is zero or the image would exceed 2^28 pixels.
    Size {
        /// Width, px.
        width: usize,
        /// Height, px.
        height: usize,
    },
    /// A parameter is NaN, infinite or out of its range.
    Parameter {
        /// Which parameter.
        name: &'static str,
        /// Its value.
        value: f64,
    },
}

impl fmt::Display for RenderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RenderError::Size { width, height } => {
                write!(f, "cannot render a {width} × {height} image: sides must be ≥ 1 and the area ≤ 2^28 pixels")
            }
            RenderError::Parameter { name, value } => write!(f, "scene parameter {name} = {value} is out of range"),
        }
    }
}

impl std::error::Error for RenderError {}

/// A small seeded generator (SplitMix64) with uniform and Gaussian draws; reproducible across
/// platforms.
#[derive(Clone, Debug)]
pub struct SplitMix64 {
    state: u64,
    spare: Option<f64>,
}

impl SplitMix64 {
    /// A generator from `seed`.
    pub fn new(seed: u64) -> Self {
        SplitMix64 { state: seed, spare: None }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [`lo`, `hi`).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    /// Standard normal (Box–Muller).
    pub fn gaussian(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        let u1 = 1.0 - self.uniform(); // (0, 1]: ln is finite
        let u2 = self.uniform();
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (2.0 * PI * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }
}

/// Renders `scene` (see the module docs for the steps).
///
/// ```
/// use vision_locate::render::{render, Depth, Lighting, PlacedMark, Scene, Shape};
///
/// let scene = Scene {
///     marks: vec![PlacedMark { shape: Shape::Dot { diameter: 40.0 }, x: 63.3, y: 47.8, reflectance: 0.1 }],
///     blur_sigma: 1.0,
///     noise_sigma: 2.0,
///     ..Scene::blank(128, 96, Depth::Eight)
/// };
/// let image = render(&scene)?;
/// assert_eq!((image.width(), image.height()), (128, 96));
/// # Ok::<(), vision_locate::render::RenderError>(())
/// ```
#[expect(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    reason = "grey levels, rounded and clamped to the depth before"
)]
pub fn render(scene: &Scene) -> Result<OwnedImage, RenderError> {
    let (w, h) = (scene.width, scene.height);
    let mut out = radiance(scene)?;
    let full = full_scale(scene.depth);
    let mut rng = SplitMix64::new(scene.seed ^ 0x05EE_D0F5_015E);
    for v in &mut out {
        if scene.noise_sigma > 0.0 {
            *v += scene.noise_sigma * rng.gaussian();
        }
        *v = v.round().clamp(0.0, full);
    }
    let pixels = match scene.depth {
        Depth::Eight => OwnedPixels::Gray8(out.iter().map(|&v| v as u8).collect()),
        Depth::Sixteen => OwnedPixels::Gray16(out.iter().map(|&v| v as u16).collect()),
    };
    Ok(OwnedImage::new(w, h, pixels).expect("the buffer has width × height samples"))
}

fn full_scale(depth: Depth) -> f64 {
    match depth {
        Depth::Eight => 255.0,
        Depth::Sixteen => 65535.0,
    }
}

/// Steps 1–3 of [`render`]: the noise-free image in grey levels of the output depth, unrounded,
/// row-major.
pub(crate) fn radiance(scene: &Scene) -> Result<Vec<f64>, RenderError> {
    let (w, h) = (scene.width, scene.height);
    if w == 0 || h == 0 || w.checked_mul(h).is_none_or(|n| n > 1 << 28) {
        return Err(RenderError::Size { width: w, height: h });
    }
    check(scene)?;
    let mut refl = vec![scene.background; w * h];
    if let Some(t) = &scene.texture {
        paint_texture(&mut refl, w, h, t, scene.seed);
    }
    for c in &scene.clutter {
        paint_clutter(&mut refl, w, h, c);
    }
    for m in &scene.marks {
        let reach = match m.shape {
            Shape::Dot { diameter } => diameter / 2.0,
            Shape::Ring { diameter, .. } => diameter / 2.0,
            Shape::Cross { length, bar_width, .. } => (length / 2.0).hypot(bar_width / 2.0),
        };
        let shape = m.shape;
        let (cx, cy) = (m.x, m.y);
        paint(&mut refl, w, h, Some((cx, cy, reach)), m.reflectance, |x, y| shape_sdf(&shape, x - cx, y - cy));
    }
    if scene.blur_sigma > 0.0 {
        gaussian_blur(&mut refl, w, h, scene.blur_sigma);
    }
    let full = full_scale(scene.depth);
    let l = &scene.lighting;
    let (gc, gs) = (l.angle.cos(), l.angle.sin());
    let (mx, my) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    // The gradient spans the image's extent along `angle`.
    let span = (w as f64 * gc.abs() + h as f64 * gs.abs()).max(1.0);
    for y in 0..h {
        for x in 0..w {
            let t = ((x as f64 - mx) * gc + (y as f64 - my) * gs) / span;
            let light = l.level * (1.0 + l.gradient * t);
            refl[y * w + x] *= full * light;
        }
    }
    Ok(refl)
}

fn check(scene: &Scene) -> Result<(), RenderError> {
    let bad = |name: &'static str, value: f64, lo: f64, hi: f64| {
        if value.is_finite() && value >= lo && value <= hi {
            Ok(())
        } else {
            Err(RenderError::Parameter { name, value })
        }
    };
    bad("background", scene.background, 0.0, 1.0)?;
    bad("blur_sigma", scene.blur_sigma, 0.0, 100.0)?;
    bad("noise_sigma", scene.noise_sigma, 0.0, 1e5)?;
    bad("lighting.level", scene.lighting.level, 0.0, 10.0)?;
    bad("lighting.gradient", scene.lighting.gradient, -1.9, 1.9)?;
    bad("lighting.angle", scene.lighting.angle, -1e6, 1e6)?;
    if let Some(t) = &scene.texture {
        bad("texture.amplitude", t.amplitude, 0.0, 1.0)?;
        bad("texture.period", t.period, 0.5, 1e6)?;
        bad("texture.angle", t.angle, -1e6, 1e6)?;
        if let Some(r) = t.arc_radius {
            bad("texture.arc_radius", r, 1.0, 1e9)?;
        }
    }
    let coord = |name, v| bad(name, v, -1e7, 1e7);
    for m in &scene.marks {
        coord("mark.x", m.x)?;
        coord("mark.y", m.y)?;
        bad("mark.reflectance", m.reflectance, 0.0, 1.0)?;
        match m.shape {
            Shape::Dot { diameter } => bad("dot.diameter", diameter, 0.0, 1e6)?,
            Shape::Ring { diameter, line_width } => {
                bad("ring.diameter", diameter, 0.0, 1e6)?;
                bad("ring.line_width", line_width, 0.0, diameter / 2.0)?;
            }
            Shape::Cross { length, bar_width, angle } => {
                bad("cross.length", length, 0.0, 1e6)?;
                bad("cross.bar_width", bar_width, 0.0, length)?;
                bad("cross.angle", angle, -1e6, 1e6)?;
            }
        }
    }
    for c in &scene.clutter {
        match *c {
            Clutter::Line { x0, y0, x1, y1, width, reflectance } => {
                for v in [x0, y0, x1, y1] {
                    coord("line end", v)?;
                }
                bad("line.width", width, 0.0, 1e6)?;
                bad("line.reflectance", reflectance, 0.0, 1.0)?;
            }
            Clutter::Edge { x, y, angle, reflectance } => {
                coord("edge.x", x)?;
                coord("edge.y", y)?;
                bad("edge.angle", angle, -1e6, 1e6)?;
                bad("edge.reflectance", reflectance, 0.0, 1.0)?;
            }
            Clutter::Speck { x, y, diameter, reflectance } => {
                coord("speck.x", x)?;
                coord("speck.y", y)?;
                bad("speck.diameter", diameter, 0.0, 1e6)?;
                bad("speck.reflectance", reflectance, 0.0, 1.0)?;
            }
        }
    }
    Ok(())
}

/// Signed distance (px, negative inside) from a point at (`x`, `y`) relative to the shape's
/// centre.
fn shape_sdf(shape: &Shape, x: f64, y: f64) -> f64 {
    match *shape {
        Shape::Dot { diameter } => x.hypot(y) - diameter / 2.0,
        Shape::Ring { diameter, line_width } => {
            let mid = (diameter - line_width) / 2.0;
            (x.hypot(y) - mid).abs() - line_width / 2.0
        }
        Shape::Cross { length, bar_width, angle } => {
            let (s, c) = angle.sin_cos();
            let u = x * c + y * s;
            let v = -x * s + y * c;
            let (a, b) = (length / 2.0, bar_width / 2.0);
            box_sdf(u, v, a, b).min(box_sdf(u, v, b, a))
        }
    }
}

/// Signed distance to the axis-aligned box |u| ≤ `a`, |v| ≤ `b`.
fn box_sdf(u: f64, v: f64, a: f64, b: f64) -> f64 {
    let (qx, qy) = (u.abs() - a, v.abs() - b);
    qx.max(0.0).hypot(qy.max(0.0)) + qx.max(qy).min(0.0)
}

fn paint_clutter(refl: &mut [f64], w: usize, h: usize, c: &Clutter) {
    match *c {
        Clutter::Line { x0, y0, x1, y1, width, reflectance } => {
            let (mx, my) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
            let len = (x1 - x0).hypot(y1 - y0);
            let ang = (y1 - y0).atan2(x1 - x0);
            let (s, co) = ang.sin_cos();
            let reach = (len / 2.0).hypot(width / 2.0);
            paint(refl, w, h, Some((mx, my, reach)), reflectance, |x, y| {
                let (dx, dy) = (x - mx, y - my);
                box_sdf(dx * co + dy * s, -dx * s + dy * co, len / 2.0, width / 2.0)
            });
        }
        Clutter::Edge { x, y, angle, reflectance } => {
            let (s, co) = angle.sin_cos();
            paint(refl, w, h, None, reflectance, |px, py| -((px - x) * co + (py - y) * s));
        }
        Clutter::Speck { x, y, diameter, reflectance } => {
            paint(refl, w, h, Some((x, y, diameter / 2.0)), reflectance, |px, py| {
                (px - x).hypot(py - y) - diameter / 2.0
            });
        }
    }
}

/// Paints `value` over `refl` weighted by each pixel's covered area of {sdf < 0}; `bound` is
/// (centre x, centre y, radius) px of a disc holding the shape, or `None` for unbounded shapes.
#[expect(clippy::cast_possible_truncation, clippy::cast_sign_loss, reason = "pixel indices, clamped to the image")]
fn paint(
    refl: &mut [f64],
    w: usize,
    h: usize,
    bound: Option<(f64, f64, f64)>,
    value: f64,
    sdf: impl Fn(f64, f64) -> f64,
) {
    let (x0, x1, y0, y1) = match bound {
        Some((cx, cy, r)) => {
            let lo = |c: f64| (c - r - 2.0).floor().max(0.0) as usize;
            let hi = |c: f64, n: usize| ((c + r + 2.0).ceil().max(0.0) as usize).min(n);
            (lo(cx), hi(cx, w), lo(cy), hi(cy, h))
        }
        None => (0, w, 0, h),
    };
    for y in y0..y1 {
        for x in x0..x1 {
            let cov = coverage(&sdf, x as f64, y as f64);
            if cov > 0.0 {
                let p = &mut refl[y * w + x];
                *p += (value - *p) * cov;
            }
        }
    }
}

/// Covered fraction of pixel (`px`, `py`) by {sdf < 0}.
fn coverage(sdf: &impl Fn(f64, f64) -> f64, px: f64, py: f64) -> f64 {
    const K: usize = 8;
    let d = sdf(px, py);
    // Half the pixel diagonal is 0.707: beyond it the pixel is wholly in or out.
    if d >= 0.75 {
        return 0.0;
    }
    if d <= -0.75 {
        return 1.0;
    }
    let hs = 1.0 / K as f64;
    let mut sum = 0.0;
    for j in 0..K {
        for i in 0..K {
            let qx = px - 0.5 + (i as f64 + 0.5) * hs;
            let qy = py - 0.5 + (j as f64 + 0.5) * hs;
            let dq = sdf(qx, qy);
            if dq >= 0.75 * hs {
                continue;
            }
            if dq <= -0.75 * hs {
                sum += 1.0;
                continue;
            }
            // The edge's local tangent line cuts the sub-square: its covered area in closed form.
            let e = 1e-6;
            let gx = sdf(qx + e, qy) - sdf(qx - e, qy);
            let gy = sdf(qx, qy + e) - sdf(qx, qy - e);
            let n = gx.hypot(gy);
            if n == 0.0 {
                sum += if dq < 0.0 { 1.0 } else { 0.0 };
                continue;
            }
            sum += halfplane_area(-dq / (n / (2.0 * e)) / hs, gx.abs() / n, gy.abs() / n);
        }
    }
    sum / (K * K) as f64
}

/// Area of {q ∈ [−½, ½]²: a·qx + b·qy < d} for a unit normal (a, b) with a, b ≥ 0.
fn halfplane_area(d: f64, a: f64, b: f64) -> f64 {
    let (a, b) = if a >= b { (a, b) } else { (b, a) };
    let hi = (a + b) / 2.0;
    let lo = (a - b) / 2.0;
    if d <= -hi {
        0.0
    } else if d >= hi {
        1.0
    } else if d < -lo {
        (d + hi).powi(2) / (2.0 * a * b)
    } else if d <= lo {
        0.5 + d / a
    } else {
        1.0 - (hi - d).powi(2) / (2.0 * a * b)
    }
}

#[expect(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    reason = "hashing the index: the bits are what counts; wave numbers are small and whole"
)]
fn paint_texture(refl: &mut [f64], w: usize, h: usize, t: &Texture, seed: u64) {
    let (s, c) = t.angle.sin_cos();
    let (mx, my) = (w as f64 / 2.0, h as f64 / 2.0);
    // Random depth per tool mark: a hash of the mark's index.
    let depth = |k: i64| {
        let mut g = SplitMix64::new(seed ^ (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        0.5 + g.uniform()
    };
    for y in 0..h {
        for x in 0..w {
            let (dx, dy) = (x as f64 - mx, y as f64 - my);
            let along = match t.arc_radius {
                None => dx * c + dy * s,
                Some(r) => (dx + r * c).hypot(dy + r * s),
            };
            let phase = along / t.period;
            let k = phase.floor();
            let v = t.amplitude * depth(k as i64) * (2.0 * PI * phase).sin();
            let p = &mut refl[y * w + x];
            *p = (*p + v).clamp(0.0, 1.0);
        }
    }
}

/// Separable Gaussian blur of `sigma` px, edges replicated.
#[expect(clippy::cast_possible_truncation, reason = "a kernel radius of a few sigma, sigma bounded")]
fn gaussian_blur(img: &mut [f64], w: usize, h: usize, sigma: f64) {
    let r = (4.0 * sigma).ceil() as isize;
    let mut k: Vec<f64> = (-r..=r).map(|i| (-(i as f64).powi(2) / (2.0 * sigma * sigma)).exp()).collect();
    let sum: f64 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= sum);
    let mut line = Vec::new();
    for y in 0..h {
        line.clear();
        line.extend_from_slice(&img[y * w..(y + 1) * w]);
        for x in 0..w {
            img[y * w + x] = convolve_at(&line, &k, x);
        }
    }
    for x in 0..w {
        line.clear();
        line.extend((0..h).map(|y| img[y * w + x]));
        for y in 0..h {
            img[y * w + x] = convolve_at(&line, &k, y);
        }
    }
}

/// The centred kernel `k` (odd length) applied to `line` at `at`, the line's ends replicated.
#[expect(
    clippy::cast_possible_wrap,
    clippy::cast_sign_loss,
    reason = "image rows are far below isize::MAX; the index is clamped into the row"
)]
fn convolve_at(line: &[f64], k: &[f64], at: usize) -> f64 {
    let r = (k.len() / 2) as isize;
    let last = line.len() as isize - 1;
    k.iter()
        .enumerate()
        .fold(0.0, |acc, (i, kv)| acc + kv * line[(at as isize + i as isize - r).clamp(0, last) as usize])
}

/// Random clutter for tests and benchmarks: `count` items (scratches, specks smaller than a
/// fifth of `mark_diameter`, and at most one part edge), none closer than `keep_out` px to
/// (`x`, `y`) — the mark's centre.
pub fn random_clutter(
    seed: u64,
    count: usize,
    width: usize,
    height: usize,
    mark: (f64, f64, f64),
    keep_out: f64,
) -> Vec<Clutter> {
    let (mx, my, mark_diameter) = mark;
    let mut g = SplitMix64::new(seed);
    let mut out = Vec::new();
    let (wf, hf) = (width as f64, height as f64);
    let mut tries = 0;
    while out.len() < count && tries < count * 50 {
        tries += 1;
        let kind = g.uniform();
        let refl = g.range(0.0, 1.0);
        let item = if kind < 0.5 {
            let (x0, y0) = (g.range(0.0, wf), g.range(0.0, hf));
            let ang = g.range(0.0, PI);
            let len = g.range(30.0, 400.0);
            Clutter::Line {
                x0,
                y0,
                x1: x0 + len * ang.cos(),
                y1: y0 + len * ang.sin(),
                width: g.range(1.0, 4.0),
                reflectance: refl,
            }
        } else if kind < 0.9 {
            Clutter::Speck {
                x: g.range(0.0, wf),
                y: g.range(0.0, hf),
                diameter: g.range(1.0, (mark_diameter / 5.0).max(1.5)),
                reflectance: refl,
            }
        } else {
            if out.iter().any(|c| matches!(c, Clutter::Edge { .. })) {
                continue;
            }
            Clutter::Edge { x: g.range(0.0, wf), y: g.range(0.0, hf), angle: g.range(-PI, PI), reflectance: refl }
        };
        if clutter_distance(&item, mx, my) >= keep_out {
            out.push(item);
        }
    }
    out
}

/// Distance (px) from (`x`, `y`) to the nearest point of a clutter item.
fn clutter_distance(c: &Clutter, x: f64, y: f64) -> f64 {
    match *c {
        Clutter::Line { x0, y0, x1, y1, width, .. } => {
            let (dx, dy) = (x1 - x0, y1 - y0);
            let t = (((x - x0) * dx + (y - y0) * dy) / (dx * dx + dy * dy).max(1e-12)).clamp(0.0, 1.0);
            (x - x0 - t * dx).hypot(y - y0 - t * dy) - width / 2.0
        }
        Clutter::Edge { x: ex, y: ey, angle, .. } => -((x - ex) * angle.cos() + (y - ey) * angle.sin()),
        Clutter::Speck { x: sx, y: sy, diameter, .. } => (x - sx).hypot(y - sy) - diameter / 2.0,
    }
}

#[cfg(test)]
#[expect(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    clippy::float_cmp,
    reason = "test values are small and whole; tests compare exact values"
)]
mod tests {
    use super::*;

    #[test]
    fn halfplane_area_is_exact_on_known_cuts() {
        assert_eq!(halfplane_area(0.0, 1.0, 0.0), 0.5);
        assert!((halfplane_area(0.25, 1.0, 0.0) - 0.75).abs() < 1e-15);
        let r = std::f64::consts::FRAC_1_SQRT_2;
        // The diagonal through the centre halves the square; a corner cut at d = −0.5/√2 …
        assert!((halfplane_area(0.0, r, r) - 0.5).abs() < 1e-15);
        // … the corner triangle with legs ½: area 1/8.
        assert!((halfplane_area(-0.5 * r, r, r) - 0.125).abs() < 1e-12);
    }

    #[test]
    fn a_disc_covers_its_area() {
        // Total covered area equals π r² to within the curvature error.
        let (w, h) = (64, 64);
        for (cx, cy, d) in [(31.3, 30.9, 20.0), (32.0, 32.0, 7.3), (20.77, 40.1, 33.3)] {
            let mut refl = vec![0.0; w * h];
            paint(&mut refl, w, h, Some((cx, cy, d / 2.0)), 1.0, |x, y| (x - cx).hypot(y - cy) - d / 2.0);
            let area: f64 = refl.iter().sum();
            let truth = PI * d * d / 4.0;
            assert!((area - truth).abs() < 1e-3 * truth, "d {d}: {area} vs {truth}");
            // Each edge pixel's coverage matches brute-force sampling at 512 × 512 points.
            for (x, y) in
                [(cx.round() + d / 2.0).floor()].iter().flat_map(|&x| [(x, cy.round()), (x + 1.0, cy.round())])
            {
                let n = 512;
                let mut inside = 0usize;
                for j in 0..n {
                    for i in 0..n {
                        let qx = x - 0.5 + (i as f64 + 0.5) / n as f64;
                        let qy = y - 0.5 + (j as f64 + 0.5) / n as f64;
                        inside += usize::from((qx - cx).hypot(qy - cy) < d / 2.0);
                    }
                }
                let brute = inside as f64 / (n * n) as f64;
                let got = refl[y as usize * w + x as usize];
                assert!((got - brute).abs() < 2e-4, "pixel {x},{y}: {got} vs {brute}");
            }
        }
    }

    #[test]
    fn a_rotated_cross_covers_its_area() {
        let (w, h) = (80, 80);
        let shape = Shape::Cross { length: 50.0, bar_width: 8.0, angle: 0.37 };
        let (cx, cy) = (40.21, 39.67);
        let mut refl = vec![0.0; w * h];
        paint(&mut refl, w, h, Some((cx, cy, 40.0)), 1.0, |x, y| shape_sdf(&shape, x - cx, y - cy));
        let area: f64 = refl.iter().sum();
        let truth = 2.0 * 50.0 * 8.0 - 64.0;
        assert!((area - truth).abs() < 2e-3 * truth, "{area} vs {truth}");
    }

    #[test]
    fn blur_keeps_the_mean_and_the_noise_has_its_sigma() {
        let scene = Scene { noise_sigma: 3.0, blur_sigma: 2.0, seed: 7, ..Scene::blank(200, 100, Depth::Sixteen) };
        let img = render(&scene).unwrap();
        let OwnedPixels::Gray16(p) = img.pixels() else { panic!("16-bit asked") };
        let n = p.len() as f64;
        let mean = p.iter().map(|&v| v as f64).sum::<f64>() / n;
        let sd = (p.iter().map(|&v| (v as f64 - mean).powi(2)).sum::<f64>() / n).sqrt();
        assert!((mean - 0.8 * 0.95 * 65535.0).abs() < 0.5, "{mean}");
        assert!((sd - 3.0).abs() < 0.1, "{sd}");
    }

    #[test]
    fn bad_scenes_are_typed_errors() {
        assert_eq!(render(&Scene::blank(0, 5, Depth::Eight)), Err(RenderError::Size { width: 0, height: 5 }));
        let s = Scene { blur_sigma: f64::NAN, ..Scene::blank(5, 5, Depth::Eight) };
        assert!(matches!(render(&s), Err(RenderError::Parameter { name: "blur_sigma", .. })));
    }
}
