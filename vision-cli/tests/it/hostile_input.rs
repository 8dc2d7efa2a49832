//! Hostile image and file input through the built binary (issue 33, item 4): `locate` and
//! `run --camera camera --source` on bombs, cut-short files, FIFOs and devices, forged file
//! names and absurd options, as the user sees them, under an address-space cap and a deadline.
#![expect(clippy::cast_possible_truncation, reason = "test values are small and whole")]

use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use image::ImageEncoder;
use vision_locate::render::{render, Depth, PlacedMark, Scene, Shape};
use vision_locate::OwnedPixels;

fn dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("hostile_input");
    std::fs::create_dir_all(&d).expect("scratch dir");
    d
}

fn arg(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

use crate::common;

use common::bounded;

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn encode(format: image::ImageFormat, img: image::DynamicImage) -> Vec<u8> {
    let mut out = Cursor::new(Vec::new());
    img.write_to(&mut out, format).expect("encode");
    out.into_inner()
}

/// A 200 × 150 frame at 16 bits with a dark 40 px dot at (99.5, 74.5) in `locate`'s pixels.
fn dot16() -> Vec<u16> {
    let scene = Scene {
        marks: vec![PlacedMark { shape: Shape::Dot { diameter: 40.0 }, x: 99.5, y: 74.5, reflectance: 0.1 }],
        blur_sigma: 1.0,
        noise_sigma: 1.5 * 257.0,
        seed: 9,
        ..Scene::blank(200, 150, Depth::Sixteen)
    };
    let OwnedPixels::Gray16(px) = render(&scene).expect("scene").into_pixels() else { panic!("16 bit") };
    px
}

fn mkfifo(name: &str) -> PathBuf {
    let fifo = dir().join(name);
    let _ = std::fs::remove_file(&fifo);
    assert!(Command::new("mkfifo").arg(&fifo).status().expect("mkfifo").success());
    fifo
}

#[test]
fn locate_refuses_a_fifo_or_a_device_unread_and_without_blocking() {
    let fifo = mkfifo("frame.png");
    for path in [arg(&fifo), "/dev/zero", "/dev/urandom"] {
        let out = bounded(&["locate", "--diameter", "40", path], 256, 60).unwrap_or_else(|| panic!("{path} blocked"));
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{path}: {err}");
        assert!(err.contains("not a regular file"), "{path}: {err}");
        assert!(out.stdout.is_empty());
    }
}

#[test]
fn run_with_a_fifo_source_fails_at_the_first_trigger_instead_of_blocking() {
    // Issue 33: the read waited for a writer for ever (VisionCameraTimeout did not apply).
    let fifo = mkfifo("camera.fifo");
    let profile = dir().join("fifo-profile.toml");
    std::fs::write(&profile, "[vision]\nVisionEnabled = true\n[camera]\nVisionCameraMarkDiameterPx = 40.0\n")
        .expect("profile");
    let program = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/programs/01-calibrate-sheet.nc");
    let args = ["run", "--camera", "camera", "--source", arg(&fifo), "--profile", arg(&profile), arg(&program)];
    let out = bounded(&args, 512, 120).expect("the run blocked on the FIFO");
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("M283 failed: ") && err.contains("camera.fifo is a FIFO, not a regular file"), "{err}");
    assert!(err.contains("v4l2:PATH"), "{err}");
}

#[test]
fn locate_refuses_a_cut_short_jpeg_as_damaged() {
    // Issue 33: a truncated JPEG decoded silently (grey below the cut) and said "no mark".
    let jpeg = encode(
        image::ImageFormat::Jpeg,
        image::DynamicImage::ImageLuma16(image::ImageBuffer::from_raw(200, 150, dot16()).expect("size"))
            .into_luma8()
            .into(),
    );
    let cut = dir().join("cut.jpg");
    std::fs::write(&cut, &jpeg[..jpeg.len() * 2 / 3]).expect("write");
    let out = bounded(&["locate", "--diameter", "40", arg(&cut)], 512, 60).expect("ran");
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("cut.jpg is damaged: the JPEG ends before its end-of-image marker"), "{err}");
    assert!(out.stdout.is_empty());
}

