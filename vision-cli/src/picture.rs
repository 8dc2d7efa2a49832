//! Pictures an operator would rather look at than read: one SVG per fit or calibration, with
//! the marks where they should be and where they were seen, each residual as an arrow blown
//! up to be visible, the predicted error as a band around the part, and (in the simulator) the
//! true error beside it.
//!
//! Residuals are thousandths of the part, so every error length (arrows, the band, the legend
//! bars) is drawn magnified by one factor `k` (1, 2 or 5 × 10ⁿ, chosen so the largest residual
//! is about an eighth of the drawing), and where each mark was seen is drawn away from where it
//! should be by its offset magnified by a second factor `m` (so the part's misplacement shows);
//! the legend states both. The marks' positions, the part's outline (the marks' convex hull
//! when the caller knows no outline) and the scale bar are to scale. Machine +Y points up; the
//! axes in the corner say so.

use std::fmt::Write as _;

/// One mark: where it should be, where it was seen, and its residual under the fit.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MarkPair {
    /// Shown beside the mark (`1`, `2`, …).
    pub label: String,
    /// Where the mark should be (commanded / nominal), machine units.
    pub commanded: [f64; 2],
    /// Where it was seen, machine units.
    pub observed: [f64; 2],
    /// Residual (fit − observed, or the verify residual), machine units.
    pub residual: [f64; 2],
    /// Left out of the fit (an outlier): drawn struck through.
    pub dropped: bool,
}

/// What one picture shows. Lengths in `unit`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Sheet {
    /// First line (`04-rectangle-fit.nc: M282 rectangle fit, line 20`).
    pub title: String,
    /// Lines under the title: the transform, RMS, prediction, truth.
    pub lines: Vec<String>,
    /// `in` or `mm`.
    pub unit: &'static str,
    /// The marks.
    pub marks: Vec<MarkPair>,
    /// The part's outline (its corners in order), if known; the marks' convex hull otherwise.
    pub outline: Vec<[f64; 2]>,
    /// The predicted 99 % bound of the error over the part, drawn as a band around it.
    pub band: Option<f64>,
    /// The true largest error (simulator only).
    pub truth: Option<f64>,
    /// A calibration's lens, drawn small beside the plot.
    pub lens: Option<LensField>,
}

/// How a lens moves the image, as arrows on a grid: drawn in a small square to the right of the
/// plot, the image as the camera sees it (y down), the arrows magnified by a stated factor.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LensField {
    /// Half the side of the square shown, pixels from the optical centre.
    pub half_px: f64,
    /// Each grid point (pixels from the optical centre, y down) and how far the lens moves it
    /// (pixels).
    pub arrows: Vec<([f64; 2], [f64; 2])>,
}

/// The inset's side, and the share of it the grid spans.
const INSET: f64 = 150.0;
const INSET_SPAN: f64 = 0.8;

const WIDTH: f64 = 800.0;
const PLOT: f64 = 560.0;
const TOP: f64 = 150.0;
/// The legend's and the lines' font size, px.
const FONT: f64 = 13.0;
/// A generous average advance of a sans-serif character, in font sizes: text measured with it
/// is never longer on screen than measured.
const ADVANCE: f64 = 0.62;
/// The largest residual is drawn about this share of the drawing long.
const ARROW_SHARE: f64 = 0.125;
/// The largest seen-from-should-be offset is drawn about this share of the drawing long.
const OFFSET_SHARE: f64 = 0.06;
/// The band is drawn at most this share of the plot wide (it says so when narrowed).
const BAND_SHARE: f64 = 0.25;

/// How wide `text` is at `size` px, at most (see [`ADVANCE`]).
pub(crate) fn text_width(text: &str, size: f64) -> f64 {
    let chars = text.chars().count() as f64;
    chars * size * ADVANCE
}

