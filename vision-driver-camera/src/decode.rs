//! Encoded images (JPEG, PNG, PGM/PNM, and BMP where the `image` crate is built with it) decoded
//! to grey with bounded work, for the camera driver and `mach-vision locate` alike.
//!
//! Limits and decisions (issue 33):
//! * The size is read from the header and checked before the pixels are allocated: at most
//!   [`MAX_PIXELS`], at most `max_side` a side, and a decoded buffer (all channels) of at most
//!   [`MAX_DECODED_BYTES`]. Peak memory of one decode is that buffer plus its grey copy (none
//!   for a grey image) plus under twice [`MAX_METADATA_BYTES`] (the bounded inflate doubles
//!   its buffer up to the bound).
//! * Metadata gets at most [`MAX_METADATA_BYTES`]: a PNG's ICC profile larger than that is
//!   dropped unread (grey needs no colour profile), other ancillary chunks beyond it refuse the
//!   image. A JPEG's metadata is bounded by its file.
//! * A JPEG must reach its end-of-image marker (bytes after it are ignored): the decoder fills a
//!   cut-short JPEG with grey and says nothing, which would read as "no mark" or a wrong one.
//!   PNG, PGM and BMP decoders report missing pixel data themselves.
//! * 16-bit samples are scaled by the data's own range: shifted left until the largest sample
//!   uses the top bit, so 10-, 12- or 14-bit sensor data in 16-bit samples (0..1023 …) spans
//!   the full range. A power of two keeps the samples' ratios exact; a PNG's `sBIT` chunk is not
//!   read (the `image` crate does not expose it) and would say no more for finding a mark.
//!   8-bit samples are kept as they are.

use std::io::{self, BufRead, Seek, SeekFrom};

use image::{DynamicImage, ImageDecoder, ImageError, ImageFormat, ImageReader, Limits};

use crate::frame::MAX_PIXELS;

/// Most bytes the decoder's own buffer may take (all channels at their depth): an 8-bit RGBA
/// frame of [`MAX_PIXELS`]. A 16-bit colour image must be smaller.
pub const MAX_DECODED_BYTES: u64 = 4 * MAX_PIXELS;

/// Most bytes of metadata (a PNG's ICC profile, text chunks) a decode may hold, 16 MiB.
pub const MAX_METADATA_BYTES: u64 = 16 << 20;

/// Why bytes did not decode to an image.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum DecodeError {
    /// The bytes start like no supported format.
    #[error("neither JPEG, PNG, PGM nor BMP")]
    UnknownFormat,
    /// The format is known but the data is not a valid image.
    #[error("{0}")]
    Invalid(String),
    /// The image ends before all of it came: a cut-short file or transfer.
    #[error("it is damaged: {0}")]
    Damaged(String),
    /// The header declares more pixels than [`MAX_PIXELS`], or a side longer than allowed.
    #[error("its header declares {width}×{height} pixels, more than {limit}")]
    TooLarge {
        /// Declared width, pixels.
        width: u32,
        /// Declared height, pixels.
        height: u32,
        /// The bound that was passed, in words (`100000000 pixels`, `16384 pixels a side`).
        limit: String,
    },
    /// Metadata above [`MAX_METADATA_BYTES`].
    #[error("its metadata takes more than {MAX_METADATA_BYTES} bytes")]
    Metadata,
    /// Reading the bytes failed.
    #[error("{0}")]
    Io(String),
}

/// A decoded grey image's samples, row-major, top row first.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum GreySamples {
    /// 8-bit, 0 black … 255 white.
    Eight(Vec<u8>),
    /// 16-bit, 0 black … 65535 white (scaled to the data's range, see the module docs).
    Sixteen(Vec<u16>),
}

/// A decoded grey image: `width × height` samples.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Grey {
    width: u32,
    height: u32,
    samples: GreySamples,
}

impl Grey {
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

    /// The samples, owned.
    #[must_use]
    pub fn into_samples(self) -> GreySamples {
        self.samples
    }
}

