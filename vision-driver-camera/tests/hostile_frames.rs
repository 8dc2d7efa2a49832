//! Hostile and damaged frames (issue 33): a header declaring a huge image, a metadata bomb, a
//! cut-short file, 10-bit data in 16-bit samples, and paths that are not regular files. Each is
//! refused (or read) within a bound this binary measures with its counting allocator.
#![expect(clippy::cast_possible_truncation, reason = "test values are small and whole")]

use std::io::Cursor;
use std::path::PathBuf;
use std::sync::mpsc;
use std::time::Duration;

use image::ImageEncoder;
use vision_core::CameraDriver;
use vision_driver_camera::{decode_image, CameraConfig, CameraError, FileSource, FrameDriver, FrameSource, Source};
use vision_locate::render::{render, Depth, PlacedMark, Scene, Shape};
use vision_locate::OwnedPixels;

#[global_allocator]
static GLOBAL: vision_testalloc::PeakAlloc = vision_testalloc::PeakAlloc;

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("hostile_frames");
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir.join(name)
}

/// A 64 × 48 frame, a dark 20 px dot at (30.0, 20.0) native, at 16 bits.
fn dot16() -> Vec<u16> {
    let scene = Scene {
        marks: vec![PlacedMark { shape: Shape::Dot { diameter: 20.0 }, x: 29.5, y: 19.5, reflectance: 0.1 }],
        blur_sigma: 1.0,
        noise_sigma: 300.0,
        seed: 4,
        ..Scene::blank(64, 48, Depth::Sixteen)
    };
    let OwnedPixels::Gray16(px) = render(&scene).expect("scene").into_pixels() else { panic!("16 bit") };
    px
}

fn encode(format: image::ImageFormat, img: image::DynamicImage) -> Vec<u8> {
    let mut out = Cursor::new(Vec::new());
    img.write_to(&mut out, format).expect("encode");
    out.into_inner()
}

fn grey8(px: &[u16]) -> image::DynamicImage {
    let px = px.iter().map(|&v| u8::try_from(v >> 8).unwrap_or(u8::MAX)).collect();
    image::DynamicImage::ImageLuma8(image::GrayImage::from_raw(64, 48, px).expect("size"))
}

/// A colour JPEG of a few hundred bytes whose frame header declares `w × h`.
fn jpeg_declaring(w: u16, h: u16) -> Vec<u8> {
    let rgb = image::RgbImage::from_fn(16, 16, |x, y| image::Rgb([(x * 16) as u8, (y * 16) as u8, 90]));
    let mut b = encode(image::ImageFormat::Jpeg, image::DynamicImage::ImageRgb8(rgb));
    let sof = b.windows(2).position(|p| p == [0xFF, 0xC0]).expect("a baseline frame header");
    b[sof + 5..sof + 7].copy_from_slice(&h.to_be_bytes());
    b[sof + 7..sof + 9].copy_from_slice(&w.to_be_bytes());
    b
}

/// An 8 × 8 PNG carrying an ICC profile of `icc` zero bytes (it compresses about 1000:1).
fn png_with_icc(icc: usize) -> Vec<u8> {
    let img = image::GrayImage::from_pixel(8, 8, image::Luma([128]));
    let mut out = Vec::new();
    let mut encoder = image::codecs::png::PngEncoder::new(&mut out);
    encoder.set_icc_profile(vec![0; icc]).expect("png takes an ICC profile");
    encoder.write_image(img.as_raw(), 8, 8, image::ExtendedColorType::L8).expect("encode");
    out
}

#[test]
fn a_jpeg_declaring_a_huge_frame_is_refused_from_its_header() {
    // Issue 33: a 629-byte JPEG declaring 20 000² cost 1 GB before the 100-megapixel check.
    for (w, h) in [(16_000, 16_000), (20_000, 20_000), (16_000, 6_251)] {
        let bytes = jpeg_declaring(w, h);
        assert!(bytes.len() < 1000, "{}", bytes.len());
        let (result, peak) = vision_testalloc::peak_during(|| decode_image(&bytes, "bomb.jpg"));
        let e = result.expect_err("refused");
        assert!(e.to_string().contains(&format!("declares {w}×{h} pixels, more than")), "{e}");
        assert!(peak < 1 << 20, "{w}×{h}: {peak} bytes allocated to refuse a header");
    }
}

#[test]
fn an_icc_profile_bomb_costs_no_more_than_the_metadata_bound() {
    // Issue 33: an ICC-profile bomb PNG cost 789 MB.
    let bytes = vision_testalloc::alone(|| png_with_icc(96 << 20));
    assert!(bytes.len() < 1 << 20, "{}", bytes.len());
    let (frame, peak) = vision_testalloc::peak_during(|| decode_image(&bytes, "icc.png"));
    assert_eq!(frame.expect("the pixels are fine").pixels(), [128; 64]);
    // The bounded inflate grows its buffer by doubling up to the bound: under twice the bound.
    let bound = usize::try_from(vision_driver_camera::decode::MAX_METADATA_BYTES).expect("fits");
    assert!(peak < 2 * bound, "{peak} bytes for an 8 × 8 image");
}

