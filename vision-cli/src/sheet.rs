//! `mach-vision sheet`: the calibration sheet M283 walks, to print.
//!
//! The drawing comes from the same table M283 walks (`vision_core::sheets`): every dot filled
//! at its true size and place, a crosshair round the centre dot (where the operator zeroes X/Y
//! with the spindle), the X+ and Y+ directions, the sheet's number and the words that walk it,
//! and two scale bars (100 mm and 4 in) to catch a printer that scaled the page. One list of
//! shapes in inches on the page (origin bottom left, +y up) is written as SVG (physical
//! `width`/`height` and a `viewBox` in inches) or as a one-page PDF of the paper's size.

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::{Args, ValueEnum};
use vision_core::sheets::{cal_sheet, known_sheets, CalSheet};

use crate::Failure;

/// Paper sizes, inches (width, height), portrait.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum Paper {
    /// US Letter, 8.5 × 11 in.
    Letter,
    /// ISO A4, 210 × 297 mm.
    A4,
}

impl Paper {
    /// Width and height, inches.
    fn size_in(self) -> (f64, f64) {
        match self {
            Paper::Letter => (8.5, 11.0),
            Paper::A4 => (210.0 / 25.4, 297.0 / 25.4),
        }
    }

    fn name(self) -> &'static str {
        match self {
            Paper::Letter => "US Letter",
            Paper::A4 => "A4",
        }
    }
}

/// Output formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum Format {
    /// SVG with physical size (print at 100 %, "actual size").
    Svg,
    /// One-page PDF.
    Pdf,
}

/// `mach-vision sheet [N] [--paper letter|a4] [--format svg|pdf] [-o FILE]`.
#[derive(Debug, Args)]
pub(crate) struct SheetArgs {
    /// The sheet number (`M283 C<N>`, on LinuxCNC `M283 P<N>`).
    #[arg(default_value_t = 1, allow_negative_numbers = true)]
    sheet: i64,
    /// The paper it is printed on.
    #[arg(long, value_enum, default_value_t = Paper::Letter)]
    paper: Paper,
    /// svg or pdf; default: from the -o file's extension, else svg.
    #[arg(long, value_enum)]
    format: Option<Format>,
    /// Where to write it; default: standard output (SVG only).
    #[arg(short = 'o', long = "output")]
    output: Option<PathBuf>,
}

/// One thing drawn, inches on the page (origin bottom left, +y up).
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Shape {
    /// A filled black disc.
    Dot { x: f64, y: f64, r: f64 },
    /// A black line `width` wide.
    Line { x0: f64, y0: f64, x1: f64, y1: f64, width: f64 },
    /// Text of height `size`, its left end at `(x, y)` on the baseline.
    Text { x: f64, y: f64, size: f64, text: String },
}

/// The lengths of the two scale bars, inches, and their labels.
const BARS: [(f64, &str); 2] = [(100.0 / 25.4, "100 mm"), (4.0, "4 in")];

