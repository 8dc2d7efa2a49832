//! Pictures an operator would rather look at than read: one SVG per fit or calibration, with
//! the marks where they should be and where they were seen, each residual as an arrow blown
//! up to be visible, the predicted error as a band around the part, and (in the simulator) the
//! true error beside it.
//!
//! Residuals are thousandths of the part, so every error length (arrows, the band, the legend
//! bars) is drawn magnified by one factor `k` (1, 2 or 5 × 10ⁿ, chosen so the largest residual
//! is about a twelfth of the drawing and the predicted band at most a fifth of it), and the legend says `×k`; positions are to scale. Machine +Y
//! points up.

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
    /// First line (`M282 rectangle fit, line 20`).
    pub title: String,
    /// Lines under the title: the transform, RMS, prediction, truth.
    pub lines: Vec<String>,
    /// `in` or `mm`.
    pub unit: &'static str,
    /// The marks.
    pub marks: Vec<MarkPair>,
    /// The part's outline (its corners in order), if known; the marks' bounding box otherwise.
    pub outline: Vec<[f64; 2]>,
    /// The predicted 99 % bound of the error over the part, drawn as a band around it.
    pub band: Option<f64>,
    /// The true largest error (simulator only).
    pub truth: Option<f64>,
}

const WIDTH: f64 = 800.0;
const PLOT: f64 = 560.0;
const TOP: f64 = 150.0;

/// The smallest 1, 2 or 5 × 10ⁿ with `largest · k ≥ target` (1 when there is nothing to show).
fn magnification(largest: f64, target: f64) -> f64 {
    if !(largest.is_finite() && largest > 0.0) {
        return 1.0;
    }
    let raw = target / largest;
    let decade = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0].into_iter().map(|m| m * decade).find(|k| *k >= raw * 0.999).unwrap_or(10.0 * decade)
}

