//! The finder against rendered images with known truth: accuracy under blur, light gradient,
//! noise and JPEG; the judgments (several, clipped, size out of range); no mark where there is
//! none; typed errors; no panic on any input.
#![expect(clippy::cast_possible_truncation, reason = "test values are small and whole")]

use image::codecs::jpeg::JpegEncoder;
use proptest::prelude::*;
use vision_locate::render::{
    random_clutter, render, Clutter, Depth, Lighting, PlacedMark, Scene, Shape, SplitMix64, Texture,
};
use vision_locate::{
    locate, GrayImage, ImageError, LocateError, Located, MarkKind, MarkSpec, NotFoundReason, OwnedPixels, Pixels,
    Polarity, SpecError,
};

const W: usize = 320;
const H: usize = 240;

fn jpeg(px: &[u8], w: usize, h: usize, q: u8) -> Vec<u8> {
    let mut buf = Vec::new();
    JpegEncoder::new_with_quality(&mut buf, q).encode(px, w as u32, h as u32, image::ExtendedColorType::L8).unwrap();
    image::load_from_memory_with_format(&buf, image::ImageFormat::Jpeg).unwrap().into_luma8().into_raw()
}

fn run(scene: &Scene, spec: &MarkSpec, jpeg_q: Option<u8>) -> Located {
    let img = render(scene).unwrap();
    match img.into_pixels() {
        OwnedPixels::Gray8(px) => {
            let px = match jpeg_q {
                Some(q) => jpeg(&px, scene.width, scene.height, q),
                None => px,
            };
            locate(&GrayImage::new(scene.width, scene.height, Pixels::Gray8(&px)).unwrap(), spec).unwrap()
        }
        OwnedPixels::Gray16(px) => {
            locate(&GrayImage::new(scene.width, scene.height, Pixels::Gray16(&px)).unwrap(), spec).unwrap()
        }
    }
}

fn shape(kind: MarkKind, d: f64, angle: f64) -> Shape {
    match kind {
        MarkKind::Dot => Shape::Dot { diameter: d },
        MarkKind::Ring => Shape::Ring { diameter: d, line_width: 0.2 * d },
        MarkKind::Cross => Shape::Cross { length: d, bar_width: 0.2 * d, angle },
    }
}

fn levels(polarity: Polarity) -> (f64, f64) {
    match polarity {
        Polarity::DarkOnLight => (0.8, 0.1),
        Polarity::LightOnDark => (0.15, 0.9),
    }
}

#[expect(clippy::too_many_arguments, reason = "every knob of a test scene")]
fn scene_with(
    kind: MarkKind,
    polarity: Polarity,
    x: f64,
    y: f64,
    d: f64,
    angle: f64,
    blur: f64,
    noise: f64,
    gradient: f64,
    seed: u64,
) -> Scene {
    let (bg, ink) = levels(polarity);
    Scene {
        background: bg,
        marks: vec![PlacedMark { shape: shape(kind, d, angle), x, y, reflectance: ink }],
        blur_sigma: blur,
        noise_sigma: noise,
        lighting: Lighting { level: 0.95, gradient, angle: (seed % 628) as f64 / 100.0 },
        seed,
        ..Scene::blank(W, H, Depth::Eight)
    }
}