/// The sheet drawn on `paper`: the shapes, centred on the page.
///
/// # Errors
/// [`Failure::Input`] when the sheet's dots do not fit on the paper with a 0.5 in margin.
pub(crate) fn layout(sheet: &CalSheet, paper: Paper) -> Result<Vec<Shape>, Failure> {
    let (w, h) = paper.size_in();
    let (cx, cy) = (w / 2.0, h / 2.0);
    let r = sheet.mark_diameter_in / 2.0;
    let (mut max_x, mut max_y) = (0.0_f64, 0.0_f64);
    for (x, y) in sheet.dots_in {
        max_x = max_x.max(x.abs() + r);
        max_y = max_y.max(y.abs() + r);
    }
    if cx - max_x < 0.5 || cy - max_y < 1.2 {
        return Err(Failure::Input(format!(
            "sheet {} ({:.2} x {:.2} in of dots) does not fit on {} paper",
            sheet.id,
            2.0 * max_x,
            2.0 * max_y,
            paper.name()
        )));
    }
    let mut shapes = Vec::new();
    for (i, (x, y)) in sheet.dots_in.iter().enumerate() {
        shapes.push(Shape::Dot { x: cx + x, y: cy + y, r });
        // The walk order beside each dot, small: the finder takes it for no mark.
        shapes.push(Shape::Text { x: cx + x + r + 0.12, y: cy + y + r + 0.05, size: 0.14, text: format!("{}", i + 1) });
    }
    // The crosshair round the sheet's origin (the spindle's X/Y zero), clear of the dot.
    let (gap, reach, thin) = (r + 0.08, r + 0.7, 0.01);
    for (dx, dy) in [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)] {
        shapes.push(Shape::Line {
            x0: cx + dx * gap,
            y0: cy + dy * gap,
            x1: cx + dx * reach,
            y1: cy + dy * reach,
            width: thin,
        });
    }
    shapes.push(Shape::Text { x: cx + reach + 0.06, y: cy - 0.06, size: 0.18, text: "X+".into() });
    shapes.push(Shape::Text { x: cx - 0.1, y: cy + reach + 0.08, size: 0.18, text: "Y+".into() });
    let title = [
        format!(
            "mach-vision calibration sheet {} - walked by M283 C{} (on LinuxCNC M283 P{})",
            sheet.id, sheet.id, sheet.id
        ),
        "Print at 100 % (actual size). Tape it flat, X+ along the machine's +X, on the surface you will cut.".into(),
        "Zero work X/Y with the spindle on the crosshair, select the camera tool, jog it over dot 1, run M283.".into(),
    ];
    for (i, line) in title.iter().enumerate() {
        let y = h - 0.55 - 0.22 * i as f64;
        shapes.push(Shape::Text { x: 0.6, y, size: if i == 0 { 0.17 } else { 0.13 }, text: line.clone() });
    }
    for (i, (length, label)) in BARS.iter().enumerate() {
        let y = 0.55 + 0.4 * i as f64;
        let x0 = 0.6;
        shapes.push(Shape::Line { x0, y0: y, x1: x0 + length, y1: y, width: 0.02 });
        for x in [x0, x0 + length] {
            shapes.push(Shape::Line { x0: x, y0: y - 0.06, x1: x, y1: y + 0.06, width: 0.01 });
        }
        shapes.push(Shape::Text {
            x: x0 + length + 0.15,
            y: y - 0.05,
            size: 0.13,
            text: format!("check: this bar measures {label}"),
        });
    }
    Ok(shapes)
}

/// Escapes text for XML and keeps PDF strings simple: ASCII only.
fn xml(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// The shapes as SVG of the page's physical size (user units: inches).
pub(crate) fn svg(shapes: &[Shape], paper: Paper) -> String {
    let (w, h) = paper.size_in();
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w:.4}in\" height=\"{h:.4}in\" viewBox=\"0 0 {w:.4} {h:.4}\">\n\
         <rect x=\"0\" y=\"0\" width=\"{w:.4}\" height=\"{h:.4}\" fill=\"white\"/>\n"
    );
    for shape in shapes {
        let _ = match shape {
            Shape::Dot { x, y, r } => {
                writeln!(s, "<circle cx=\"{x:.5}\" cy=\"{:.5}\" r=\"{r:.5}\" fill=\"black\"/>", h - y)
            }
            Shape::Line { x0, y0, x1, y1, width } => writeln!(
                s,
                "<line x1=\"{x0:.5}\" y1=\"{:.5}\" x2=\"{x1:.5}\" y2=\"{:.5}\" stroke=\"black\" stroke-width=\"{width:.4}\"/>",
                h - y0,
                h - y1
            ),
            Shape::Text { x, y, size, text } => writeln!(
                s,
                "<text x=\"{x:.4}\" y=\"{:.4}\" font-family=\"Helvetica, Arial, sans-serif\" font-size=\"{size:.3}\">{}</text>",
                h - y,
                xml(text)
            ),
        };
    }
    s.push_str("</svg>\n");
    s
}

