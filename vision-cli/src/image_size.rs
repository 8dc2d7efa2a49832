//! The size of an image file, read from its header before anything is decoded, and the bounds
//! `mach-vision locate` holds it to.

use std::path::Path;

use vision_locate::MarkSpec;

use crate::Failure;

/// The most pixels of one image `locate` decodes: the camera driver's bound (100 megapixels).
pub(crate) const MAX_PIXELS: u64 = vision_driver_camera::MAX_PIXELS;

/// The width and height, pixels, that `path`'s header declares; nothing else of the file is
/// read.
///
/// # Errors
/// [`Failure::Input`] when the file cannot be opened or is no image this tool reads.
pub(crate) fn image_dimensions(path: &Path) -> Result<(u32, u32), Failure> {
    // A FIFO or a device is refused unread, never opened for a blocking read; the header's
    // metadata (a PNG's ICC profile) is held to the decoder's bound.
    let file = vision_driver_camera::file::open_regular(path)
        .map_err(|e| Failure::Input(format!("cannot read image {}: {e}", path.display())))?;
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(vision_driver_camera::decode::MAX_METADATA_BYTES);
    let mut reader = image::ImageReader::new(std::io::BufReader::new(file))
        .with_guessed_format()
        .map_err(|e| Failure::Input(format!("cannot read image {}: {e}", path.display())))?;
    reader.limits(limits);
    reader
        .into_dimensions()
        .map_err(|e| Failure::Input(format!("cannot decode image {}: {e} — use PNG, JPEG, PGM or BMP", path.display())))
}

/// Checks, from its header alone, that the image at `path` can be decoded and searched for
/// `spec` within the bounds: at most [`MAX_PIXELS`], and a search within the finder's memory
/// bound ([`vision_locate::check_size`]: [`vision_locate::MAX_SEARCH_BYTES`], which a small
/// diameter on a large image exceeds). Returns its width and height, pixels.
///
/// # Errors
/// [`Failure::Input`] naming the file, the bound and what to do.
pub(crate) fn check_image_size(path: &Path, spec: &MarkSpec) -> Result<(u32, u32), Failure> {
    let (w, h) = image_dimensions(path)?;
    let pixels = u64::from(w) * u64::from(h);
    if pixels > MAX_PIXELS {
        return Err(Failure::Input(format!(
            "image {} is {w} × {h} pixels ({} megapixels), over the {} megapixels an image may have — crop or \
             scale it around the mark",
            path.display(),
            pixels.div_ceil(1_000_000),
            MAX_PIXELS / 1_000_000
        )));
    }
    vision_locate::check_size(w as usize, h as usize, spec)
        .map_err(|e| Failure::Input(format!("image {}: {e}", path.display())))?;
    Ok((w, h))
}