fn found(r: Located) -> vision_locate::Mark {
    match r {
        Located::Found(m) => m,
        Located::NotFound(why) => panic!("no mark: {why:?}"),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 160, ..ProptestConfig::default() })]

    /// Any kind, either polarity, blur up to 3 px, noise up to 3 grey levels, a light gradient
    /// up to 30 % and, half the time, JPEG quality 75: the centre within 0.05 px (the study
    /// measures the real spread; this bounds every single case) and the size within 3 %.
    #[test]
    fn finds_the_mark_within_bounds(
        kind in prop_oneof![Just(MarkKind::Dot), Just(MarkKind::Ring), Just(MarkKind::Cross)],
        polarity in prop_oneof![Just(Polarity::DarkOnLight), Just(Polarity::LightOnDark)],
        d in 30.0f64..90.0,
        fx in 0.0f64..1.0, fy in 0.0f64..1.0,
        angle in -0.78f64..0.78,
        blur in 0.0f64..3.0,
        noise in 0.0f64..3.0,
        gradient in 0.0f64..0.3,
        use_jpeg in any::<bool>(),
        seed in any::<u64>(),
    ) {
        let m = d / 2.0 + 8.0;
        let (x, y) = (m + fx * (W as f64 - 2.0 * m), m + fy * (H as f64 - 2.0 * m));
        let scene = scene_with(kind, polarity, x, y, d, angle, blur, noise, gradient, seed);
        let spec = MarkSpec::new(kind, d, 0.2, polarity).unwrap();
        let mark = found(run(&scene, &spec, use_jpeg.then_some(75)));
        let err = (mark.x - x).hypot(mark.y - y);
        prop_assert!(err < 0.05, "centre off by {err} px: {mark:?} vs ({x}, {y})");
        prop_assert!((mark.diameter - d).abs() < 0.03 * d, "size {} vs {d}", mark.diameter);
        if kind == MarkKind::Cross {
            let a = mark.angle.expect("a cross has an angle");
            let da = (a - angle + std::f64::consts::FRAC_PI_4).rem_euclid(std::f64::consts::FRAC_PI_2) - std::f64::consts::FRAC_PI_4;
            prop_assert!(da.abs() < 0.01, "angle {a} vs {angle}");
        } else {
            prop_assert!(mark.angle.is_none());
        }
        prop_assert!(mark.score > 0.8 && mark.score <= 1.0);
    }

    /// Random bytes of random sizes and any spec: an answer, never a panic.
    #[test]
    fn never_panics(
        w in 1usize..80, h in 1usize..80,
        bytes in proptest::collection::vec(any::<u8>(), 0..6400),
        d in prop_oneof![Just(f64::NAN), Just(-1.0), 0.0f64..200.0],
        tol in prop_oneof![Just(f64::NAN), -0.5f64..1.5],
        kind in prop_oneof![Just(MarkKind::Dot), Just(MarkKind::Ring), Just(MarkKind::Cross)],
        wide in any::<bool>(),
    ) {
        let spec = MarkSpec { kind, diameter_px: d, tolerance: tol, polarity: Polarity::DarkOnLight };
        if wide {
            let px: Vec<u16> = bytes.chunks(2).map(|c| u16::from(c[0]) << 8 | u16::from(*c.last().unwrap())).collect();
            if let Ok(img) = GrayImage::new(w, h, Pixels::Gray16(&px)) {
                let _ = locate(&img, &spec);
            }
        } else if let Ok(img) = GrayImage::new(w, h, Pixels::Gray8(&bytes[..bytes.len().min(w * h)])) {
            let _ = locate(&img, &spec);
        }
    }
}