/// The shapes as a one-page PDF of the paper's size (points: 72 per inch; Helvetica).
pub(crate) fn pdf(shapes: &[Shape], paper: Paper) -> Vec<u8> {
    let (w, h) = paper.size_in();
    let pt = |v: f64| v * 72.0;
    // A circle as four Bézier quarters (κ = 0.5523).
    let k = 0.552_284_749_8;
    let mut content = String::new();
    for shape in shapes {
        let _ = match shape {
            Shape::Dot { x, y, r } => {
                let (x, y, r) = (pt(*x), pt(*y), pt(*r));
                let c = k * r;
                writeln!(
                    content,
                    "{:.3} {y:.3} m {:.3} {:.3} {:.3} {:.3} {x:.3} {:.3} c {:.3} {:.3} {:.3} {:.3} {:.3} {y:.3} c \
                     {:.3} {:.3} {:.3} {:.3} {x:.3} {:.3} c {:.3} {:.3} {:.3} {:.3} {:.3} {y:.3} c f",
                    x + r,
                    x + r,
                    y + c,
                    x + c,
                    y + r,
                    y + r,
                    x - c,
                    y + r,
                    x - r,
                    y + c,
                    x - r,
                    x - r,
                    y - c,
                    x - c,
                    y - r,
                    y - r,
                    x + c,
                    y - r,
                    x + r,
                    y - c,
                    x + r
                )
            }
            Shape::Line { x0, y0, x1, y1, width } => writeln!(
                content,
                "{:.3} w {:.3} {:.3} m {:.3} {:.3} l S",
                pt(*width),
                pt(*x0),
                pt(*y0),
                pt(*x1),
                pt(*y1)
            ),
            Shape::Text { x, y, size, text } => {
                let text: String = text
                    .chars()
                    .map(|c| if c.is_ascii() && !c.is_ascii_control() { c } else { '?' })
                    .collect::<String>()
                    .replace('\\', "\\\\")
                    .replace('(', "\\(")
                    .replace(')', "\\)");
                writeln!(content, "BT /F1 {:.2} Tf {:.3} {:.3} Td ({text}) Tj ET", pt(*size), pt(*x), pt(*y))
            }
        };
    }
    let objects = [
        "<< /Type /Catalog /Pages 2 0 R >>".to_string(),
        "<< /Type /Pages /Kids [3 0 R] /Count 1 >>".to_string(),
        format!(
            "<< /Type /Page /Parent 2 0 R /MediaBox [0 0 {:.3} {:.3}] /Resources << /Font << /F1 4 0 R >> >> /Contents 5 0 R >>",
            pt(w),
            pt(h)
        ),
        "<< /Type /Font /Subtype /Type1 /BaseFont /Helvetica >>".to_string(),
        format!("<< /Length {} >>\nstream\n{content}endstream", content.len()),
    ];
    let mut out = b"%PDF-1.4\n".to_vec();
    let mut offsets = Vec::with_capacity(objects.len());
    for (i, body) in objects.iter().enumerate() {
        offsets.push(out.len());
        out.extend_from_slice(format!("{} 0 obj\n{body}\nendobj\n", i + 1).as_bytes());
    }
    let xref = out.len();
    let mut tail = format!("xref\n0 {}\n0000000000 65535 f \n", objects.len() + 1);
    for o in offsets {
        let _ = writeln!(tail, "{o:010} 00000 n ");
    }
    let _ = write!(tail, "trailer\n<< /Size {} /Root 1 0 R >>\nstartxref\n{xref}\n%%EOF\n", objects.len() + 1);
    out.extend_from_slice(tail.as_bytes());
    out
}