/// The 1, 2 or 5 × 10ⁿ that makes `largest · k` nearest `target` (by ratio; 1 when there is
/// nothing to show).
fn magnification(largest: f64, target: f64) -> f64 {
    if !(largest.is_finite() && largest > 0.0 && target.is_finite() && target > 0.0) {
        return 1.0;
    }
    let raw = target / largest;
    let decade = 10f64.powf(raw.log10().floor());
    [0.5, 1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * decade)
        .min_by(|a, b| (a / raw).ln().abs().total_cmp(&(b / raw).ln().abs()))
        .unwrap_or(1.0)
}

/// Text safe inside an SVG element or attribute.
fn xml(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            c if c.is_control() => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// Numbers as SVG writes them: 2 decimals of a pixel, never NaN (drawn at 0 instead).
fn n(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.2}")
    } else {
        "0".to_string()
    }
}

/// The SVG document of `sheet`.
pub(crate) fn svg(sheet: &Sheet) -> String {
    let outline =
        if sheet.outline.is_empty() { hull(sheet.marks.iter().map(|m| m.commanded)) } else { sheet.outline.clone() };
    let points = outline.iter().copied().chain(sheet.marks.iter().map(|m| m.commanded));
    let (lo, hi) = extent(points);
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-9);
    let scale = PLOT / (span * 1.3);
    let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let at = |p: [f64; 2]| [WIDTH / 2.0 + (p[0] - centre[0]) * scale, TOP + PLOT / 2.0 - (p[1] - centre[1]) * scale];
    let largest = sheet.marks.iter().map(|m| length(m.residual)).chain(sheet.truth).fold(0.0, f64::max);
    let k = magnification(largest, span * ARROW_SHARE);
    let offset = sheet
        .marks
        .iter()
        .map(|m| length([m.observed[0] - m.commanded[0], m.observed[1] - m.commanded[1]]))
        .fold(0.0, f64::max);
    let seen_k = magnification(offset, span * OFFSET_SHARE).max(1.0);
    let height = TOP + PLOT + 150.0;

    let mut s = String::new();
    // Writing to a String cannot fail.
    let _ = writeln!(
        s,
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{height}" viewBox="0 0 {WIDTH} {height}" font-family="sans-serif" font-size="{FONT}">"##
    );
    let _ = writeln!(s, r##"<rect width="100%" height="100%" fill="white"/>"##);
    let _ = writeln!(
        s,
        r##"<text class="title" x="20" y="28" font-size="18" font-weight="bold">{}</text>"##,
        xml(&sheet.title)
    );
    for (i, line) in sheet.lines.iter().enumerate() {
        let _ = writeln!(s, r##"<text x="20" y="{}">{}</text>"##, 52.0 + 18.0 * i as f64, xml(line));
    }
    let path = |pts: &[[f64; 2]]| {
        pts.iter().enumerate().fold(String::new(), |mut d, (i, p)| {
            let q = at(*p);
            let _ = write!(d, "{}{} {} ", if i == 0 { "M" } else { "L" }, n(q[0]), n(q[1]));
            d
        }) + "Z"
    };
    let mut band_narrowed = false;
    if let Some(band) = sheet.band {
        let mut width = (2.0 * band * k * scale).max(1.0);
        if width > BAND_SHARE * PLOT {
            width = BAND_SHARE * PLOT;
            band_narrowed = true;
        }
        let _ = writeln!(
            s,
            r##"<path class="band" d="{}" fill="none" stroke="#f4a259" stroke-opacity="0.35" stroke-width="{}" stroke-linejoin="round"/>"##,
            path(&outline),
            n(width)
        );
    }
    let _ = writeln!(
        s,
        r##"<path class="part" d="{}" fill="none" stroke="#555" stroke-dasharray="6 4"/>"##,
        path(&outline)
    );
    for m in &sheet.marks {
        let c = at(m.commanded);
        let seen = [
            m.commanded[0] + (m.observed[0] - m.commanded[0]) * seen_k,
            m.commanded[1] + (m.observed[1] - m.commanded[1]) * seen_k,
        ];
        let o = at(seen);
        let colour = if m.dropped { "#999" } else { "#1f6feb" };
        let _ = writeln!(
            s,
            r##"<circle class="commanded" cx="{}" cy="{}" r="7" fill="none" stroke="{colour}" stroke-width="2"/>"##,
            n(c[0]),
            n(c[1])
        );
        let _ = writeln!(
            s,
            r##"<path class="observed" d="M{} {} l10 10 m0 -10 l-10 10" fill="none" stroke="{}" stroke-width="2"/>"##,
            n(o[0] - 5.0),
            n(o[1] - 5.0),
            if m.dropped { "#999" } else { "#d1242f" }
        );
        let tip = [c[0] + m.residual[0] * k * scale, c[1] - m.residual[1] * k * scale];
        let _ = writeln!(
            s,
            r##"<line class="residual" x1="{}" y1="{}" x2="{}" y2="{}" stroke="#2da44e" stroke-width="2.5" marker-end="url(#tip)"/>"##,
            n(c[0]),
            n(c[1]),
            n(tip[0]),
            n(tip[1])
        );
        let label = if m.dropped { format!("{} (dropped)", m.label) } else { m.label.clone() };
        let _ = writeln!(s, r##"<text x="{}" y="{}">{}</text>"##, n(c[0] + 10.0), n(c[1] - 10.0), xml(&label));
        if m.dropped {
            let _ = writeln!(
                s,
                r##"<line class="dropped" x1="{}" y1="{}" x2="{}" y2="{}" stroke="#999" stroke-width="2"/>"##,
                n(c[0] - 12.0),
                n(c[1] + 12.0),
                n(c[0] + 12.0),
                n(c[1] - 12.0)
            );
        }
    }
    axes(&mut s, sheet.unit, span, scale);
    if let Some(field) = &sheet.lens {
        lens_inset(&mut s, field);
    }
    legend(&mut s, sheet, Magnified { k, seen: seen_k, band_narrowed }, scale, TOP + PLOT + 20.0);
    let _ = writeln!(
        s,
        r##"<defs><marker id="tip" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="4" markerHeight="4" orient="auto"><path d="M0 0 L10 5 L0 10 z" fill="#2da44e"/></marker></defs>"##
    );
    s.push_str("</svg>\n");
    s
}

/// [`LensField`] in the plot's upper right corner.
fn lens_inset(s: &mut String, field: &LensField) {
    let (x0, y0) = (WIDTH - INSET - 20.0, TOP + 20.0);
    let px = INSET * INSET_SPAN / 2.0 / field.half_px.max(1e-9);
    let steps = (field.arrows.len() as f64).sqrt().max(2.0) - 1.0;
    let largest = field.arrows.iter().map(|(_, d)| length(*d) * px).fold(0.0, f64::max);
    let k = magnification(largest, INSET * INSET_SPAN / steps * 0.8);
    let _ = writeln!(
        s,
        r##"<g class="lens-field"><rect x="{}" y="{}" width="{INSET}" height="{INSET}" fill="none" stroke="#999"/>"##,
        n(x0),
        n(y0)
    );
    for (p, d) in &field.arrows {
        let (x, y) = (x0 + INSET / 2.0 + p[0] * px, y0 + INSET / 2.0 + p[1] * px);
        let _ = writeln!(
            s,
            r##"<line x1="{}" y1="{}" x2="{}" y2="{}" stroke="#8250df" stroke-width="1.5" marker-end="url(#lens-tip)"/>"##,
            n(x),
            n(y),
            n(x + d[0] * px * k),
            n(y + d[1] * px * k)
        );
    }
    let label = format!("the lens as the camera sees it, arrows ×{}", magnification_text(k));
    let _ = writeln!(
        s,
        r##"<text x="{}" y="{}">{}</text><defs><marker id="lens-tip" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="4" markerHeight="4" orient="auto"><path d="M0 0 L10 5 L0 10 z" fill="#8250df"/></marker></defs></g>"##,
        n(WIDTH - 20.0 - text_width(&label, FONT)),
        n(y0 - 6.0),
        xml(&label)
    );
}

/// The X and Y directions in the plot's lower left corner, and a scale bar of a round length
/// about a fifth of the drawing in its lower right.
fn axes(s: &mut String, unit: &str, span: f64, scale: f64) {
    let (x0, y0) = (40.0, TOP + PLOT - 10.0);
    for (dx, dy, name) in [(50.0, 0.0, "X"), (0.0, -50.0, "Y")] {
        let _ = writeln!(
            s,
            r##"<line class="axis" x1="{x0}" y1="{y0}" x2="{}" y2="{}" stroke="#333" stroke-width="1.5"/><text class="axis-label" x="{}" y="{}">{name}</text>"##,
            n(x0 + dx),
            n(y0 + dy),
            n(x0 + dx + if dx > 0.0 { 6.0 } else { -4.0 }),
            n(y0 + dy + if dy < 0.0 { -6.0 } else { 4.0 })
        );
    }
    let length = round_length(span / 5.0);
    let px = length * scale;
    let (x1, y) = (WIDTH - 40.0, TOP + PLOT - 10.0);
    let _ = writeln!(
        s,
        r##"<line class="scale-bar" x1="{}" y1="{y}" x2="{x1}" y2="{y}" stroke="#333" stroke-width="3"/><text class="scale-bar-label" x="{}" y="{}" text-anchor="middle">{} {unit}</text>"##,
        n(x1 - px),
        n(x1 - px / 2.0),
        n(y - 8.0),
        format_length(length)
    );
}

/// The largest 1, 2 or 5 × 10ⁿ not above `v` (1 for nothing to show).
fn round_length(v: f64) -> f64 {
    if !(v.is_finite() && v > 0.0) {
        return 1.0;
    }
    let decade = 10f64.powf(v.log10().floor());
    [5.0, 2.0, 1.0].into_iter().map(|m| m * decade).find(|l| *l <= v * 1.000_001).unwrap_or(decade)
}

/// A round length as text, without trailing zeros (`0.5`, `2`, `0.001`).
fn format_length(v: f64) -> String {
    let t = format!("{v:.6}");
    t.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// The magnifications a picture is drawn with.
#[derive(Debug, Clone, Copy)]
struct Magnified {
    /// Of every error length (arrows, band, bars).
    k: f64,
    /// Of where each mark was seen, away from where it should be.
    seen: f64,
    /// The band was drawn narrower than `k` makes it.
    band_narrowed: bool,
}

/// The legend: symbols, the magnifications, and bars for the largest residual, the predicted
/// bound and the truth at the same magnification, each bar starting after the longest name.
fn legend(s: &mut String, sheet: &Sheet, mag: Magnified, scale: f64, y: f64) {
    let u = sheet.unit;
    let seen = if mag.seen > 1.0 {
        format!("× where it was seen, its offset from ○ ×{}", magnification_text(mag.seen))
    } else {
        "× where it was seen (to scale)".to_string()
    };
    let lines = [
        format!("○ where the mark should be   {seen}"),
        format!(
            "→ residual, and every error length below, ×{} (positions and the scale bar to scale)",
            magnification_text(mag.k)
        ),
    ];
    for (i, line) in lines.iter().enumerate() {
        let _ = writeln!(s, r##"<text class="legend" x="20" y="{}">{}</text>"##, n(y + 18.0 * i as f64), xml(line));
    }
    let largest = sheet.marks.iter().filter(|m| !m.dropped).map(|m| length(m.residual)).fold(0.0, f64::max);
    let band_name = if mag.band_narrowed {
        "predicted 99 % bound (the band, drawn narrower)"
    } else {
        "predicted 99 % bound (the band)"
    };
    let bars = [
        ("largest residual", Some(largest), "#2da44e"),
        (band_name, sheet.band, "#f4a259"),
        ("true error (simulator)", sheet.truth, "#8250df"),
    ];
    let labels: Vec<(String, f64, &str)> = bars
        .iter()
        .filter_map(|(name, v, colour)| {
            v.map(|v| (format!("{name} {} {u}", vision_math::chain::fixed(v, 5)), v, *colour))
        })
        .collect();
    let bar_x = 20.0 + labels.iter().map(|(t, ..)| text_width(t, FONT)).fold(0.0, f64::max) + 16.0;
    let mut row = y + 18.0 * 2.0 + 8.0;
    for (label, v, colour) in labels {
        let _ = writeln!(
            s,
            r##"<text class="bar-label" x="20" y="{}">{}</text><rect class="bar" x="{}" y="{}" width="{}" height="10" fill="{colour}"/>"##,
            n(row),
            xml(&label),
            n(bar_x),
            n(row - 9.0),
            n((v * mag.k * scale).clamp(1.0, (WIDTH - 20.0 - bar_x).max(1.0)))
        );
        row += 22.0;
    }
}

fn magnification_text(k: f64) -> String {
    if k >= 1.0 {
        format!("{k:.0}")
    } else {
        format!("{k}")
    }
}

/// Length of a vector `[x, y]` (0 for a non-finite one, which is not drawn).
fn length(v: [f64; 2]) -> f64 {
    let l = v[0].hypot(v[1]);
    if l.is_finite() {
        l
    } else {
        0.0
    }
}

fn extent(points: impl Iterator<Item = [f64; 2]>) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in points.filter(|p| p[0].is_finite() && p[1].is_finite()) {
        for i in 0..2 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    if lo[0] > hi[0] {
        ([0.0; 2], [1.0; 2])
    } else {
        (lo, hi)
    }
}

/// The points' convex hull, counter-clockwise (Andrew's monotone chain); fewer than three
/// points off one line give their bounding box, so the outline is never empty.
fn hull(points: impl Iterator<Item = [f64; 2]>) -> Vec<[f64; 2]> {
    let mut p: Vec<[f64; 2]> = points.filter(|p| p[0].is_finite() && p[1].is_finite()).collect();
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    p.dedup();
    let bbox = |p: &[[f64; 2]]| {
        let (lo, hi) = extent(p.iter().copied());
        vec![lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]]
    };
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    let chain = |pts: &mut dyn Iterator<Item = [f64; 2]>| {
        let mut out: Vec<[f64; 2]> = Vec::new();
        for q in pts {
            while out.len() >= 2 && cross(out[out.len() - 2], out[out.len() - 1], q) <= 0.0 {
                out.pop();
            }
            out.push(q);
        }
        out.pop();
        out
    };
    let mut h = chain(&mut p.iter().copied());
    h.extend(chain(&mut p.iter().rev().copied()));
    if h.len() < 3 {
        return bbox(&p);
    }
    h
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;

    fn fit_sheet() -> Sheet {
        let marks = [
            ([0.0, 0.0], [0.00006, -0.00006]),
            ([6.0, 0.0], [0.00009, 0.00006]),
            ([6.0, 4.0], [-0.00009, -0.00008]),
            ([0.0, 4.0], [0.00006, 0.00008]),
        ];
        Sheet {
            title: "M282 rectangle fit <line 20> & more".into(),
            lines: vec!["rotation 0.301725 deg".into(), "rms 0.00011 in".into()],
            unit: "in",
            marks: marks
                .iter()
                .enumerate()
                .map(|(i, (p, r))| MarkPair {
                    label: format!("{}", i + 1),
                    commanded: *p,
                    observed: [p[0] + 0.01, p[1] + 0.02],
                    residual: *r,
                    dropped: i == 3,
                })
                .collect(),
            outline: Vec::new(),
            band: Some(0.0004),
            truth: Some(0.0002),
            lens: None,
        }
    }

    #[test]
    fn magnification_is_a_round_factor_that_makes_errors_visible() {
        assert_eq!(magnification(0.00013, 0.6), 5000.0);
        assert_eq!(magnification(0.0004, 0.6), 2000.0);
        assert_eq!(magnification(0.6, 0.6), 1.0);
        assert_eq!(magnification(0.0, 0.6), 1.0);
        assert_eq!(magnification(f64::NAN, 0.6), 1.0);
        assert_eq!(magnification(10.0, 0.6), 0.05);
        assert_eq!(magnification(0.0003, 0.6), 2000.0);
    }

    fn attr(e: roxmltree::Node<'_, '_>, a: &str) -> f64 {
        e.attribute(a).and_then(|v| v.parse::<f64>().ok()).unwrap_or_else(|| panic!("{a} of {e:?}"))
    }

    #[test]
    fn the_picture_parses_and_shows_what_it_claims() {
        let sheet = fit_sheet();
        let text = svg(&sheet);
        let doc = roxmltree::Document::parse(&text).expect("well-formed SVG");
        let root = doc.root_element();
        assert_eq!(root.tag_name().name(), "svg");
        let class = |c: &str| doc.descendants().filter(|e| e.attribute("class") == Some(c)).collect::<Vec<_>>();
        assert_eq!(class("commanded").len(), 4);
        assert_eq!(class("observed").len(), 4);
        assert_eq!(class("residual").len(), 4);
        assert_eq!(class("dropped").len(), 1);
        assert_eq!(class("band").len(), 1);
        let texts: String =
            doc.descendants().filter(roxmltree::Node::is_text).filter_map(|e| e.text()).collect::<Vec<_>>().join("\n");
        assert!(texts.contains("M282 rectangle fit <line 20> & more"), "{texts}");
        // The largest error length (the 0.0002 in truth) wants ×3750 to be an eighth of the
        // 6 in drawing: ×5000 is the nearest round factor.
        assert!(texts.contains("every error length below, ×5000"), "the magnification is stated: {texts}");
        // The marks were seen 0.0224 in off: ×20 makes that about 6 % of the drawing.
        assert!(texts.contains("its offset from ○ ×20"), "{texts}");
        // Drawn at ×5000 the band would be 4 in wide, more than a quarter of the plot.
        assert!(texts.contains("predicted 99 % bound (the band, drawn narrower) 0.00040 in"), "{texts}");
        assert!(texts.contains("true error (simulator) 0.00020 in"), "{texts}");
        assert!(texts.contains("4 (dropped)"));

        // Pixels per inch: the plot spans 1.3× the part's larger side (6 in) in 560 px.
        let px_per_in = PLOT / (6.0 * 1.3);
        // The arrows are the residuals at the stated magnification: the first mark's arrow
        // points right and down on screen (residual +X, −Y), 0.00006·√2 in × 5000 long.
        let arrow = class("residual")[0];
        let (dx, dy) = (attr(arrow, "x2") - attr(arrow, "x1"), attr(arrow, "y2") - attr(arrow, "y1"));
        assert!(dx > 0.0 && dy > 0.0, "({dx}, {dy})");
        assert!((dx.hypot(dy) - 0.00006 * 2f64.sqrt() * 5000.0 * px_per_in).abs() < 0.05, "{dx} {dy}");
        // The largest arrow is about an eighth of the drawing (a round factor: within 2×).
        let longest = class("residual")
            .iter()
            .map(|a| (attr(*a, "x2") - attr(*a, "x1")).hypot(attr(*a, "y2") - attr(*a, "y1")))
            .fold(0.0, f64::max);
        let drawing = 6.0 * px_per_in;
        assert!(longest > drawing / 16.0 && longest < drawing / 4.0, "{longest} of {drawing}");
        // Each × is its mark's offset ×20 away from its ○: (0.01, 0.02) in → (+, −) on screen.
        let (o, c) = (class("observed")[0], class("commanded")[0]);
        let d = o.attribute("d").expect("d");
        let xy: Vec<f64> = d[1..].split_whitespace().take(2).map(|v| v.parse().expect("number")).collect();
        let (ox, oy) = (xy[0] + 5.0, xy[1] + 5.0);
        assert!((ox - attr(c, "cx") - 0.01 * 20.0 * px_per_in).abs() < 0.05, "{ox}");
        assert!((oy - attr(c, "cy") + 0.02 * 20.0 * px_per_in).abs() < 0.05, "{oy}");
        // The bars are in proportion to their values, and each starts after every label ends.
        let bars = class("bar");
        assert!((attr(bars[1], "width") / attr(bars[2], "width") - 2.0).abs() < 0.01);
        let label_end = class("bar-label")
            .iter()
            .map(|t| attr(*t, "x") + text_width(t.text().expect("label"), FONT))
            .fold(0.0, f64::max);
        assert!(bars.iter().all(|b| attr(*b, "x") > label_end), "the legend's bars clear its labels");
        // Axes and a scale bar of a round length, drawn to scale: 1 in is a fifth of 6 in or less.
        assert_eq!(class("axis").len(), 2);
        let bar = class("scale-bar")[0];
        assert!((attr(bar, "x2") - attr(bar, "x1") - px_per_in).abs() < 0.05);
        assert_eq!(class("scale-bar-label")[0].text(), Some("1 in"));
    }

    #[test]
    fn three_marks_are_outlined_as_their_triangle() {
        let mut sheet = fit_sheet();
        sheet.marks.truncate(3);
        let text = svg(&sheet);
        let doc = roxmltree::Document::parse(&text).expect("well-formed SVG");
        let part = doc.descendants().find(|e| e.attribute("class") == Some("part")).expect("outline");
        let d = part.attribute("d").expect("d");
        assert_eq!(d.matches(['M', 'L']).count(), 3, "{d}");
        assert_eq!(hull([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]].into_iter()).len(), 4, "a line: its box");
        assert_eq!(hull([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0], [2.0, 2.0]].into_iter()).len(), 4);
    }

    #[test]
    fn degenerate_input_still_draws_a_valid_picture() {
        let mut sheet = fit_sheet();
        sheet.marks[0].observed = [f64::NAN, f64::INFINITY];
        sheet.marks[1].residual = [f64::NAN, 0.0];
        sheet.band = None;
        sheet.truth = None;
        let text = svg(&sheet);
        assert!(!text.contains("NaN") && !text.contains("inf"), "{text}");
        roxmltree::Document::parse(&text).expect("well-formed");
        let empty = Sheet { marks: Vec::new(), ..fit_sheet() };
        roxmltree::Document::parse(&svg(&empty)).expect("well-formed without marks");
    }

    #[test]
    fn a_lens_is_drawn_as_arrows_in_its_own_square_with_their_factor() {
        // Barrel: every point moves towards the centre, the corners by 2 px.
        let arrows = [[-100.0, -100.0], [0.0, 0.0], [100.0, 100.0], [100.0, -100.0]]
            .map(|p: [f64; 2]| (p, [-p[0] * 0.02, -p[1] * 0.02]))
            .to_vec();
        let sheet = Sheet { lens: Some(LensField { half_px: 100.0, arrows }), ..fit_sheet() };
        let text = svg(&sheet);
        let doc = roxmltree::Document::parse(&text).expect("well-formed");
        let group = doc.descendants().find(|n| n.attribute("class") == Some("lens-field")).expect("the inset");
        let lines: Vec<_> = group.descendants().filter(|n| n.has_tag_name("line")).collect();
        assert_eq!(lines.len(), 4);
        // The corner arrow points inwards (+x from the left), its 2 px along x drawn ×50 at the
        // inset's 0.6 px per image pixel (the grid's 100 px are 60 px): 60 px long.
        let (x1, x2) = (attr(lines[0], "x1"), attr(lines[0], "x2"));
        assert!((x2 - x1 - 60.0).abs() < 1e-9, "{x1} {x2}");
        assert!(text.contains("arrows ×50"), "{text}");
        assert!(!svg(&fit_sheet()).contains("lens-field"), "a fit has no lens");
    }
}
