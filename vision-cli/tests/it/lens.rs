//! What a distorting lens costs the cut, and the gate it must pass. Random worlds (as
//! `acceptance.rs`'s, σ = 0.1 px) with and without a lens, with their own camera orientations
//! and with the camera at exactly 45° and mirrored, are calibrated by the sheet walk (example 1,
//! with its lift) and aligned by examples 4 and 5 at the calibration height and 4 % farther.
//! Each fit's true cut error is compared with the least-squares floor ([`floors`]) and with
//! the 99 % bound M282 predicts; without noise the cut must be exact.
//!
//! The gate, all lenses, 40 worlds per case:
//! `cargo test --release -p vision-cli --test it lens -- --ignored --nocapture`
//! (`a_distorting_lens_cuts_at_the_floor_over_many_worlds`). The quick form
//! (`a_distorting_lens_is_measured`) runs always on a few worlds and gates only the lenses in
//! its [`Limits`].
#![expect(clippy::float_cmp, reason = "the height and the lenses are exact constants, compared as such")]

use std::ops::Range;

use vision_core::ParamValue;
use vision_driver_sim::World;
use vision_host::Record;

use crate::acceptance::{grid, last_fit, p95, random_world, sheet_report, Rig, EX1, EX4, EX5};

/// The lenses, `[k1, k2, p1, p2, k3]` (OpenCV's convention, as the world's `camera.distortion`);
/// `None` is a perfect lens.
const LENSES: [(&str, Option<[f64; 5]>); 4] = [
    ("none", None),
    ("k1 −0.10", Some(K1_ONLY)),
    ("k1 +0.08, k2 −0.02", Some([0.08, -0.02, 0.0, 0.0, 0.0])),
    ("k1 −0.10, p1/p2 0.002/−0.001", Some([-0.10, 0.0, 0.002, -0.001, 0.0])),
];

/// The lens whose estimated k1 is checked.
const K1_ONLY: [f64; 5] = [-0.10, 0.0, 0.0, 0.0, 0.0];

/// The part's working distance over the calibration's.
const HEIGHTS: [f64; 2] = [1.0, 1.04];

/// Examples 4 and 5: the fixture each aligns, the program, the part's size (inches).
const EXAMPLES: [(&str, &str, (f64, f64)); 2] =
    [("rectangle part", EX4, (6.0, 4.0)), ("similarity part", EX5, (8.0, 6.0))];

/// How the camera is turned: as the random world drew it (every orientation, ±3° off the 90°
/// multiple), or exactly 45° and mirrored (the farthest from any axis swap).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Camera {
    Drawn,
    Diagonal,
}

impl Camera {
    fn name(self) -> &'static str {
        match self {
            Camera::Drawn => "random",
            Camera::Diagonal => "45° mirrored",
        }
    }
}

/// World `case` at σ = `sigma` px with `lens` and the camera turned by `camera`; its
/// `units_per_pixel` holds at its working distance, the calibration height.
fn world(case: u64, sigma: f64, lens: Option<[f64; 5]>, camera: Camera) -> World {
    let mut w = random_world(case, sigma, 1.0);
    w.camera.distortion = lens;
    w.camera.reference_working_distance = Some(w.camera.working_distance);
    if camera == Camera::Diagonal {
        w.camera.rotation_deg = 45.0;
        w.camera.mirror = true;
    }
    w
}

