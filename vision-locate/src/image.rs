//! Grayscale images as borrowed slices (the finder's input) and owned buffers (the renderer's
//! output).

use std::fmt;

/// The samples of a [`GrayImage`], row-major, top row first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pixels<'a> {
    /// 8-bit samples, 0 = black, 255 = white.
    Gray8(&'a [u8]),
    /// 16-bit samples, 0 = black, 65535 = white.
    Gray16(&'a [u16]),
}

impl Pixels<'_> {
    fn len(&self) -> usize {
        match self {
            Pixels::Gray8(p) => p.len(),
            Pixels::Gray16(p) => p.len(),
        }
    }
}

/// A borrowed grayscale image whose buffer length matches its size (checked by [`GrayImage::new`]).
///
/// Pixel convention: (0, 0) is the centre of the top-left pixel, x grows to the right, y down;
/// pixel (i, j) covers the square [i − ½, i + ½] × [j − ½, j + ½].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GrayImage<'a> {
    width: usize,
    height: usize,
    pixels: Pixels<'a>,
}

/// Why a buffer is not an image.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ImageError {
    /// Width or height is zero.
    ZeroSize {
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
    },
    /// `width × height` overflows `usize`.
    TooLarge {
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
    },
    /// The buffer holds a different number of samples than `width × height`.
    BufferLength {
        /// `width × height`.
        expected: usize,
        /// Samples in the buffer.
        actual: usize,
    },
}

impl fmt::Display for ImageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ImageError::ZeroSize { width, height } => {
                write!(f, "image is {width} × {height} pixels: both sides must be at least 1 — check the frame source")
            }
            ImageError::TooLarge { width, height } => {
                write!(f, "image size {width} × {height} overflows the address space — check the frame header")
            }
            ImageError::BufferLength { expected, actual } => write!(
                f,
                "image buffer holds {actual} samples but width × height is {expected} — check the row stride and bit depth"
            ),
        }
    }
}

impl std::error::Error for ImageError {}

impl<'a> GrayImage<'a> {
    /// Wraps `pixels` as a `width × height` image (sizes in pixels), checking the buffer length.
    ///
    /// ```
    /// use vision_locate::{GrayImage, ImageError, Pixels};
    /// let buf = vec![0u8; 12];
    /// assert!(GrayImage::new(4, 3, Pixels::Gray8(&buf)).is_ok());
    /// assert_eq!(
    ///     GrayImage::new(5, 3, Pixels::Gray8(&buf)),
    ///     Err(ImageError::BufferLength { expected: 15, actual: 12 })
    /// );
    /// ```
    pub fn new(width: usize, height: usize, pixels: Pixels<'a>) -> Result<Self, ImageError> {
        if width == 0 || height == 0 {
            return Err(ImageError::ZeroSize { width, height });
        }
        let expected = width.checked_mul(height).ok_or(ImageError::TooLarge { width, height })?;
        if pixels.len() != expected {
            return Err(ImageError::BufferLength { expected, actual: pixels.len() });
        }
        Ok(GrayImage { width, height, pixels })
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The samples.
    pub fn pixels(&self) -> Pixels<'a> {
        self.pixels
    }

    /// The largest sample value of this depth (255 or 65535).
    pub fn full_scale(&self) -> f64 {
        match self.pixels {
            Pixels::Gray8(_) => 255.0,
            Pixels::Gray16(_) => 65535.0,
        }
    }
}

/// Owned samples of an [`OwnedImage`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum OwnedPixels {
    /// 8-bit samples.
    Gray8(Vec<u8>),
    /// 16-bit samples.
    Gray16(Vec<u16>),
}

/// An owned grayscale image (what [`crate::render`] produces). Same pixel convention as
/// [`GrayImage`]; the buffer length always equals `width × height`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OwnedImage {
    width: usize,
    height: usize,
    pixels: OwnedPixels,
}

impl OwnedImage {
    /// Takes ownership of `pixels` as a `width × height` image, checking the length like
    /// [`GrayImage::new`].
    pub fn new(width: usize, height: usize, pixels: OwnedPixels) -> Result<Self, ImageError> {
        let borrowed = match &pixels {
            OwnedPixels::Gray8(p) => Pixels::Gray8(p),
            OwnedPixels::Gray16(p) => Pixels::Gray16(p),
        };
        GrayImage::new(width, height, borrowed)?;
        Ok(OwnedImage { width, height, pixels })
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The samples.
    pub fn pixels(&self) -> &OwnedPixels {
        &self.pixels
    }

    /// Gives the buffer back.
    pub fn into_pixels(self) -> OwnedPixels {
        self.pixels
    }

    /// Borrows this image as the finder's input.
    pub fn view(&self) -> GrayImage<'_> {
        let pixels = match &self.pixels {
            OwnedPixels::Gray8(p) => Pixels::Gray8(p),
            OwnedPixels::Gray16(p) => Pixels::Gray16(p),
        };
        GrayImage { width: self.width, height: self.height, pixels }
    }
}
