//! Frames: 8-bit grey images, decoded from what sources deliver (JPEG, PNG, PGM files and
//! snapshots; raw GREY, YUYV and MJPEG device buffers).

use std::io::Cursor;

use crate::config::PixelFormat;
use crate::decode::{decode_grey, DecodeError, GreySamples, MAX_METADATA_BYTES};
use crate::error::CameraError;

/// Most pixels in one frame (100 megapixels): a bound on what a hostile source can make us
/// allocate.
pub const MAX_PIXELS: u64 = 100_000_000;

/// One grey frame, row-major, 8 bits per pixel, `width × height` bytes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frame {
    width: u32,
    height: u32,
    pixels: Vec<u8>,
}

impl Frame {
    /// A frame of `width × height` from its row-major pixels; `None` when the sizes disagree or
    /// a side is 0.
    #[must_use]
    pub fn new(width: u32, height: u32, pixels: Vec<u8>) -> Option<Frame> {
        let n = u64::from(width) * u64::from(height);
        (n > 0 && n <= MAX_PIXELS && usize::try_from(n).ok() == Some(pixels.len())).then_some(Frame {
            width,
            height,
            pixels,
        })
    }

    /// Width, pixels.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height, pixels.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The pixels, row-major.
    #[must_use]
    pub fn pixels(&self) -> &[u8] {
        &self.pixels
    }

    /// The pixels, owned.
    #[must_use]
    pub fn into_pixels(self) -> Vec<u8> {
        self.pixels
    }
}

/// Decodes an encoded image (JPEG, PNG, PGM/PNM, by its content) to grey with the bounds of
/// [`crate::decode`]: the size is checked from the header first (at most [`MAX_PIXELS`] and
/// [`crate::settings::MAX_SIDE_PX`] a side), a cut-short JPEG is refused as damaged, colour
/// becomes luma (ITU-R BT.709 weights, the `image` crate's), 16-bit samples are scaled by their
/// range and rounded to 8 bits.
///
/// # Errors
/// [`CameraError::Decode`] naming `from`, [`CameraError::Damaged`],
/// [`CameraError::TooManyPixels`] or [`CameraError::TooLarge`] (metadata).
pub fn decode_image(bytes: &[u8], from: &str) -> Result<Frame, CameraError> {
    let max_side = u32::try_from(crate::settings::MAX_SIDE_PX).unwrap_or(u32::MAX);
    let grey = decode_grey(Cursor::new(bytes), max_side).map_err(|e| camera_error(e, from))?;
    let (w, h) = (grey.width(), grey.height());
    let pixels = match grey.into_samples() {
        GreySamples::Eight(p) => p,
        // Rounded as the `image` crate converts 16 to 8 bits.
        GreySamples::Sixteen(p) => {
            p.iter().map(|&v| u8::try_from((u32::from(v) + 128) / 257).unwrap_or(u8::MAX)).collect()
        }
    };
    Frame::new(w, h, pixels)
        .ok_or_else(|| CameraError::Decode { from: from.to_string(), reason: format!("an image of {w}×{h} pixels") })
}

/// A [`DecodeError`] as the driver reports it, naming where the frame came from.
fn camera_error(e: DecodeError, from: &str) -> CameraError {
    let from = from.to_string();
    match e {
        DecodeError::Damaged(reason) => CameraError::Damaged { from, reason },
        DecodeError::TooLarge { width, height, limit } => CameraError::TooManyPixels { from, width, height, limit },
        DecodeError::Metadata => CameraError::TooLarge {
            from,
            limit: usize::try_from(MAX_METADATA_BYTES).unwrap_or(usize::MAX),
            what: "bytes of metadata",
        },
        other => CameraError::Decode { from, reason: other.to_string() },
    }
}