/// Decodes an encoded image to grey within the bounds of the module docs: colour becomes luma
/// (ITU-R BT.709 weights, the `image` crate's), 16-bit samples stay 16-bit, scaled to their range.
/// `max_side` bounds each side, pixels.
///
/// # Errors
/// A [`DecodeError`]; nothing larger than its header's check is allocated first.
pub fn decode_grey<R: BufRead + Seek>(mut reader: R, max_side: u32) -> Result<Grey, DecodeError> {
    let io_err = |e: io::Error| DecodeError::Io(e.to_string());
    let start = reader.stream_position().map_err(io_err)?;
    let mut head = Vec::with_capacity(16);
    io::Read::read_to_end(&mut io::Read::take(&mut reader, 16), &mut head).map_err(io_err)?;
    let format = image::guess_format(&head).map_err(|_| DecodeError::UnknownFormat)?;
    if format == ImageFormat::Jpeg {
        reader.seek(SeekFrom::Start(start)).map_err(io_err)?;
        jpeg_reaches_its_end(&mut reader)?;
    }
    reader.seek(SeekFrom::Start(start)).map_err(io_err)?;
    let mut reader = ImageReader::with_format(reader, format);
    // The PNG decoder takes its metadata allowance from here; the size is checked below, from
    // the header, before the pixels are allocated.
    let mut limits = Limits::no_limits();
    limits.max_alloc = Some(MAX_METADATA_BYTES);
    reader.limits(limits);
    let decoder = reader.into_decoder().map_err(classify)?;
    let (width, height) = decoder.dimensions();
    let too_large = |limit: String| DecodeError::TooLarge { width, height, limit };
    if width == 0 || height == 0 {
        return Err(DecodeError::Invalid(format!("an image of {width}×{height} pixels")));
    }
    if width.max(height) > max_side {
        return Err(too_large(format!("{max_side} pixels a side")));
    }
    if u64::from(width) * u64::from(height) > MAX_PIXELS {
        return Err(too_large(format!("{MAX_PIXELS} pixels")));
    }
    if decoder.total_bytes() > MAX_DECODED_BYTES {
        return Err(too_large(format!(
            "{MAX_DECODED_BYTES} bytes decoded ({} bytes a pixel)",
            decoder.color_type().bytes_per_pixel()
        )));
    }
    let image = DynamicImage::from_decoder(decoder).map_err(classify)?;
    let samples = match image.color() {
        image::ColorType::L16 | image::ColorType::La16 | image::ColorType::Rgb16 | image::ColorType::Rgba16 => {
            let mut grey = image.into_luma16().into_raw();
            to_full_range(&mut grey);
            GreySamples::Sixteen(grey)
        }
        _ => GreySamples::Eight(image.into_luma8().into_raw()),
    };
    Ok(Grey { width, height, samples })
}

/// `image`'s error in this module's terms: running out of data is damage, not a bad format.
fn classify(e: ImageError) -> DecodeError {
    match e {
        ImageError::IoError(io) if io.kind() == io::ErrorKind::UnexpectedEof => {
            DecodeError::Damaged(format!("it ends before its pixel data does ({io})"))
        }
        ImageError::IoError(io) => DecodeError::Io(io.to_string()),
        ImageError::Limits(_) => DecodeError::Metadata,
        ImageError::Unsupported(_) => DecodeError::Invalid(e.to_string()),
        other => {
            let text = other.to_string();
            // The PNG and BMP decoders say "unexpected end of file" / "EOF" in their own errors.
            if text.to_ascii_lowercase().contains("end of file") || text.contains("EOF") {
                DecodeError::Damaged(text)
            } else {
                DecodeError::Invalid(text)
            }
        }
    }
}

/// Shifts 16-bit samples left until the largest uses the top bit (see the module docs).
fn to_full_range(samples: &mut [u16]) {
    let largest = samples.iter().copied().max().unwrap_or(0);
    let shift = largest.leading_zeros();
    if largest > 0 && shift > 0 {
        for s in samples {
            *s <<= shift;
        }
    }
}