/// The next smaller of 1, 2, 5 × 10ⁿ.
fn step_down(k: f64) -> f64 {
    let decade = 10f64.powf(k.log10().floor());
    let m = k / decade;
    if m > 4.99 {
        2.0 * decade
    } else if m > 1.99 {
        decade
    } else {
        0.5 * decade
    }
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
    let outline = if sheet.outline.is_empty() {
        bounding_box(sheet.marks.iter().map(|m| m.commanded))
    } else {
        sheet.outline.clone()
    };
    let points = outline.iter().copied().chain(sheet.marks.iter().flat_map(|m| [m.commanded, m.observed]));
    let (lo, hi) = extent(points);
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-9);
    let scale = PLOT / (span * 1.3);
    let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let at = |p: [f64; 2]| [WIDTH / 2.0 + (p[0] - centre[0]) * scale, TOP + PLOT / 2.0 - (p[1] - centre[1]) * scale];
    // Residual arrows about a twelfth of the drawing, but the band (usually the largest
    // length) never wider than a fifth of it.
    let largest = sheet.marks.iter().map(|m| length(m.residual)).chain(sheet.truth).fold(0.0, f64::max);
    let mut k = magnification(largest, span * 0.08);
    if let Some(band) = sheet.band.filter(|b| *b > 0.0 && b.is_finite()) {
        while band * k > span * 0.2 && k > f64::MIN_POSITIVE {
            k = step_down(k);
        }
    }
    let height = TOP + PLOT + 130.0;

    let mut s = String::new();
    // Writing to a String cannot fail.
    let _ = writeln!(
        s,
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{height}" viewBox="0 0 {WIDTH} {height}" font-family="sans-serif" font-size="13">"##
    );
    let _ = writeln!(s, r##"<rect width="100%" height="100%" fill="white"/>"##);
    let _ = writeln!(s, r##"<text x="20" y="28" font-size="18" font-weight="bold">{}</text>"##, xml(&sheet.title));
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
    if let Some(band) = sheet.band {
        let _ = writeln!(
            s,
            r##"<path class="band" d="{}" fill="none" stroke="#f4a259" stroke-opacity="0.35" stroke-width="{}" stroke-linejoin="round"/>"##,
            path(&outline),
            n((2.0 * band * k * scale).max(1.0))
        );
    }
    let _ = writeln!(
        s,
        r##"<path class="part" d="{}" fill="none" stroke="#555" stroke-dasharray="6 4"/>"##,
        path(&outline)
    );
    for m in &sheet.marks {
        let c = at(m.commanded);
        let o = at(m.observed);
        let colour = if m.dropped { "#999" } else { "#1f6feb" };
        let _ = writeln!(
            s,
            r##"<circle class="commanded" cx="{}" cy="{}" r="7" fill="none" stroke="{colour}" stroke-width="2"/>"##,
            n(c[0]),
            n(c[1])
        );
        let _ = writeln!(
            s,
            r##"<path class="observed" d="M{} {} l12 12 m0 -12 l-12 12" fill="none" stroke="{}" stroke-width="2"/>"##,
            n(o[0] - 6.0),
            n(o[1] - 6.0),
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
    legend(&mut s, sheet, k, scale, TOP + PLOT + 20.0);
    let _ = writeln!(
        s,
        r##"<defs><marker id="tip" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="4" markerHeight="4" orient="auto"><path d="M0 0 L10 5 L0 10 z" fill="#2da44e"/></marker></defs>"##
    );
    s.push_str("</svg>\n");
    s
}

/// The legend: symbols, the magnification, and bars for the largest residual, the predicted
/// bound and the truth at the same magnification.
fn legend(s: &mut String, sheet: &Sheet, k: f64, scale: f64, y: f64) {
    let u = sheet.unit;
    let _ = writeln!(
        s,
        r##"<text class="legend" x="20" y="{}">○ where the mark should be   × where it was seen   → residual, and every error length below, ×{} (positions to scale)</text>"##,
        n(y),
        magnification_text(k)
    );
    let largest = sheet.marks.iter().filter(|m| !m.dropped).map(|m| length(m.residual)).fold(0.0, f64::max);
    let bars = [
        ("largest residual", Some(largest), "#2da44e"),
        ("predicted 99 % bound (the band)", sheet.band, "#f4a259"),
        ("true error (simulator)", sheet.truth, "#8250df"),
    ];
    let mut row = y + 24.0;
    for (name, value, colour) in bars {
        let Some(v) = value else { continue };
        let _ = writeln!(
            s,
            r##"<rect class="bar" x="300" y="{}" width="{}" height="10" fill="{colour}"/><text x="20" y="{}">{} {} {u}</text>"##,
            n(row - 9.0),
            n((v * k * scale).clamp(1.0, WIDTH - 320.0)),
            n(row),
            xml(name),
            vision_math::chain::fixed(v, 5)
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

/// The corners of the points' bounding box, counter-clockwise.
fn bounding_box(points: impl Iterator<Item = [f64; 2]>) -> Vec<[f64; 2]> {
    let (lo, hi) = extent(points);
    vec![lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]]
}

#[cfg(test)]
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
        }
    }

    #[test]
    fn magnification_is_a_round_factor_that_makes_errors_visible() {
        assert_eq!(magnification(0.00013, 0.6), 5000.0);
        assert_eq!(magnification(0.0004, 0.6), 2000.0);
        assert_eq!(magnification(0.6, 0.6), 1.0);
        assert_eq!(magnification(0.0, 0.6), 1.0);
        assert_eq!(magnification(f64::NAN, 0.6), 1.0);
        assert_eq!(magnification(10.0, 0.6), 0.1);
        assert_eq!([5000.0, 2000.0, 1000.0, 0.5].map(step_down), [2000.0, 1000.0, 500.0, 0.2]);
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
            doc.descendants().filter(|e| e.is_text()).filter_map(|e| e.text()).collect::<Vec<_>>().join("\n");
        assert!(texts.contains("M282 rectangle fit <line 20> & more"), "{texts}");
        // The largest residual (0.00012 in) wants ×5000 to be a twelfth of the 6.01 in drawing;
        // the 0.0004 in band then exceeds a fifth of it until ×2000.
        assert!(texts.contains("×2000"), "the magnification is stated: {texts}");
        assert!(texts.contains("predicted 99 % bound (the band) 0.00040 in"), "{texts}");
        assert!(texts.contains("true error (simulator) 0.00020 in"), "{texts}");
        assert!(texts.contains("4 (dropped)"));

        // The arrows are the residuals at the stated magnification: the first mark's arrow
        // points right and down on screen (residual +X, −Y), 0.00006·√2 in × 2000 long.
        let arrow = class("residual")[0];
        let f = |a: &str| arrow.attribute(a).and_then(|v| v.parse::<f64>().ok()).expect("number");
        let (dx, dy) = (f("x2") - f("x1"), f("y2") - f("y1"));
        assert!(dx > 0.0 && dy > 0.0, "({dx}, {dy})");
        // Pixels per inch: the plot spans 1.3× the larger side (6.01 in: marks and the seen
        // positions) in 560 px.
        let px_per_in = PLOT / (6.01 * 1.3);
        assert!((dx.hypot(dy) - 0.00006 * 2f64.sqrt() * 2000.0 * px_per_in).abs() < 0.05, "{dx} {dy}");
        // The bars are in proportion to their values.
        let bars = class("bar");
        let w = |i: usize| bars[i].attribute("width").and_then(|v| v.parse::<f64>().ok()).expect("width");
        assert!((w(1) / w(2) - 2.0).abs() < 0.01, "bound 0.0004 vs truth 0.0002: {} {}", w(1), w(2));
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
}
