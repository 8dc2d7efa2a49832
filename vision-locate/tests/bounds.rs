//! Issue 33: the finder's work, memory and time are bounded — a field of small dots is refused
//! as cluttered once it holds more than `MAX_BLOBS` mark-sized blobs, the search never takes
//! more memory than `search_bytes` says (and refuses, unallocated, above `MAX_SEARCH_BYTES`),
//! and a deadline cuts it off.
#![expect(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    clippy::float_cmp,
    reason = "test values are small and whole; tests compare exact values"
)]

use std::time::{Duration, Instant};

use vision_locate::render::{render, Depth, PlacedMark, Scene, Shape};
use vision_locate::{
    check_size, locate, locate_within, search_bytes, Budget, GrayImage, LocateError, Located, MarkKind, MarkSpec,
    NotFoundReason, OwnedImage, Pixels, Polarity, MAX_BLOBS, MAX_SEARCH_BYTES,
};
use vision_testalloc::{peak_during, PeakAlloc};

#[global_allocator]
static GLOBAL: PeakAlloc = PeakAlloc;

fn dot(d: f64) -> MarkSpec {
    MarkSpec::new(MarkKind::Dot, d, 0.25, Polarity::DarkOnLight).expect("spec")
}

/// A `size` × `size` frame tiled with dark dots of `d` px every `pitch` px, and how many.
fn field(size: usize, d: f64, pitch: f64) -> (OwnedImage, usize) {
    let scene = Scene::dot_field(size, d, pitch);
    let count = scene.marks.len();
    (render(&scene).expect("scene"), count)
}

/// One dark dot of `d` px at (`x`, `y`) in a `w` × `h` frame.
fn one_dot(w: usize, h: usize, d: f64, x: f64, y: f64) -> OwnedImage {
    let scene = Scene {
        marks: vec![PlacedMark { shape: Shape::Dot { diameter: d }, x, y, reflectance: 0.1 }],
        blur_sigma: 1.0,
        noise_sigma: 1.5,
        seed: 7,
        ..Scene::blank(w, h, Depth::Eight)
    };
    render(&scene).expect("scene")
}

#[test]
fn a_field_of_more_mark_sized_blobs_than_the_bound_is_cut_off_as_cluttered() {
    // Issue 33: a 9 MP field of 6 px dots took 46 s (120 s on the reporter's machine) before
    // answering "12 marks in view". Beyond MAX_BLOBS kept blobs the search now stops.
    let (image, dots) = field(1300, 6.0, 12.0);
    assert!(dots > MAX_BLOBS, "{dots} dots");
    let (answer, _) = peak_during(|| locate(&image.view(), &dot(6.0)));
    assert_eq!(answer, Ok(Located::NotFound(NotFoundReason::Cluttered { limit: MAX_BLOBS })));
    assert_eq!(
        NotFoundReason::Cluttered { limit: MAX_BLOBS }.to_string(),
        "the search was cut off: more than 10000 mark-sized blobs in view — check the diameter setting, or narrow \
         the search to the mark"
    );
    // Under the bound the search runs to its end, and refuses to pick one of them.
    let (image, dots) = field(600, 6.0, 12.0);
    assert!(dots < MAX_BLOBS);
    let (answer, _) = peak_during(|| locate(&image.view(), &dot(6.0)));
    assert_eq!(answer, Ok(Located::NotFound(NotFoundReason::SeveralCandidates { count: 12 })));
}

#[test]
fn a_deadline_that_has_passed_cuts_the_search_off() {
    let image = one_dot(320, 240, 40.0, 161.3, 118.7);
    let spec = dot(40.0);
    let (passed, _) = peak_during(|| locate_within(&image.view(), &spec, &Budget::until(Instant::now())));
    assert_eq!(passed, Err(LocateError::Deadline));
    assert_eq!(
        LocateError::Deadline.to_string(),
        "the search was cut off at its deadline before it finished; nothing is known of the mark"
    );
    // A deadline that leaves time changes nothing.
    let (later, _) =
        peak_during(|| locate_within(&image.view(), &spec, &Budget::until(Instant::now() + Duration::from_secs(3600))));
    let (unbounded, _) = peak_during(|| locate(&image.view(), &spec));
    assert!(matches!(later, Ok(Located::Found(_))), "{later:?}");
    assert_eq!(later, unbounded);
}

#[test]
fn the_search_takes_no_more_memory_than_its_bound() {
    // (side, diameter): blocks of 1, 1, 2, 5 and 13 px; the last is the cluttered field.
    let cases: Vec<(OwnedImage, f64)> = vec![
        (one_dot(1600, 1200, 6.0, 800.3, 600.6), 6.0),
        (one_dot(1000, 1000, 4.0, 500.0, 500.0), 4.0),
        (one_dot(1200, 900, 12.0, 600.2, 450.1), 12.0),
        (one_dot(1200, 900, 40.0, 600.2, 450.1), 40.0),
        (one_dot(2000, 2000, 100.0, 1000.2, 1000.1), 100.0),
        (field(1300, 6.0, 12.0).0, 6.0),
    ];
    for (image, d) in &cases {
        let spec = dot(*d);
        let (w, h) = (image.width(), image.height());
        let bound = search_bytes(w, h, &spec);
        let (answer, peak) = peak_during(|| locate(&image.view(), &spec));
        assert!(answer.is_ok(), "{answer:?}");
        assert!(peak as u64 <= bound, "{w}×{h} at {d} px: peak {peak} over the bound {bound}");
        // The bound is the buffers' own size, not a guess far above: 16 bytes a block.
        let f = ((0.75 * d / 6.0).round() as usize).max(1);
        let blocks = (w / f) * (h / f);
        assert!(peak >= 16 * blocks, "{w}×{h} at {d} px: peak {peak} below the {blocks} blocks' 16 bytes");
    }
}

#[test]
fn an_image_too_large_to_search_is_refused_before_anything_is_allocated() {
    // Issue 33: 22 000² at --diameter 4 allocated 8 GB. 67 MP at blocks of 1 px needs more than
    // 1 GiB; the finder refuses it without allocating, and says which diameter would fit.
    let (w, h) = (8200, 8200);
    let pixels = vec![255u8; w * h];
    let image = GrayImage::new(w, h, Pixels::Gray8(&pixels)).expect("image");
    let (answer, peak) = peak_during(|| locate(&image, &dot(4.0)));
    let Err(LocateError::TooLarge { width, height, factor, needed, limit, diameter_within }) = answer else {
        panic!("{answer:?}")
    };
    assert_eq!((width, height, factor, limit), (w, h, 1, MAX_SEARCH_BYTES));
    assert!(needed > MAX_SEARCH_BYTES && needed == search_bytes(w, h, &dot(4.0)));
    assert!(peak < 4096, "{peak} bytes allocated");
    // The suggestion is the smallest diameter that fits: blocks of 2 px.
    assert_eq!(diameter_within, 12.0);
    assert_eq!(check_size(w, h, &dot(12.0)), Ok(()));
    assert!(matches!(check_size(w, h, &dot(11.0)), Err(LocateError::TooLarge { .. })));
    assert_eq!(
        answer.expect_err("too large").to_string(),
        format!(
            "searching a 8200 × 8200 image at blocks of 1 px needs {} MiB, over the finder's 1024 MiB limit — crop the \
             image around the mark, or give a mark diameter of at least 12 px",
            needed.div_ceil(1 << 20)
        )
    );
}
