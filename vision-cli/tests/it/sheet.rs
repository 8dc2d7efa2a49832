//! `mach-vision sheet`: the printed calibration sheet has its dots at true size and place.
#![expect(clippy::cast_possible_truncation, clippy::cast_sign_loss, reason = "test values are small and whole")]

use std::path::PathBuf;
use std::process::Command;

use vision_core::sheets::cal_sheet;
use vision_locate::{locate, GrayImage, Located, MarkKind, MarkSpec, Pixels, Polarity};

fn scratch(name: &str) -> PathBuf {
    crate::common::scratch("sheet", name)
}

fn sheet(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_mach-vision")).arg("sheet").args(args).output().expect("spawn")
}

/// Pixels per inch the sheet is rasterised at.
const PPI: f64 = 150.0;

/// The SVG file drawn by librsvg's `rsvg-convert` (Debian's `librsvg2-bin`, which `scripts/test`
/// installs) at [`PPI`] on white: an SVG renderer that is not ours. Grey levels, row-major, and
/// the width in pixels; the size is checked against the paper's `(width, height)` in inches.
fn rasterise(svg: &std::path::Path, paper_in: (f64, f64)) -> (Vec<u8>, usize) {
    let png = svg.with_extension("png");
    let dpi = PPI.to_string();
    let out = Command::new("rsvg-convert")
        .args(["--dpi-x", &dpi, "--dpi-y", &dpi, "--background-color", "white", "--format", "png", "-o"])
        .arg(&png)
        .arg(svg)
        .output()
        .unwrap_or_else(|e| panic!("rsvg-convert ({e}): install Debian's librsvg2-bin (scripts/test does)"));
    assert!(out.status.success(), "rsvg-convert: {}", String::from_utf8_lossy(&out.stderr));
    let image = image::open(&png).expect("rsvg-convert's PNG").to_luma8();
    let (w, h) = (image.width() as usize, image.height() as usize);
    let expected = ((paper_in.0 * PPI).round() as usize, (paper_in.1 * PPI).round() as usize);
    assert!(w.abs_diff(expected.0) <= 1 && h.abs_diff(expected.1) <= 1, "{w}x{h} px, expected {expected:?}");
    (image.into_raw(), w)
}

#[test]
fn the_svg_sheet_rasterised_has_every_dot_where_the_table_says_within_a_thousandth() {
    let table = cal_sheet(1).expect("sheet 1");
    for (paper, (w_in, h_in)) in [("letter", (8.5, 11.0)), ("a4", (210.0 / 25.4, 297.0 / 25.4))] {
        let dir = scratch(paper);
        let file = dir.join("sheet.svg");
        let out = sheet(&["1", "--paper", paper, "-o", file.to_str().expect("utf-8")]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        assert!(String::from_utf8_lossy(&out.stdout).contains("print it at 100 %"));
        let text = std::fs::read_to_string(&file).expect("svg");
        assert!(text.contains(&format!("width=\"{w_in:.4}in\" height=\"{h_in:.4}in\"")), "physical size");
        assert!(text.contains("check: this bar measures 100 mm") && text.contains("check: this bar measures 4 in"));

        let (gray, w) = rasterise(&file, (w_in, h_in));

        let d = table.mark_diameter_in * PPI;
        let spec = MarkSpec::new(MarkKind::Dot, d, 0.1, Polarity::DarkOnLight).expect("spec");
        for (x, y) in table.dots_in {
            // A window of 1.2 in round where the dot should be (the crosshair and labels in it).
            let (u, v) = ((w_in / 2.0 + x) * PPI, (h_in / 2.0 - y) * PPI);
            let half = 0.6 * PPI;
            let (u0, v0) = ((u - half) as usize, (v - half) as usize);
            let n = (2.0 * half) as usize;
            let window: Vec<u8> = (v0..v0 + n).flat_map(|row| gray[row * w + u0..row * w + u0 + n].to_vec()).collect();
            let image = GrayImage::new(n, n, Pixels::Gray8(&window)).expect("image");
            let Located::Found(m) = locate(&image, &spec).expect("locate") else {
                panic!("{paper}: no dot found at ({x}, {y}) in")
            };
            // Pixel centres to corner coordinates, then inches in the sheet's frame.
            let found_x = (u0 as f64 + m.x + 0.5) / PPI - w_in / 2.0;
            let found_y = h_in / 2.0 - (v0 as f64 + m.y + 0.5) / PPI;
            assert!(
                (found_x - x).abs() < 0.001 && (found_y - y).abs() < 0.001,
                "{paper}: dot ({x}, {y}) in found at ({found_x:.5}, {found_y:.5})"
            );
            assert!((m.diameter / PPI - table.mark_diameter_in).abs() < 0.002, "{paper}: true size: {}", m.diameter);
        }
    }
}

#[test]
fn the_pdf_is_written_to_a_file_and_bad_requests_say_what_to_do() {
    let dir = scratch("pdf");
    let file = dir.join("sheet.pdf");
    let out = sheet(&["-o", file.to_str().expect("utf-8")]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let bytes = std::fs::read(&file).expect("pdf");
    assert!(bytes.starts_with(b"%PDF-1.4") && bytes.ends_with(b"%%EOF\n"));
    assert!(String::from_utf8_lossy(&bytes).contains("/MediaBox [0 0 612.000 792.000]"), "US Letter");

    let out = sheet(&["--format", "pdf"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("give -o FILE.pdf"));
    let out = sheet(&["7"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no calibration sheet 7 — the sheets are 1"));
    // Standard output gets the SVG.
    let out = sheet(&[]);
    assert!(out.status.success() && String::from_utf8_lossy(&out.stdout).starts_with("<svg "));
}