/// Runs `mach-vision sheet`.
pub(crate) fn run(args: &SheetArgs) -> Result<String, Failure> {
    let sheet = u32::try_from(args.sheet).ok().and_then(cal_sheet).ok_or_else(|| {
        Failure::Input(format!("no calibration sheet {} — the sheets are {}", args.sheet, known_sheets()))
    })?;
    let by_name = args.output.as_ref().and_then(|p| p.extension()).and_then(|e| e.to_str()).and_then(|e| {
        match e.to_ascii_lowercase().as_str() {
            "pdf" => Some(Format::Pdf),
            "svg" => Some(Format::Svg),
            _ => None,
        }
    });
    let format = args.format.or(by_name).unwrap_or(Format::Svg);
    let shapes = layout(sheet, args.paper)?;
    let bytes = match format {
        Format::Svg => svg(&shapes, args.paper).into_bytes(),
        Format::Pdf => pdf(&shapes, args.paper),
    };
    let Some(path) = &args.output else {
        return match format {
            Format::Svg => Ok(String::from_utf8_lossy(&bytes).into_owned()),
            Format::Pdf => Err(Failure::Input("--format pdf writes a file: give -o FILE.pdf".into())),
        };
    };
    std::fs::write(path, &bytes).map_err(|e| Failure::Input(format!("cannot write {}: {e}", path.display())))?;
    Ok(format!(
        "wrote calibration sheet {} ({}, {}) to {} — print it at 100 % and check the scale bars\n",
        sheet.id,
        args.paper.name(),
        if format == Format::Pdf { "PDF" } else { "SVG" },
        path.display()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_dot_of_the_table_is_drawn_at_its_size_and_place() {
        let sheet = cal_sheet(1).expect("sheet 1");
        for paper in [Paper::Letter, Paper::A4] {
            let (w, h) = paper.size_in();
            let dots: Vec<_> = layout(sheet, paper)
                .expect("fits")
                .into_iter()
                .filter_map(|s| match s {
                    Shape::Dot { x, y, r } => Some((x - w / 2.0, y - h / 2.0, r)),
                    _ => None,
                })
                .collect();
            assert_eq!(dots.len(), sheet.dots_in.len());
            for ((x, y, r), (tx, ty)) in dots.iter().zip(sheet.dots_in) {
                assert!((x - tx).abs() < 1e-12 && (y - ty).abs() < 1e-12 && (r - 0.25).abs() < 1e-12, "{paper:?}");
            }
        }
    }

    #[test]
    fn the_pdf_is_one_page_of_the_paper_with_a_valid_cross_reference_table() {
        let sheet = cal_sheet(1).expect("sheet 1");
        let bytes = pdf(&layout(sheet, Paper::A4).expect("fits"), Paper::A4);
        let text = String::from_utf8(bytes.clone()).expect("ascii");
        assert!(text.starts_with("%PDF-1.4\n") && text.ends_with("%%EOF\n"));
        assert!(text.contains("/MediaBox [0 0 595.276 841.890]"), "A4 in points");
        assert_eq!(text.matches("/Type /Page ").count(), 1);
        // Every xref entry points at its object.
        let xref = text.find("\nxref\n").expect("xref") + 1;
        let start: usize = text[text.rfind("startxref\n").expect("startxref") + 10..]
            .lines()
            .next()
            .and_then(|l| l.parse().ok())
            .expect("offset");
        assert_eq!(start, xref);
        for (i, line) in text[xref..].lines().skip(3).take(5).enumerate() {
            let at: usize = line[..10].parse().expect("offset");
            assert!(text[at..].starts_with(&format!("{} 0 obj", i + 1)), "object {}", i + 1);
        }
        // The stream's length is its content's.
        let s = text.find("stream\n").expect("stream") + 7;
        let e = text.find("endstream").expect("end");
        assert!(text.contains(&format!("/Length {}", e - s)));
        // Five dots, each four curves and a fill.
        assert_eq!(text.matches(" c f\n").count(), 5);
    }
}
