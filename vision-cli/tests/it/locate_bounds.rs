//! Issue 33: `mach-vision locate` within bounded memory, through the built binary under an
//! address-space limit — images too large to search are refused from their header, before a
//! pixel is decoded, and the images are decoded one at a time.
#![expect(clippy::cast_possible_truncation, clippy::cast_sign_loss, reason = "test values are small and whole")]

use std::io::Write as _;
use std::path::PathBuf;
use std::process::Output;

fn dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("locate_bounds");
    std::fs::create_dir_all(&d).expect("scratch dir");
    d
}

/// Writes (once: kept between runs) a `side` × `side` 8-bit grey PNG, white, with a black dot
/// of `dot` px diameter at its centre, row by row: the test never holds the image.
fn png(name: &str, side: u32, dot: f64) -> PathBuf {
    let path = dir().join(name);
    if path.exists() {
        return path;
    }
    let tmp = dir().join(format!("{name}.part"));
    let file = std::io::BufWriter::new(std::fs::File::create(&tmp).expect("create"));
    let mut encoder = png::Encoder::new(file, side, side);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    let mut writer = encoder.write_header().expect("header");
    let mut stream = writer.stream_writer().expect("stream");
    let c = f64::from(side) / 2.0;
    let white = vec![255u8; side as usize];
    let mut row = white.clone();
    for y in 0..side {
        // The pixels whose centres are inside the dot: a chord of the row.
        let dy = f64::from(y) + 0.5 - c;
        let half = ((dot / 2.0).powi(2) - dy * dy).max(0.0).sqrt();
        row.copy_from_slice(&white);
        if half > 0.0 {
            let (x0, x1) = ((c - half - 0.5).ceil() as usize, (c + half - 0.5).floor() as usize);
            row[x0..=x1].fill(0);
        }
        stream.write_all(&row).expect("row");
    }
    stream.finish().expect("finish");
    std::fs::rename(&tmp, &path).expect("rename");
    path
}

use crate::common;

/// Runs `mach-vision locate ARGS` under an address-space limit of `megabytes`, killed after
/// `seconds` ([`common::bounded`]).
fn bounded(args: &[&str], megabytes: u64, seconds: u64) -> Option<Output> {
    let all: Vec<&str> = std::iter::once("locate").chain(args.iter().copied()).collect();
    common::bounded(&all, megabytes, seconds)
}

#[test]
fn an_image_over_the_pixel_bound_is_refused_from_its_header() {
    // Issue 33: a 22 000² PNG of half a megabyte at --diameter 4 allocated 8 GB.
    let big = png("22000.png", 22_000, 40.0);
    let path = big.to_str().expect("utf-8");
    let out = bounded(&["--diameter", "4", path], 256, 60).expect("refused in time");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(out.stdout.is_empty());
    assert!(
        err.contains(&format!(
            "image {path} is 22000 × 22000 pixels (484 megapixels), over the 100 megapixels an image may have — crop or scale it around the mark"
        )),
        "{err}"
    );
}

#[test]
fn an_image_too_large_to_search_at_its_diameter_is_refused_from_its_header() {
    // 81 megapixels is within the pixel bound, but at --diameter 4 the finder would search it in
    // blocks of 1 px: 16 bytes a pixel, over its 1 GiB. A later file does not help the first.
    let big = png("9000.png", 9_000, 40.0);
    let small = png("3000.png", 3_000, 40.0);
    let (big, small) = (big.to_str().expect("utf-8"), small.to_str().expect("utf-8"));
    let out = bounded(&["--diameter", "4", small, big], 256, 60).expect("refused in time");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(out.stdout.is_empty(), "nothing is searched before every file is sized");
    assert!(
        err.contains(&format!("image {big}: searching a 9000 × 9000 image at blocks of 1 px needs 12"))
            && err.contains(
                " MiB, over the finder's 1024 MiB limit — crop the image around the mark, or give a mark diameter of at least 12 px"
            ),
        "{err}"
    );
}

#[test]
fn images_are_decoded_one_at_a_time() {
    // Issue 33: 40 files of 120 KB took 3.9 GB, all decoded before any was searched. Twenty
    // 9-megapixel images (9 MB each decoded, 180 MB together) now fit in 96 MB.
    let file = png("3000.png", 3_000, 40.0);
    let path = file.to_str().expect("utf-8");
    let mut args = vec!["--diameter", "40", "--json"];
    args.extend([path; 20]);
    let out = bounded(&args, 96, 300).expect("ran in time");
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let report = String::from_utf8(out.stdout).expect("utf-8");
    assert_eq!(report.lines().count(), 20);
    for line in report.lines() {
        let o: serde_json::Value = serde_json::from_str(line).expect("JSON");
        assert_eq!(o["found"], true, "{o}");
        assert!(
            (o["x"].as_f64().unwrap() - 1499.5).abs() < 0.05 && (o["y"].as_f64().unwrap() - 1499.5).abs() < 0.05,
            "{o}"
        );
    }
}