/// A world calibrated by the sheet walk: the parameters it wrote, the camera tool's offset it
/// left in the tool table (world unit, the world's sign convention), and the walk's records.
struct Walk {
    world: World,
    params: Vec<(&'static str, ParamValue)>,
    camera_offset: [f64; 2],
    records: Vec<Record>,
}

/// Example 1 on `world`; `None` when it is refused.
fn walk(world: World) -> Option<Walk> {
    let mut rig = Rig::new(world.clone(), false);
    let records = rig.run_to_refusal(EX1);
    if records.iter().any(|r| r.result.is_err()) {
        return None;
    }
    let interp = rig.machine.interpreter();
    let sign = world.machine.controller().tool_table_sign();
    let table = interp.tool_offset(world.machine.camera_tool).expect("camera tool").xy();
    let params = rig.handler.session().module().params().config_values();
    Some(Walk { world, params, camera_offset: [table.x / sign, table.y / sign], records })
}

/// `walk`'s world with only `present` on the table and the camera at `height` × the
/// calibration's working distance, calibrated as the walk left it.
fn walked_rig(walk: &Walk, height: f64, present: &str) -> Rig {
    let mut world = walk.world.clone();
    world.fixtures.iter_mut().for_each(|f| f.present = f.name == present);
    world.camera.working_distance *= height;
    world.machine.camera_table_offset = Some(walk.camera_offset);
    let mut rig = Rig::new(world, false);
    let module = rig.handler.session_mut().module_mut();
    for (name, value) in &walk.params {
        module.set_param(name, value.clone()).expect("calibration");
    }
    rig
}

/// The k1 the sheet walk estimated, read from the walk's M283 report (`records` are the
/// walk's); `None` when the walk could not measure it.
fn estimated_k1(records: &[Record]) -> Option<f64> {
    let lens = sheet_report(records).lens;
    lens.measured[0].then_some(lens.k1)
}

/// One alignment: the true cut error over the part grid and M282's predicted 99 % bound, inches.
#[derive(Debug, Clone, Copy)]
struct Fit {
    cut: f64,
    bound: f64,
}

/// Runs example `example` (an index into [`EXAMPLES`]) on `rig`; `None` when it is refused.
fn align(rig: &mut Rig, example: usize) -> Option<Fit> {
    let (fixture, program, (x, y)) = EXAMPLES[example];
    let records = rig.run_to_refusal(program);
    let fit = last_fit(&records).ok()?;
    Some(Fit { cut: rig.max_cut_error(&records, fixture, &grid(x, y)), bound: fit.predicted.bound99 })
}

/// The median of `v`.
fn median(v: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = v.collect();
    v.sort_by(f64::total_cmp);
    v[(v.len() - 1) / 2]
}

/// The least-squares floor of one camera orientation and example, inches.
#[derive(Debug, Clone, Copy)]
struct Floor {
    p95: f64,
    median: f64,
}

/// The floor per camera orientation and example: the p95 (and median) of the cut errors of the
/// same worlds and marks with no lens and a perfect calibration (`Sim::calibrated_params`, the
/// true camera offset) at the calibration height. No calibration error, no lens, no height
/// change: what least squares reaches with the camera's noise alone.
fn floors(worlds: Range<u64>, camera: Camera) -> [Floor; 2] {
    [0, 1].map(|example| {
        let cuts: Vec<f64> = worlds
            .clone()
            .map(|case| {
                let mut w = world(case, 0.1, None, camera);
                w.machine.camera_table_offset = None;
                w.fixtures.iter_mut().for_each(|f| f.present = f.name == EXAMPLES[example].0);
                align(&mut Rig::new(w, true), example).expect("a perfect calibration aligns").cut
            })
            .collect();
        Floor { p95: p95(cuts.iter().copied()), median: median(cuts.iter().copied()) }
    })
}

/// The fits of one example in one case, and how many walks or fits were refused.
#[derive(Debug, Default, Clone)]
struct Fits {
    fits: Vec<Fit>,
    refused: usize,
}

/// One case: a lens, a camera orientation, a part height; the fits per example; the k1 each
/// world's walk estimated.
#[derive(Debug, Clone)]
struct Case {
    lens: usize,
    camera: Camera,
    height: f64,
    examples: [Fits; 2],
    k1: Vec<Option<f64>>,
}

/// Every lens × camera orientation × height over `worlds` at σ = 0.1 px: each world walked at
/// the calibration height, then examples 4 and 5 each in a fresh rig from that calibration;
/// with the floors per camera orientation.
fn lens_cases(worlds: Range<u64>) -> (Vec<(Camera, [Floor; 2])>, Vec<Case>) {
    let mut cases = Vec::new();
    let mut all_floors = Vec::new();
    for camera in [Camera::Drawn, Camera::Diagonal] {
        all_floors.push((camera, floors(worlds.clone(), camera)));
        for (lens, (_, coefficients)) in LENSES.iter().enumerate() {
            let mut here: Vec<Case> = HEIGHTS
                .iter()
                .map(|&height| Case { lens, camera, height, examples: Default::default(), k1: Vec::new() })
                .collect();
            for case in worlds.clone() {
                let walked = walk(world(case, 0.1, *coefficients, camera));
                for c in &mut here {
                    c.k1.push(walked.as_ref().and_then(|w| estimated_k1(&w.records)));
                    for (example, fits) in c.examples.iter_mut().enumerate() {
                        let fit = walked
                            .as_ref()
                            .and_then(|w| align(&mut walked_rig(w, c.height, EXAMPLES[example].0), example));
                        match fit {
                            Some(f) => fits.fits.push(f),
                            None => fits.refused += 1,
                        }
                    }
                }
            }
            cases.extend(here);
        }
    }
    (all_floors, cases)
}

/// What one case's example measured against its floor.
#[derive(Debug, Clone, Copy)]
struct Figures {
    p95_ratio: f64,
    median_ratio: f64,
    coverage: f64,
}

/// `fits` (at least one) against `floor`.
fn figures(fits: &Fits, floor: Floor) -> Figures {
    let cuts = || fits.fits.iter().map(|f| f.cut);
    let covered = fits.fits.iter().filter(|f| f.cut <= f.bound).count();
    Figures {
        p95_ratio: p95(cuts()) / floor.p95,
        median_ratio: median(cuts()) / floor.median,
        coverage: covered as f64 / fits.fits.len() as f64,
    }
}

/// Without noise: per lens, camera orientation and part height, the worst cut error of
/// examples 4 and 5 over `worlds` walked at the calibration height (inches), and the refusals.
fn exact_cases(worlds: Range<u64>) -> Vec<(usize, Camera, f64, f64, usize)> {
    let mut out = Vec::new();
    for camera in [Camera::Drawn, Camera::Diagonal] {
        for (lens, (_, coefficients)) in LENSES.iter().enumerate() {
            let walks: Vec<Option<Walk>> =
                worlds.clone().map(|case| walk(world(case, 0.0, *coefficients, camera))).collect();
            for height in HEIGHTS {
                let (mut worst, mut refused) = (0.0f64, 0);
                for (walked, example) in walks.iter().flat_map(|w| [(w, 0), (w, 1)]) {
                    let fit =
                        walked.as_ref().and_then(|w| align(&mut walked_rig(w, height, EXAMPLES[example].0), example));
                    match fit {
                        Some(f) => worst = worst.max(f.cut),
                        None => refused += 1,
                    }
                }
                out.push((lens, camera, height, worst, refused));
            }
        }
    }
    out
}

/// What a form gates: the lenses (names in [`LENSES`]) held to the limits, the largest p95 over
/// the floor, the smallest share of fits inside the predicted 99 % bound, the largest cut
/// error without noise (inches), and whether the k1 estimated for [`K1_ONLY`] must be within
/// 10 % of the truth in every walk.
struct Limits {
    lenses: Vec<&'static str>,
    p95_ratio: f64,
    coverage: f64,
    exact_in: f64,
    k1: bool,
}

/// Measures `worlds` (and `exact_worlds` without noise), prints the table, and fails on any
/// gated lens outside `limits` or any refusal.
fn lens_gate(worlds: Range<u64>, exact_worlds: Range<u64>, limits: &Limits) {
    let gated = |lens: usize| limits.lenses.contains(&LENSES[lens].0);
    let mut failures = Vec::new();
    let (floors, cases) = lens_cases(worlds.clone());
    for (camera, [f4, f5]) in &floors {
        println!(
            "floor, camera {}: p95 {:.6} / {:.6} in, median {:.6} / {:.6} in (examples 4 / 5)",
            camera.name(),
            f4.p95,
            f5.p95,
            f4.median,
            f5.median
        );
    }
    println!(
        "| lens | camera | height | p95 / floor (ex. 4, 5) | median / floor (ex. 4, 5) | covered (ex. 4, 5) | fits |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for c in &cases {
        let what = format!("{} {} ×{}", LENSES[c.lens].0, c.camera.name(), c.height);
        if c.examples.iter().any(|f| f.fits.is_empty()) {
            println!("| {} | {} | ×{:.2} | every walk or fit refused |", LENSES[c.lens].0, c.camera.name(), c.height);
            failures.push(format!("{what}: every walk or fit refused"));
            continue;
        }
        let floor = floors.iter().find(|(camera, _)| *camera == c.camera).expect("floor").1;
        let [a, b] = [0, 1].map(|e| figures(&c.examples[e], floor[e]));
        let fits = c.examples.iter().map(|f| f.fits.len()).sum::<usize>();
        let refused = c.examples.iter().map(|f| f.refused).sum::<usize>();
        println!(
            "| {} | {} | ×{:.2} | {:.2}, {:.2} | {:.2}, {:.2} | {:.1} %, {:.1} % | {fits}{} |",
            LENSES[c.lens].0,
            c.camera.name(),
            c.height,
            a.p95_ratio,
            b.p95_ratio,
            a.median_ratio,
            b.median_ratio,
            a.coverage * 100.0,
            b.coverage * 100.0,
            if refused > 0 { format!(" ({refused} refused)") } else { String::new() }
        );
        if refused > 0 {
            failures.push(format!("{what}: {refused} refused"));
        }
        for (example, f) in [(4, a), (5, b)] {
            if gated(c.lens) && (f.p95_ratio > limits.p95_ratio || f.coverage < limits.coverage) {
                failures.push(format!("{what} example {example}: {f:?}"));
            }
        }
    }
    // The walks are shared by the heights: the estimates of the calibration height's cases.
    for c in cases.iter().filter(|c| LENSES[c.lens].1 == Some(K1_ONLY) && c.height == 1.0) {
        let estimated: Vec<f64> = c.k1.iter().flatten().copied().collect();
        let within = estimated.iter().filter(|k| (*k - K1_ONLY[0]).abs() <= 0.1 * K1_ONLY[0].abs()).count();
        let what = format!("estimated k1, lens {}, camera {}", LENSES[c.lens].0, c.camera.name());
        println!("{what}: estimated in {} of {} walks, within 10 % in {within}", estimated.len(), c.k1.len());
        if limits.k1 && within < c.k1.len() {
            failures.push(format!("{what}: within 10 % in {within} of {}", c.k1.len()));
        }
    }
    for (lens, camera, height, worst, refused) in exact_cases(exact_worlds.clone()) {
        let what = format!("σ = 0, lens {}, camera {}, ×{height:.2}", LENSES[lens].0, camera.name());
        let refusals = if refused > 0 { format!(" ({refused} refused)") } else { String::new() };
        println!("{what}, {} worlds: worst cut {worst:.2e} in{refusals}", exact_worlds.end - exact_worlds.start);
        if refused > 0 || (gated(lens) && worst > limits.exact_in) {
            failures.push(format!("{what}: worst {worst:e} in{refusals}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The quick form, always run: 16 worlds (16 fits per case and example, so the p95 is the
/// largest), 4 without noise, every lens gated with room for the p95 of 16.
#[test]
fn a_distorting_lens_is_measured() {
    let limits = Limits {
        lenses: LENSES.map(|(name, _)| name).to_vec(),
        p95_ratio: 1.5,
        coverage: 0.9,
        exact_in: 1e-6,
        k1: true,
    };
    lens_gate(7000..7016, 7000..7004, &limits);
}

/// The gate: 40 worlds per case (40 fits per case and example), 8 without noise; every lens at
/// p95 ≤ 1.2 × the floor, covered ≥ 98 %, exact to 1e-6 in without noise, k1 estimated.
#[test]
#[ignore = "the gate the lens model must pass; run it in a release build"]
fn a_distorting_lens_cuts_at_the_floor_over_many_worlds() {
    let limits = Limits {
        lenses: LENSES.map(|(name, _)| name).to_vec(),
        p95_ratio: 1.2,
        coverage: 0.98,
        exact_in: 1e-6,
        k1: true,
    };
    lens_gate(7100..7140, 7100..7108, &limits);
}