#[test]
fn a_cut_short_frame_is_refused_as_damaged_never_decoded() {
    // Issue 33: a truncated JPEG decoded silently (grey below the cut: "no mark", or a wrong one).
    let px = vision_testalloc::alone(dot16);
    let jpeg = encode(image::ImageFormat::Jpeg, grey8(&px));
    for cut in [jpeg.len() / 3, jpeg.len() / 2, jpeg.len() - 40, jpeg.len() - 2] {
        let e = vision_testalloc::alone(|| decode_image(&jpeg[..cut], "cut.jpg")).expect_err("cut short");
        assert!(e.to_string().contains("the frame from cut.jpg is damaged"), "{cut} of {}: {e}", jpeg.len());
    }
    // Any prefix of a PNG, PGM or JPEG is refused or gives the very same pixels.
    for format in [image::ImageFormat::Png, image::ImageFormat::Pnm, image::ImageFormat::Jpeg] {
        let bytes = encode(format, grey8(&px));
        let whole = decode_image(&bytes, "whole").expect("whole");
        for cut in 0..bytes.len() {
            if let Ok(frame) = vision_testalloc::alone(|| decode_image(&bytes[..cut], "cut")) {
                assert_eq!(frame, whole, "{format:?} cut at {cut} of {} decoded to other pixels", bytes.len());
            }
        }
    }
}

#[test]
fn a_16_bit_frame_holding_10_bit_data_is_found() {
    // Issue 33: 10-bit data in 16-bit samples (0..1023) kept its top 8 bits: a black frame.
    let ten_bit: Vec<u16> = vision_testalloc::alone(dot16).iter().map(|&v| v >> 6).collect();
    let path = scratch("ten-bit.png");
    image::ImageBuffer::<image::Luma<u16>, _>::from_raw(64, 48, ten_bit).expect("size").save(&path).expect("save");
    let config = CameraConfig::new(Source::Files(path.clone()), 20.0);
    let mut camera = FrameDriver::new(config, FileSource::new(&path)).expect("driver");
    let reading = vision_testalloc::alone(|| camera.trigger()).expect("reading");
    assert!(reading.found(), "{:?}", camera.last_miss());
    assert!((reading.x_px - 30.0).abs() < 0.2 && (reading.y_px - 20.0).abs() < 0.2, "{reading:?}");
}

/// The first frame of `path`, or `None` when it did not come within 30 s (it blocked).
fn first_frame(path: PathBuf) -> Option<Result<vision_driver_camera::Frame, CameraError>> {
    let (tx, rx) = mpsc::channel();
    // Not inside `alone`: a blocked read would hold the measurements' lock for ever.
    std::thread::spawn(move || {
        let _ = tx.send(FileSource::new(path).frame());
    });
    rx.recv_timeout(Duration::from_secs(30)).ok()
}

#[cfg(unix)]
#[test]
fn a_fifo_or_a_device_is_refused_unread() {
    let fifo = scratch("frames.fifo");
    let _ = std::fs::remove_file(&fifo);
    let made = std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo");
    assert!(made.success());
    // No writer: an open without O_NONBLOCK would wait for one for ever.
    let e = first_frame(fifo.clone()).expect("a FIFO without a writer blocked the read").expect_err("refused");
    assert!(e.to_string().contains("is a FIFO, not a regular file"), "{e}");
    for device in ["/dev/zero", "/dev/urandom"] {
        let e = first_frame(device.into()).expect("not blocked").expect_err("refused");
        assert!(e.to_string().contains("is a character device, not a regular file"), "{e}");
        assert!(e.to_string().contains("v4l2:"), "{e}");
    }
    std::fs::remove_file(&fifo).expect("clean up");
}

#[test]
fn a_large_honest_png_still_decodes_under_the_metadata_bound() {
    // The PNG decoder's own buffers come out of the metadata allowance: a 20-megapixel 16-bit
    // frame (40 MB of samples) must not be refused by it.
    let bytes = vision_testalloc::alone(|| {
        let img = image::ImageBuffer::<image::Luma<u16>, _>::from_fn(5000, 4000, |x, y| {
            image::Luma([((x + y) % 4096) as u16])
        });
        encode(image::ImageFormat::Png, image::DynamicImage::ImageLuma16(img))
    });
    let frame = vision_testalloc::alone(|| decode_image(&bytes, "big.png")).expect("decodes");
    assert_eq!((frame.width(), frame.height()), (5000, 4000));
    // 12-bit data (largest 4095) scaled by 16: the brightest sample is near white.
    assert_eq!(frame.pixels().iter().max(), Some(&255));
}