/// Decodes one raw V4L2 buffer of `format`, `width × height`, rows `stride` bytes apart (the
/// device's `bytesperline`; 0 for packed rows).
///
/// # Errors
/// [`CameraError::ShortFrame`] when the buffer is too short for the format;
/// [`CameraError::Decode`] for a bad MJPEG frame, or one of another size.
pub fn decode_raw(
    format: PixelFormat,
    width: u32,
    height: u32,
    stride: u32,
    bytes: &[u8],
    device: &str,
) -> Result<Frame, CameraError> {
    let (w, h) = (width as usize, height as usize);
    let too_large = || CameraError::TooLarge { from: device.to_string(), limit: 16_384, what: "pixels a side" };
    if w == 0 || h == 0 || u64::from(width) * u64::from(height) > MAX_PIXELS {
        return Err(too_large());
    }
    let per_pixel = match format {
        PixelFormat::Grey => 1,
        PixelFormat::Yuyv => 2,
        PixelFormat::Mjpeg => {
            let frame = decode_image(bytes, device)?;
            if (frame.width, frame.height) != (width, height) {
                return Err(CameraError::Decode {
                    from: device.to_string(),
                    reason: format!("an MJPEG frame of {}×{} in a {width}×{height} stream", frame.width, frame.height),
                });
            }
            return Ok(frame);
        }
    };
    let row = w * per_pixel;
    let stride = if stride == 0 { row } else { stride as usize };
    let want = stride.max(row) * (h - 1) + row;
    if stride < row || bytes.len() < want {
        return Err(CameraError::ShortFrame {
            device: device.to_string(),
            got: bytes.len(),
            want: stride.max(row) * h,
        });
    }
    let mut pixels = Vec::with_capacity(w * h);
    for y in 0..h {
        let line = &bytes[y * stride..y * stride + row];
        match format {
            PixelFormat::Grey => pixels.extend_from_slice(line),
            // Y0 U Y1 V: the even bytes are luma.
            _ => pixels.extend(line.iter().step_by(2)),
        }
    }
    Frame::new(width, height, pixels).ok_or_else(too_large)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn encode(format: image::ImageFormat, img: &image::DynamicImage) -> Vec<u8> {
        let mut out = Cursor::new(Vec::new());
        img.write_to(&mut out, format).expect("encode");
        out.into_inner()
    }

    fn gradient(w: u32, h: u32) -> image::GrayImage {
        image::GrayImage::from_fn(w, h, |x, y| image::Luma([u8::try_from((x * 7 + y * 3) % 256).unwrap_or(0)]))
    }

    #[test]
    fn png_and_pgm_decode_exactly_and_colour_becomes_luma() {
        let g = gradient(13, 7);
        for format in [image::ImageFormat::Png, image::ImageFormat::Pnm] {
            let f = decode_image(&encode(format, &image::DynamicImage::ImageLuma8(g.clone())), "t").expect("decode");
            assert_eq!((f.width(), f.height(), f.pixels()), (13, 7, g.as_raw().as_slice()), "{format:?}");
        }
        let rgb = image::RgbImage::from_pixel(4, 3, image::Rgb([200, 200, 200]));
        let f = decode_image(&encode(image::ImageFormat::Png, &image::DynamicImage::ImageRgb8(rgb)), "t").expect("rgb");
        assert!(f.pixels().iter().all(|&p| p == 200));
        let jpeg = encode(image::ImageFormat::Jpeg, &image::DynamicImage::ImageLuma8(gradient(32, 16)));
        let f = decode_image(&jpeg, "t").expect("jpeg");
        assert_eq!((f.width(), f.height()), (32, 16));
        let e = decode_image(b"not an image", "a.bin").expect_err("garbage");
        assert!(e.to_string().starts_with("Malformed response: the frame from a.bin is not an image"), "{e}");
    }

    #[test]
    fn raw_buffers_decode_with_their_stride() {
        // YUYV 2×2 with a 2-byte row pad: Y = 10 20 / 30 40.
        let yuyv = [10, 128, 20, 128, 0, 0, 30, 128, 40, 128, 0, 0];
        let f = decode_raw(PixelFormat::Yuyv, 2, 2, 6, &yuyv, "/dev/video9").expect("yuyv");
        assert_eq!(f.pixels(), [10, 20, 30, 40]);
        let f = decode_raw(PixelFormat::Grey, 3, 1, 0, &[1, 2, 3], "d").expect("grey");
        assert_eq!(f.pixels(), [1, 2, 3]);
        let e = decode_raw(PixelFormat::Yuyv, 2, 2, 0, &yuyv[..7], "/dev/video9").expect_err("short");
        assert_eq!(e, CameraError::ShortFrame { device: "/dev/video9".into(), got: 7, want: 8 });
        let jpeg = encode(image::ImageFormat::Jpeg, &image::DynamicImage::ImageLuma8(gradient(16, 8)));
        assert!(decode_raw(PixelFormat::Mjpeg, 16, 8, 0, &jpeg, "d").is_ok());
        let e = decode_raw(PixelFormat::Mjpeg, 32, 8, 0, &jpeg, "d").expect_err("size");
        assert!(e.to_string().contains("16×8 in a 32×8 stream"), "{e}");
    }

    proptest! {
        /// Any bytes, any claimed format and size: a frame or a typed error, never a panic.
        #[test]
        fn arbitrary_buffers_never_panic(
            bytes in proptest::collection::vec(any::<u8>(), 0..400),
            w in 0u32..40, h in 0u32..40, stride in 0u32..100, which in 0usize..3,
        ) {
            let format = [PixelFormat::Grey, PixelFormat::Yuyv, PixelFormat::Mjpeg][which];
            if let Ok(f) = decode_raw(format, w, h, stride, &bytes, "d") {
                prop_assert_eq!(f.pixels().len(), (w * h) as usize);
            }
            let _ = decode_image(&bytes, "d");
        }

        /// A PNG or PGM header followed by garbage: a typed error, never a panic.
        #[test]
        fn damaged_images_never_panic(tail in proptest::collection::vec(any::<u8>(), 0..200), png in any::<bool>()) {
            let head: &[u8] = if png { b"\x89PNG\r\n\x1a\n" } else { b"P5\n4 4\n255\n" };
            let _ = decode_image(&[head, &tail].concat(), "d");
        }
    }
}
