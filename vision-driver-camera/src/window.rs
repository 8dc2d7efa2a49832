//! The search window (`VisionCameraSearchRadius`): only a disc about the image centre is
//! searched, so marks that neighbour the one M281 centred do not make the view ambiguous.

use crate::frame::Frame;

/// The part of `frame` to search when only pixels within `radius_pct` percent of half the
/// shorter side of the centre count: the disc's bounding box, pixels outside the disc set to
/// the median of a 3-pixel band just inside its edge (the ground around the window, so the
/// window's own edge shows as little contrast as the light allows), and the box's top-left
/// pixel in `frame`. `None` at 100 % (the whole frame).
#[must_use]
pub(crate) fn window(frame: &Frame, radius_pct: f64) -> Option<(Frame, u32, u32)> {
    if !(radius_pct < 100.0) {
        return None;
    }
    let (w, h) = (f64::from(frame.width()), f64::from(frame.height()));
    let r = radius_pct.max(0.0) / 100.0 * w.min(h) / 2.0;
    let (cx, cy) = (w / 2.0, h / 2.0);
    // Pixel i covers [i, i + 1) in native (corner) coordinates.
    #[expect(clippy::cast_possible_truncation, clippy::cast_sign_loss, reason = "clamped to the frame")]
    let span = |c: f64, side: f64| ((c - r).floor().max(0.0) as u32, (c + r).ceil().min(side) as u32);
    let (x0, x1) = span(cx, w);
    let (y0, y1) = span(cy, h);
    if x1 <= x0 || y1 <= y0 {
        return None;
    }
    let stride = frame.width() as usize;
    let inside = |x: u32, y: u32| (f64::from(x) + 0.5 - cx).hypot(f64::from(y) + 0.5 - cy);
    let mut band = [0u64; 256];
    for y in y0..y1 {
        for x in x0..x1 {
            let d = inside(x, y);
            if d <= r && d > r - 3.0 {
                band[frame.pixels()[y as usize * stride + x as usize] as usize] += 1;
            }
        }
    }
    let total: u64 = band.iter().sum();
    let mut seen = 0;
    let fill = band
        .iter()
        .position(|&n| {
            seen += n;
            seen * 2 >= total
        })
        .and_then(|v| u8::try_from(v).ok())
        .unwrap_or(128);
    let mut pixels = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
    for y in y0..y1 {
        for x in x0..x1 {
            pixels.push(if inside(x, y) <= r { frame.pixels()[y as usize * stride + x as usize] } else { fill });
        }
    }
    Frame::new(x1 - x0, y1 - y0, pixels).map(|f| (f, x0, y0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_window_keeps_the_disc_and_fills_the_rest_with_its_edge() {
        // 20×10: left half 100, right half 200; a 50 % radius is 2.5 px about (10, 5).
        let pixels = (0..200).map(|i| if i % 20 < 10 { 100 } else { 200 }).collect();
        let frame = Frame::new(20, 10, pixels).expect("frame");
        assert!(window(&frame, 100.0).is_none());
        let (crop, x0, y0) = window(&frame, 50.0).expect("window");
        assert_eq!((crop.width(), crop.height(), x0, y0), (6, 6, 7, 2));
        // The centre pixels are kept; the box corners are outside the disc and filled.
        assert_eq!(crop.pixels()[2 * 6 + 2], 100);
        assert_eq!(crop.pixels()[2 * 6 + 3], 200);
        let corner = crop.pixels()[0];
        assert!(corner == 100 || corner == 200, "the band's median, {corner}");
        let (crop, ..) = window(&frame, 5.0).expect("a tiny window still has a pixel");
        assert!(crop.width() >= 1 && crop.height() >= 1);
    }
}