/// Walks a JPEG's markers (segments skipped by their length, entropy-coded data scanned for the
/// next marker) and succeeds at the end-of-image marker; the end of the data first is damage.
fn jpeg_reaches_its_end<R: BufRead>(reader: &mut R) -> Result<(), DecodeError> {
    let cut = || DecodeError::Damaged("the JPEG ends before its end-of-image marker (cut short)".into());
    let io_err = |e: io::Error| DecodeError::Io(e.to_string());
    loop {
        match next_marker(reader).map_err(io_err)? {
            None => return Err(cut()),
            Some(0xD9) => return Ok(()),
            // SOI and TEM stand alone; the rest carry a length.
            Some(0xD8 | 0x01) => {}
            Some(_) => {
                let mut len = [0u8; 2];
                if io::Read::read_exact(reader, &mut len).is_err() {
                    return Err(cut());
                }
                let body = u64::from(u16::from_be_bytes(len))
                    .checked_sub(2)
                    .ok_or_else(|| DecodeError::Invalid("a JPEG segment shorter than its own length field".into()))?;
                let skipped = io::copy(&mut io::Read::take(&mut *reader, body), &mut io::sink()).map_err(io_err)?;
                if skipped < body {
                    return Err(cut());
                }
            }
        }
    }
}

/// The code of the next marker (`FF xx`, not a stuffed `FF 00`, a restart `FF D0`…`FF D7` or a
/// fill byte), read past it; `None` at the end of the data.
fn next_marker<R: BufRead>(reader: &mut R) -> io::Result<Option<u8>> {
    loop {
        loop {
            let buf = reader.fill_buf()?;
            if buf.is_empty() {
                return Ok(None);
            }
            if let Some(i) = buf.iter().position(|&b| b == 0xFF) {
                reader.consume(i + 1);
                break;
            }
            let n = buf.len();
            reader.consume(n);
        }
        let code = loop {
            let buf = reader.fill_buf()?;
            let Some(&b) = buf.first() else { return Ok(None) };
            reader.consume(1);
            if b != 0xFF {
                break b;
            }
        };
        if !matches!(code, 0x00 | 0xD0..=0xD7) {
            return Ok(Some(code));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    #[test]
    fn the_marker_walk_skips_segments_and_stuffed_bytes() {
        // SOI, an APP1 holding a thumbnail's FF D9, a scan with FF 00 and a restart, EOI.
        let whole = [
            &[0xFF, 0xD8][..],
            &[0xFF, 0xE1, 0x00, 0x06, 0xFF, 0xD9, 0xAB, 0xCD],
            &[0xFF, 0xDA, 0x00, 0x02, 0x12, 0xFF, 0x00, 0x34, 0xFF, 0xD3, 0x56],
            &[0xFF, 0xFF, 0xD9, 0x00, 0x00],
        ]
        .concat();
        assert_eq!(jpeg_reaches_its_end(&mut Cursor::new(&whole)), Ok(()));
        for cut in 0..whole.len() - 2 {
            let e = jpeg_reaches_its_end(&mut Cursor::new(&whole[..cut]));
            assert!(matches!(e, Err(DecodeError::Damaged(_))), "{cut}: {e:?}");
        }
        let short = [0xFF, 0xD8, 0xFF, 0xE0, 0x00, 0x01, 0xFF, 0xD9];
        assert!(matches!(jpeg_reaches_its_end(&mut Cursor::new(&short)), Err(DecodeError::Invalid(_))));
    }

    #[test]
    fn sixteen_bit_samples_are_scaled_by_their_range() {
        let mut ten_bit = vec![0, 1, 512, 1023];
        to_full_range(&mut ten_bit);
        assert_eq!(ten_bit, [0, 64, 32768, 65472]);
        let mut full = vec![3, 65535];
        to_full_range(&mut full);
        assert_eq!(full, [3, 65535]);
        let mut black = vec![0, 0];
        to_full_range(&mut black);
        assert_eq!(black, [0, 0]);
    }
}