#[test]
fn locate_decodes_bombs_within_a_small_address_space() {
    // Issue 33: a JPEG declaring 16 000² took 1 GB, an ICC-profile bomb PNG hundreds of MB.
    let rgb = image::RgbImage::from_fn(16, 16, |x, y| image::Rgb([(x * 16) as u8, (y * 16) as u8, 90]));
    let mut jpeg = encode(image::ImageFormat::Jpeg, image::DynamicImage::ImageRgb8(rgb));
    let sof = jpeg.windows(2).position(|p| p == [0xFF, 0xC0]).expect("a baseline frame header");
    jpeg[sof + 5..sof + 9].copy_from_slice(&[0x3E, 0x80, 0x3E, 0x80]);
    let bomb = dir().join("bomb.jpg");
    std::fs::write(&bomb, &jpeg).expect("write");
    let out = bounded(&["locate", "--diameter", "40", arg(&bomb)], 256, 60).expect("ran");
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    // Refused from the header, before anything is decoded.
    assert!(err.contains("bomb.jpg is 16000 × 16000 pixels (256 megapixels), over the 100 megapixels"), "{err}");

    let mut png = Vec::new();
    let mut encoder = image::codecs::png::PngEncoder::new(&mut png);
    encoder.set_icc_profile(vec![0; 200 << 20]).expect("ICC");
    encoder.write_image(&[200; 64], 8, 8, image::ExtendedColorType::L8).expect("encode");
    let icc = dir().join("icc-bomb.png");
    std::fs::write(&icc, &png).expect("write");
    let out = bounded(&["locate", "--diameter", "4", arg(&icc)], 256, 60).expect("ran");
    // Decoded (its ICC profile dropped): a blank 8 × 8 image has no mark, exit 1.
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("no mark in 1 of 1 images"), "{}", stderr(&out));
}

#[test]
fn locate_finds_10_bit_data_in_16_bit_samples() {
    // Issue 33: never found, and the message blamed focus.
    let ten_bit: Vec<u16> = dot16().iter().map(|&v| v >> 6).collect();
    let path = dir().join("ten-bit.png");
    image::ImageBuffer::<image::Luma<u16>, _>::from_raw(200, 150, ten_bit).expect("size").save(&path).expect("save");
    let out = bounded(&["locate", "--diameter", "40", arg(&path)], 512, 60).expect("ran");
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{text}{}", stderr(&out));
    // Rendered at (99.5, 74.5) in the renderer's pixel-corner frame: the same numbers here.
    assert!(text.contains("found x=99.5") && text.contains(" y=74.5"), "{text}");
}

#[test]
fn a_file_name_cannot_forge_a_line_of_the_text_output() {
    let blank = encode(
        image::ImageFormat::Png,
        image::DynamicImage::ImageLuma8(image::GrayImage::from_pixel(64, 48, image::Luma([200]))),
    );
    let forged = dir().join("blank.png\nok.png: found x=1.0000 y=2.0000 diameter=40.000 score=1.0000");
    std::fs::write(&forged, &blank).expect("write");
    let plain = dir().join("plain name.png");
    std::fs::write(&plain, &blank).expect("write");
    let out = bounded(&["locate", "--diameter", "40", arg(&forged), arg(&plain)], 512, 60).expect("ran");
    let text = String::from_utf8(out.stdout.clone()).expect("utf-8");
    assert_eq!(out.status.code(), Some(1), "{text}");
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2, "{text}");
    assert!(lines[0].starts_with('"') && lines[0].contains("blank.png\\nok.png: found"), "{text}");
    assert!(lines[0].contains("\": not found: "), "{text}");
    // An ordinary name is printed as it is.
    assert!(lines[1].starts_with(&format!("{}: not found: ", plain.display())), "{text}");
    assert!(!stderr(&out).contains('\n') || stderr(&out).lines().count() == 1, "{}", stderr(&out));
}

#[test]
fn absurd_options_get_short_messages_in_the_options_units() {
    let png = dir().join("opt.png");
    std::fs::write(
        &png,
        encode(
            image::ImageFormat::Png,
            image::DynamicImage::ImageLuma8(image::GrayImage::from_pixel(8, 8, image::Luma([9]))),
        ),
    )
    .expect("write");
    let out = bounded(&["locate", "--diameter", "1e-300", arg(&png)], 512, 60).expect("ran");
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.len() < 200, "{} bytes: {err}", err.len());
    assert!(err.contains("--diameter 1e-300") && err.contains("below the 4 px"), "{err}");
    let out = bounded(&["locate", "--diameter", "40", "--tolerance", "150", arg(&png)], 512, 60).expect("ran");
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("--tolerance 150: ") && err.contains("percent") && !err.contains("fraction"), "{err}");
    assert!(!err.contains("1.5"), "{err}");
}