/// Sharp, nearly noise-free marks that `examples/locate_stress.rs` found missed (400 × 400 px,
/// ring line and cross bar 0.2 × the size): rings whose line fell apart into an arc in the coarse
/// search's upper contrast level, and crosses along the pixel axes, whose fit could not settle
/// the blur below a pixel (a singular system, or a blur jumping on and off its bound).
#[test]
fn sharp_marks_the_stress_missed_are_found() {
    let cases = [
        (
            MarkKind::Ring,
            Polarity::DarkOnLight,
            286.6834232910234,
            54.76054302604002,
            48.844841176358,
            0.0,
            14166473869716118006,
            0.0,
        ),
        (
            MarkKind::Ring,
            Polarity::DarkOnLight,
            269.01457058429685,
            235.1127443678913,
            49.04056834824942,
            0.0,
            7483854707913251939,
            0.0,
        ),
        (
            MarkKind::Ring,
            Polarity::LightOnDark,
            307.40747953579273,
            108.71404405734538,
            33.94810681454,
            0.0,
            12917395730094274147,
            0.5,
        ),
        (
            MarkKind::Cross,
            Polarity::DarkOnLight,
            166.17919564185684,
            191.51665166826308,
            68.90889522868076,
            0.0003450923602773548,
            6739880452500824026,
            0.0,
        ),
        (
            MarkKind::Cross,
            Polarity::DarkOnLight,
            245.07508385832796,
            252.18208629059507,
            122.94890092347813,
            2.5856001927171413e-5,
            16866257477905049738,
            0.0,
        ),
        (
            MarkKind::Cross,
            Polarity::LightOnDark,
            208.96796374064067,
            330.2427159190217,
            55.05025928189086,
            -0.0016934827623441562,
            12269804755735283513,
            0.0,
        ),
        (
            MarkKind::Ring,
            Polarity::LightOnDark,
            269.58779562882006,
            257.5885340496342,
            88.18104483925802,
            0.0,
            13542541454447140766,
            0.0,
        ),
        // Sharp crosses at about 0°, which a damped last stage got stuck on (the blur sits at
        // its bound, where the model is not smooth): the last stage stays plain Gauss–Newton.
        (
            MarkKind::Cross,
            Polarity::DarkOnLight,
            236.79826601980486,
            177.98635431317848,
            72.83484965755275,
            1.1112192163986734e-5,
            18278448675365618784,
            0.0,
        ),
        (
            MarkKind::Cross,
            Polarity::DarkOnLight,
            94.77569238377959,
            342.28951293846615,
            93.34738073784143,
            0.0032152956405336885,
            11133492710960226775,
            0.0,
        ),
    ];
    for (kind, polarity, x, y, d, angle, seed, noise) in cases {
        let (bg, ink) = levels(polarity);
        let scene = Scene {
            background: bg,
            marks: vec![PlacedMark { shape: shape(kind, d, angle), x, y, reflectance: ink }],
            noise_sigma: noise,
            seed,
            ..Scene::blank(400, 400, Depth::Eight)
        };
        let spec = MarkSpec::new(kind, d, 0.2, polarity).unwrap();
        let mark = found(run(&scene, &spec, None));
        let err = (mark.x - x).hypot(mark.y - y);
        assert!(err < 0.02, "{kind:?} d {d}: centre off by {err} px: {mark:?} vs ({x}, {y})");
    }
}

#[test]
fn sixteen_bit_images_work_alike() {
    let mut scene =
        scene_with(MarkKind::Dot, Polarity::DarkOnLight, 150.37, 110.81, 50.0, 0.0, 1.5, 2.0 * 257.0, 0.2, 3);
    scene.depth = Depth::Sixteen;
    let spec = MarkSpec::new(MarkKind::Dot, 50.0, 0.2, Polarity::DarkOnLight).unwrap();
    let mark = found(run(&scene, &spec, None));
    assert!((mark.x - 150.37).abs() < 0.02 && (mark.y - 110.81).abs() < 0.02, "{mark:?}");
}

#[test]
fn two_marks_are_refused() {
    let mut scene = scene_with(MarkKind::Dot, Polarity::DarkOnLight, 90.0, 120.0, 40.0, 0.0, 1.0, 2.0, 0.0, 1);
    let second = PlacedMark { x: 230.0, ..scene.marks[0] };
    scene.marks.push(second);
    let spec = MarkSpec::new(MarkKind::Dot, 40.0, 0.2, Polarity::DarkOnLight).unwrap();
    assert_eq!(run(&scene, &spec, None), Located::NotFound(NotFoundReason::SeveralCandidates { count: 2 }));
}

#[test]
fn a_mark_cut_by_the_border_is_clipped() {
    for (x, y) in [(5.0, 120.0), (160.0, 236.0), (318.0, 40.0), (-3.0, 0.0)] {
        let scene = scene_with(MarkKind::Dot, Polarity::DarkOnLight, x, y, 60.0, 0.0, 1.0, 2.0, 0.1, 2);
        let spec = MarkSpec::new(MarkKind::Dot, 60.0, 0.2, Polarity::DarkOnLight).unwrap();
        assert_eq!(run(&scene, &spec, None), Located::NotFound(NotFoundReason::Clipped), "mark at {x},{y}");
    }
}

#[test]
fn a_mark_of_the_wrong_size_is_reported_as_such() {
    let scene = scene_with(MarkKind::Dot, Polarity::DarkOnLight, 160.0, 120.0, 60.0, 0.0, 1.0, 2.0, 0.0, 4);
    // Expecting 45 ± 20 % (36 … 54 px): the 60 px dot is seen but refused.
    let spec = MarkSpec::new(MarkKind::Dot, 45.0, 0.2, Polarity::DarkOnLight).unwrap();
    match run(&scene, &spec, None) {
        Located::NotFound(NotFoundReason::SizeOutOfRange { diameter, min, max }) => {
            assert!((diameter - 60.0).abs() < 0.5 && (min, max) == (36.0, 54.0), "{diameter} {min} {max}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn the_wrong_polarity_finds_nothing() {
    let scene = scene_with(MarkKind::Dot, Polarity::DarkOnLight, 160.0, 120.0, 50.0, 0.0, 1.0, 2.0, 0.0, 5);
    let spec = MarkSpec::new(MarkKind::Dot, 50.0, 0.2, Polarity::LightOnDark).unwrap();
    assert!(matches!(run(&scene, &spec, None), Located::NotFound(_)));
}

#[test]
fn the_mark_is_found_among_clutter() {
    let mut g = SplitMix64::new(11);
    for k in 0..10 {
        let (x, y) = (g.range(60.0, 260.0), g.range(60.0, 180.0));
        let mut scene = scene_with(MarkKind::Dot, Polarity::DarkOnLight, x, y, 40.0, 0.0, 1.0, 2.0, 0.2, k);
        scene.clutter = random_clutter(k, 8, W, H, (x, y, 40.0), 35.0);
        let spec = MarkSpec::new(MarkKind::Dot, 40.0, 0.2, Polarity::DarkOnLight).unwrap();
        let mark = found(run(&scene, &spec, Some(75)));
        assert!((mark.x - x).hypot(mark.y - y) < 0.05, "image {k}: {mark:?} vs {x},{y}");
    }
}

/// 200 mark-free images — blank, gradients, machined-surface textures, part edges, scratches
/// and specks: never a mark.
#[test]
fn no_mark_is_reported_where_there_is_none() {
    let mut g = SplitMix64::new(2027);
    let kinds = [MarkKind::Dot, MarkKind::Ring, MarkKind::Cross];
    let pols = [Polarity::DarkOnLight, Polarity::LightOnDark];
    for k in 0..200u64 {
        let mut scene = Scene {
            background: g.range(0.2, 0.9),
            blur_sigma: g.range(0.0, 3.0),
            noise_sigma: g.range(0.0, 4.0),
            lighting: Lighting { level: 0.95, gradient: g.range(-0.6, 0.6), angle: g.range(-3.0, 3.0) },
            seed: k,
            ..Scene::blank(W, H, Depth::Eight)
        };
        match k % 5 {
            0 => {}
            1 => {
                scene.texture = Some(Texture {
                    amplitude: g.range(0.02, 0.2),
                    period: g.range(2.0, 30.0),
                    angle: g.range(0.0, 3.0),
                    arc_radius: None,
                });
            }
            2 => {
                scene.texture = Some(Texture {
                    amplitude: g.range(0.02, 0.2),
                    period: g.range(2.0, 30.0),
                    angle: g.range(0.0, 3.0),
                    arc_radius: Some(g.range(100.0, 2000.0)),
                });
            }
            3 => {
                scene.clutter.push(Clutter::Edge {
                    x: g.range(0.0, W as f64),
                    y: g.range(0.0, H as f64),
                    angle: g.range(-3.0, 3.0),
                    reflectance: g.range(0.0, 1.0),
                });
                scene.clutter.push(Clutter::Edge {
                    x: g.range(0.0, W as f64),
                    y: g.range(0.0, H as f64),
                    angle: g.range(-3.0, 3.0),
                    reflectance: g.range(0.0, 1.0),
                });
            }
            _ => scene.clutter = random_clutter(k, 12, W, H, (-1e3, -1e3, 40.0), 0.0),
        }
        let img = render(&scene).unwrap();
        let view = img.view();
        // Each image is searched for a dot of 40 px and for one other kind and size, both
        // polarities: every kind, size and polarity meets every kind of background.
        let (kind, d) = (kinds[(k / 5) as usize % 3], [24.0, 40.0, 70.0][(k / 15) as usize % 3]);
        for (kind, d) in [(MarkKind::Dot, 40.0), (kind, d)] {
            for pol in pols {
                let spec = MarkSpec::new(kind, d, 0.25, pol).unwrap();
                let r = locate(&view, &spec).unwrap();
                assert!(
                    matches!(r, Located::NotFound(_)),
                    "image {k} ({:?}): {kind:?} {pol:?} {d} px → {r:?}",
                    scene.clutter.first()
                );
            }
        }
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let buf = [0u8; 12];
    assert_eq!(GrayImage::new(0, 3, Pixels::Gray8(&buf)), Err(ImageError::ZeroSize { width: 0, height: 3 }));
    assert_eq!(GrayImage::new(4, 4, Pixels::Gray8(&buf)), Err(ImageError::BufferLength { expected: 16, actual: 12 }));
    assert_eq!(
        GrayImage::new(usize::MAX, 2, Pixels::Gray8(&buf)),
        Err(ImageError::TooLarge { width: usize::MAX, height: 2 })
    );
    let img = GrayImage::new(4, 3, Pixels::Gray8(&buf)).unwrap();
    let spec = |d: f64, t: f64| MarkSpec {
        kind: MarkKind::Dot,
        diameter_px: d,
        tolerance: t,
        polarity: Polarity::DarkOnLight,
    };
    assert!(matches!(locate(&img, &spec(f64::NAN, 0.2)), Err(LocateError::Spec(SpecError::Diameter(_)))));
    assert_eq!(locate(&img, &spec(0.0, 0.2)), Err(LocateError::Spec(SpecError::Diameter(0.0))));
    assert_eq!(locate(&img, &spec(-5.0, 0.2)), Err(LocateError::Spec(SpecError::Diameter(-5.0))));
    assert_eq!(locate(&img, &spec(f64::INFINITY, 0.2)), Err(LocateError::Spec(SpecError::Diameter(f64::INFINITY))));
    assert_eq!(locate(&img, &spec(2.0, 0.2)), Err(LocateError::Spec(SpecError::DiameterTooSmall(2.0))));
    for t in [0.0, 1.0, -0.1, 1.5] {
        assert_eq!(locate(&img, &spec(20.0, t)), Err(LocateError::Spec(SpecError::Tolerance(t))));
    }
    assert!(matches!(locate(&img, &spec(20.0, f64::NAN)), Err(LocateError::Spec(SpecError::Tolerance(_)))));
    // A valid spec on a tiny image is a judgment, not an error.
    assert_eq!(locate(&img, &spec(20.0, 0.2)), Ok(Located::NotFound(NotFoundReason::NoCandidate)));
}

#[test]
fn the_cramer_rao_bound_agrees_with_its_closed_form() {
    // With everything but the centre known, a disc edge of contrast A and width σₑ over the
    // perimeter 2πR gives cx the Fisher information A²·πR/(2√π·σₑ)/σ², for a Gaussian edge
    // profile; the pixel's square makes the blurred edge's width σₑ = √(s² + 1/12) and its
    // profile nearly Gaussian. Unknown nuisance parameters (radius, blur, background and
    // contrast planes) can only raise the bound — the light planes’ slopes correlate with the
    // centre (1.3–1.5 × here) — and it scales as σ/|A| exactly.
    for (d, s, a, sigma) in
        [(100.0, 1.0, 150.0, 2.0), (40.0, 0.6, -80.0, 1.0), (200.0, 3.0, 100.0, 4.0), (60.0, 0.0, 170.0, 2.0)]
    {
        let (cx, cy) = vision_locate::dot_crb(d, s, 190.0, a, sigma).expect("regular");
        let width = (s * s + 1.0 / 12.0f64).sqrt();
        let closed =
            sigma / a.abs() * (2.0 * std::f64::consts::PI.sqrt() * width / (std::f64::consts::PI * d / 2.0)).sqrt();
        for v in [cx, cy] {
            assert!(v / closed > 1.0 && v / closed < 1.6, "d {d}: {v} vs {closed}");
        }
        let (half, _) = vision_locate::dot_crb(d, s, 190.0, 2.0 * a, sigma).expect("regular");
        assert!((half * 2.0 / cx - 1.0).abs() < 1e-9, "twice the contrast halves the bound");
    }
}
