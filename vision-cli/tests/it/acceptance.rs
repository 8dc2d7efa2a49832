//! End-to-end acceptance (issue 5): the manual's programs on the built-in world, and on random
//! worlds (every camera orientation, camera rotation up to ±3° off the 90° multiple, part
//! rotation ±5°, shift ±0.5 in, scale 0.995–1.005, σ = 0.1 px at 0.002 in/px), calibration
//! and cut errors against the truth, in inches and in millimetres. It lives here, not in the
//! simulator, because it needs the Vision M-code handler: the simulator stays below that layer.
#![expect(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    clippy::float_cmp,
    reason = "test values are small and whole; tests compare exact values"
)]

use vision_core::{CalReport, Params, Timestamp, VisionModule};
use vision_driver_sim::{Fixture, Sim, SimMachine, World};
use vision_gcode::Event;
use vision_host::fixed_clock;
use vision_host::{ProgramHandler, Record, Session};
use vision_math::{LengthUnit, Point2, Vector2};
use vision_mcode::Outcome;

pub(crate) const EX1: &str = include_str!("../../../examples/programs/01-calibrate-sheet.nc");
const EX2: &str = include_str!("../../../examples/programs/02-verify-calibration.nc");
const EX3: &str = include_str!("../../../examples/programs/03-quick-diameter-cal.nc");
pub(crate) const EX4: &str = include_str!("../../../examples/programs/04-rectangle-fit.nc");
pub(crate) const EX5: &str = include_str!("../../../examples/programs/05-similarity-fit.nc");
const EX6: &str = include_str!("../../../examples/programs/06-pound-variables.nc");
const EX7: &str = include_str!("../../../examples/programs/07-switch-jobs.nc");

/// A world, its machine, and the Vision session as the M-code handler (the path of
/// `mach-vision run` and of every bridge).
pub(crate) struct Rig {
    pub(crate) sim: Sim,
    pub(crate) machine: SimMachine,
    pub(crate) handler: ProgramHandler,
}

impl Rig {
    pub(crate) fn new(world: World, calibrated: bool) -> Rig {
        let sim = Sim::new(world).expect("valid world");
        let clock = fixed_clock(Timestamp::from_unix(1_800_000_000, 0));
        let machine = SimMachine::new(&sim).expect("machine");
        let mut params = Params::default();
        params.set("VisionEnabled", true).expect("set");
        params.set("VisionDriver", "Sim").expect("set");
        params.set("VisionCameraToolNumber", i64::from(sim.world().machine.camera_tool)).expect("set");
        if calibrated {
            params = sim.calibrated_params(&params).expect("calibrated");
        }
        let module = VisionModule::new(params).with_driver(Box::new(sim.camera()));
        let controller = sim.world().machine.controller();
        Rig { sim, machine, handler: ProgramHandler::new(Session::new(module), controller, clock) }
    }

    /// Brings the head back to the world's start Z (the calibration height) in machine
    /// coordinates. The camera follows Z, and examples 4 and 5 end their demo cut at Z0.25 with
    /// the cutter: each program here starts where an operator's next job would look from.
    fn back_to_start_height(&mut self) {
        let z = self.sim.world().machine.start[2];
        let mut ignore = |_: &Event| {};
        let line = format!("G20 G90 G53 G0 Z{z}\n");
        self.machine.run_program(&line, None, &mut ignore).expect("G53 Z move");
    }

    /// Runs `program` from the start height; returns the Vision records it produced.
    pub(crate) fn run(&mut self, program: &str) -> Vec<Record> {
        self.back_to_start_height();
        let mut ignore = |_: &Event| {};
        if let Err(e) = self.machine.run_program(program, Some(&mut self.handler), &mut ignore) {
            panic!("program failed: {e}\n{program}");
        }
        self.handler.take_records()
    }

    /// Runs `program` from the start height up to its end or its first refusal; returns the
    /// Vision records.
    pub(crate) fn run_to_refusal(&mut self, program: &str) -> Vec<Record> {
        self.back_to_start_height();
        let mut ignore = |_: &Event| {};
        let _ = self.machine.run_program(program, Some(&mut self.handler), &mut ignore);
        self.handler.take_records()
    }

    fn calibration_error(&self) -> vision_driver_sim::CalibrationError {
        let interp = self.machine.interpreter();
        let unit = interp.units();
        let camera = self.sim.world().machine.camera_tool;
        let offset = interp.tool_offset(camera).expect("camera tool").xy().coords;
        self.sim.calibration_error(self.handler.session().module().params(), offset, unit)
    }

    /// The worst cut error over `grid` (world unit) with the alignment the last M282 emitted.
    pub(crate) fn max_cut_error(&self, records: &[Record], fixture: &str, grid: &[Point2<f64>]) -> f64 {
        let setup = records.iter().rev().find_map(Record::applied_gcode).expect("an M282 ran").to_vec();
        grid.iter().map(|p| self.machine.cut_error(&setup, fixture, *p).expect("cut")).fold(0.0, f64::max)
    }
}

pub(crate) fn sheet_report(records: &[Record]) -> vision_core::SheetReport {
    records
        .iter()
        .find_map(|r| match &r.result {
            Ok(Outcome::Calibrate(reply)) => match &reply.report {
                CalReport::Sheet(s) => Some(s.clone()),
                CalReport::Quick(_) => None,
            },
            _ => None,
        })
        .expect("M283 C ran")
}

pub(crate) fn grid(x: f64, y: f64) -> Vec<Point2<f64>> {
    (0..=6).flat_map(|i| (0..=4).map(move |j| Point2::new(x * f64::from(i) / 6.0, y * f64::from(j) / 4.0))).collect()
}

/// The program in millimetres: G20 → G21, and every length word (X Y Z I J Q) and F × 25.4.
fn to_mm(program: &str) -> String {
    program
        .lines()
        .map(|line| {
            let (code, comment) = line.find('(').map_or((line, ""), |i| line.split_at(i));
            let words: Vec<String> = code
                .split_whitespace()
                .map(|w| {
                    let (letter, rest) = w.split_at(1);
                    match (letter, rest.parse::<f64>()) {
                        ("G", _) if rest == "20" => "G21".to_string(),
                        ("X" | "Y" | "Z" | "I" | "J" | "Q" | "F", Ok(v)) => format!("{letter}{}", v * 25.4),
                        _ => w.to_string(),
                    }
                })
                .collect();
            format!("{} {comment}", words.join(" "))
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn every_example_program_runs_on_the_default_world() {
    for (name, program) in [("1", EX1), ("2", EX2), ("3", EX3), ("4", EX4), ("5", EX5), ("6", EX6), ("7", EX7)] {
        let mut rig = Rig::new(World::default_world(), true);
        let records = rig.run(program);
        assert!(!records.is_empty(), "example {name} ran no Vision M-code");
        assert!(records.iter().all(|r| r.result.is_ok()), "example {name}: {records:?}");
    }
    // The built-in world is calibrated: its example 1 lands on the truth, and shows the print.
    let mut rig = Rig::new(World::default_world(), true);
    let records = rig.run(EX1);
    let e = rig.calibration_error();
    assert!(e.k_relative < 2e-3 && e.offset < 1e-3 && e.remap_matches, "{e:?}");
    let s = sheet_report(&records);
    assert!((s.sheet_scale.x - 1.0008).abs() < 2e-4 && (s.sheet_scale.y - 1.0012).abs() < 2e-4, "{s:?}");
    // Example 4 on it: the demo target is 0.3° askew and printed large; the cut follows it.
    let mut rig = Rig::new(World::default_world(), true);
    let records = rig.run(EX4);
    assert!(rig.max_cut_error(&records, "demo target", &grid(6.0, 4.0)) < 2e-3);
}

/// Deterministic uniform numbers for the random worlds.
struct Lcg(u64);

impl Lcg {
    fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);

        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn within(&mut self, half: f64) -> f64 {
        (2.0 * self.unit() - 1.0) * half
    }
}

fn part(name: &str, marks: &[[f64; 2]], rng: &mut Lcg, uniform: bool) -> Fixture {
    let sx = 1.0 + rng.within(0.005);
    let sy = if uniform { sx } else { 1.0 + rng.within(0.005) };
    Fixture {
        name: name.into(),
        sheet: None,
        marks: marks.to_vec(),
        diameter: Some(0.25),
        shift: [rng.within(0.5), rng.within(0.5)],
        rotation_deg: rng.within(5.0),
        scale: [sx, sy],
        center: None,
        present: false,
    }
}

/// A random world: camera orientation `case % 8`, up to ±3° more, σ = `sigma`; sheet 1 (print
/// scale `print`) on the table, two parts waiting; the camera tool uncalibrated, dot 1 somewhere
/// in view.
pub(crate) fn random_world(case: u64, sigma: f64, print: f64) -> World {
    let mut rng = Lcg(case.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03);
    let mut w = World::default_world();
    w.seed = case;
    w.camera.rotation_deg = 90.0 * f64::from(u32::try_from(case % 4).expect("small")) + rng.within(3.0);
    w.camera.mirror = (case / 4) % 2 == 1;
    w.camera.units_per_pixel = 0.002;
    w.camera.center_bias_px = [rng.within(5.0), rng.within(5.0)];
    w.camera.offset = [rng.within(4.0), rng.within(4.0)];
    w.camera.noise_px = sigma;
    w.camera.jobs.clear();
    w.machine.camera_table_offset = Some([0.0, 0.0]);
    w.machine.start_tool = w.machine.camera_tool;
    w.fixtures = vec![
        Fixture {
            name: "sheet".into(),
            sheet: Some(1),
            marks: vec![],
            diameter: None,
            shift: [0.0, 0.0],
            rotation_deg: rng.within(1.0),
            scale: [print, print],
            center: None,
            present: true,
        },
        part("rectangle part", &[[0.0, 0.0], [6.0, 0.0], [6.0, 4.0], [0.0, 4.0]], &mut rng, false),
        part("similarity part", &[[0.0, 0.0], [8.0, 0.0], [4.0, 6.0]], &mut rng, true),
    ];
    // Dot 1 anywhere in view: up to 0.8 in (≈ 400 px) off the optical axis, with the uncalibrated
    // camera tool (table offset 0) active, so the spindle is where the program position says.
    let dot1 = w.work_to_machine(w.fixtures[0].true_point(Point2::new(-2.5, -4.0), LengthUnit::Inch));
    let axis = dot1 + Vector2::new(rng.within(0.8), rng.within(0.8));
    w.machine.start = [axis.x - w.camera.offset[0], axis.y - w.camera.offset[1], 0.0];
    w
}

/// What one scenario measured, inches (relative for K).
#[derive(Debug, Default, Clone, Copy)]
struct Worst {
    k_relative: f64,
    offset_in: f64,
    centre_in: f64,
    rectangle_cut_in: f64,
    similarity_cut_in: f64,
}

impl Worst {
    fn max(self, o: Worst) -> Worst {
        Worst {
            k_relative: self.k_relative.max(o.k_relative),
            offset_in: self.offset_in.max(o.offset_in),
            centre_in: self.centre_in.max(o.centre_in),
            rectangle_cut_in: self.rectangle_cut_in.max(o.rectangle_cut_in),
            similarity_cut_in: self.similarity_cut_in.max(o.similarity_cut_in),
        }
    }
}

/// Calibrate, verify, align a rectangle part and a similarity part; check every bound. Bounds
/// are in inches and scale by 25.4 in millimetres.
fn scenario(case: u64, sigma: f64, print: f64, unit: LengthUnit) -> Worst {
    let exact = sigma == 0.0;
    let k = LengthUnit::Inch.factor_to(unit);
    let program = |p: &str| if unit == LengthUnit::Millimetre { to_mm(p) } else { p.to_string() };
    let what = format!("case {case} σ {sigma} print {print} {unit:?}");
    let mut rig = Rig::new(random_world(case, sigma, print), false);

    let records = rig.run(&program(EX1));
    let e = rig.calibration_error();
    let (k_bound, offset_bound) = if exact { (1e-6, 1e-6) } else { (2e-3, 1e-3) };
    assert!(e.remap_matches, "{what}: {e:?}");
    assert!(e.k_relative <= k_bound, "{what}: K error {e:?}");
    assert!(e.offset <= offset_bound * k, "{what}: offset error {e:?}");
    let s = sheet_report(&records);
    let scale_tol = if exact { 1e-9 } else { 1e-3 };
    assert!(
        (s.sheet_scale.x - print).abs() < scale_tol && (s.sheet_scale.y - print).abs() < scale_tol,
        "{what}: {s:?}"
    );

    rig.run(&program(EX2));
    let centre = {
        let interp = rig.machine.interpreter();
        Vector2::new(interp.param(500), interp.param(501))
    };
    let centre_bound = if exact { 1e-6 } else { 5e-3 };
    assert!(centre.norm() < centre_bound * k, "{what}: centre residual {centre:?}");

    let cut_bound = if exact { 1e-6 } else { 2e-3 };
    rig.sim.set_present("sheet", false).expect("fixture");
    rig.sim.set_present("rectangle part", true).expect("fixture");
    let records = rig.run(&program(EX4));
    let rectangle_cut = rig.max_cut_error(&records, "rectangle part", &grid(6.0, 4.0));
    assert!(rectangle_cut <= cut_bound, "{what}: rectangle cut error {rectangle_cut}");

    rig.sim.set_present("rectangle part", false).expect("fixture");
    rig.sim.set_present("similarity part", true).expect("fixture");
    let records = rig.run(&program(EX5));
    let similarity_cut = rig.max_cut_error(&records, "similarity part", &grid(8.0, 6.0));
    assert!(similarity_cut <= cut_bound, "{what}: similarity cut error {similarity_cut}");
    // The world is in inches: cut errors are in inches whatever the program's unit.
    Worst {
        k_relative: e.k_relative,
        offset_in: e.offset / k,
        centre_in: centre.norm() / k,
        rectangle_cut_in: rectangle_cut,
        similarity_cut_in: similarity_cut,
    }
}

/// Runs `cases` at σ = 0.1 px and σ = 0 and prints the worst of each.
fn sweep(cases: std::ops::Range<u64>, print: f64, unit: LengthUnit) {
    let (mut noisy, mut exact) = (Worst::default(), Worst::default());
    for case in cases {
        noisy = noisy.max(scenario(case, 0.1, print, unit));
        exact = exact.max(scenario(case, 0.0, print, unit));
    }
    println!("{unit:?}, print {print}: worst at σ = 0.1 px {noisy:?}");
    println!("{unit:?}, print {print}: worst at σ = 0 {exact:?}");
}

#[test]
fn random_worlds_in_inches() {
    sweep(0..16, 1.0, LengthUnit::Inch);
}

#[test]
fn random_worlds_in_millimetres() {
    sweep(100..116, 1.0, LengthUnit::Millimetre);
}

#[test]
fn a_sheet_printed_large_is_measured_not_baked_into_k() {
    sweep(200..208, 1.002, LengthUnit::Inch);
}

#[test]
fn the_mm_conversion_scales_lengths_only() {
    assert_eq!(
        to_mm("G90 G20 (x)\nG0 X1 Y-2\nM283 Q0.5\nM280 P3"),
        "G90 G21 (x)\nG0 X25.4 Y-50.8 \nM283 Q12.7 \nM280 P3 "
    );
}

// Issue 18: accuracy beyond the seed. Parts are aligned with a perfect calibration (the true K
// and camera offset), so what is measured is the alignment itself.

/// The last M282's report, or its refusal.
pub(crate) fn last_fit(records: &[Record]) -> Result<vision_core::AlignReport, String> {
    records
        .iter()
        .rev()
        .find_map(|r| match (r.mcode, &r.result) {
            (282, Ok(Outcome::Apply(reply))) => Some(Ok(reply.report.clone())),
            (282, Err(e)) => Some(Err(e.to_string())),
            _ => None,
        })
        .expect("an M282 ran")
}

/// A random world (as [`random_world`]) with a perfect calibration and only `present` on the
/// table.
fn aligned_rig(case: u64, sigma: f64, edit: impl FnOnce(&mut World)) -> Rig {
    let mut w = random_world(case, sigma, 1.0);
    w.machine.camera_table_offset = None;
    edit(&mut w);
    Rig::new(w, true)
}

/// Over random worlds at σ = 0.1 px, the true cut error of every rectangle and similarity fit
/// is inside the 99 % bound M282 predicts in at least 98 % of the fits.
#[test]
fn the_predicted_bound_covers_the_true_cut_error() {
    let (mut fits, mut covered, mut worst_ratio) = (0u32, 0u32, 0.0f64);
    for case in 300..360 {
        for (fixture, program, size) in [("rectangle part", EX4, (6.0, 4.0)), ("similarity part", EX5, (8.0, 6.0))] {
            let mut rig = aligned_rig(case, 0.1, |w| {
                w.fixtures.iter_mut().for_each(|f| f.present = f.name == fixture);
            });
            let records = rig.run(program);
            let fit = last_fit(&records).expect("accepted");
            let cut = rig.max_cut_error(&records, fixture, &grid(size.0, size.1));
            fits += 1;
            covered += u32::from(cut <= fit.predicted.bound99);
            worst_ratio = worst_ratio.max(cut / fit.predicted.bound99);
        }
    }
    println!("prediction: {covered} of {fits} cut errors inside the 99 % bound; worst cut / bound {worst_ratio:.3}");
    assert!(f64::from(covered) >= 0.98 * f64::from(fits), "{covered} of {fits}");
}

/// A rectangle run over `marks` (program coordinates, inches), then the cutter.
fn rectangle_program(marks: &[[f64; 2]]) -> String {
    let captures: String = marks.iter().map(|[x, y]| format!("G0 X{x} Y{y}\nM281\n")).collect();
    format!("G90 G20 G17\nG54\nT98 M6\nM280 P4\n{captures}M282\nT1 M6\nM30\n")
}

/// Six marks, one of them 0.05 in off where the part was printed: the mark is dropped and the
/// cut error is the floor of the five good marks (exact without noise); without the rule the
/// fit is refused.
#[test]
fn a_displaced_mark_among_six_is_dropped_and_the_cut_recovers() {
    let nominal = [[0.0, 0.0], [3.0, 0.0], [6.0, 0.0], [6.0, 4.0], [3.0, 4.0], [0.0, 4.0]];
    let (mut floor, mut recovered, mut worst) = (0.0f64, 0.0f64, 0.0f64);
    let cases = 400..424;
    for case in cases.clone() {
        let bad = usize::try_from(case % 6).expect("small");
        let five: Vec<[f64; 2]> = nominal.iter().enumerate().filter(|(i, _)| *i != bad).map(|(_, m)| *m).collect();
        let cut = |sigma: f64, displaced: bool, factor: f64, program: &str| {
            let mut rig = aligned_rig(case, sigma, |w| {
                let part = &mut w.fixtures[1];
                part.marks = nominal.to_vec();
                if displaced {
                    part.marks[bad][1] += 0.05;
                }
                w.fixtures.iter_mut().for_each(|f| f.present = f.name == "rectangle part");
            });
            rig.handler.session_mut().module_mut().set_param("VisionOutlierFactor", factor).expect("set");
            let records = rig.run_to_refusal(program);
            match last_fit(&records) {
                Ok(fit) => {
                    let expected = (displaced && factor > 0.0).then_some(bad + 1);
                    assert_eq!(fit.dropped.map(|d| d.mark), expected, "case {case}");
                    Some(rig.max_cut_error(&records, "rectangle part", &grid(6.0, 4.0)))
                }
                Err(e) => {
                    assert!(e.contains("VisionFitMaxResidual"), "case {case}: {e}");
                    None
                }
            }
        };
        let six = rectangle_program(&nominal);
        let exact = cut(0.0, true, 6.0, &six).expect("the displaced mark is dropped");
        assert!(exact < 1e-6, "case {case}: without noise the cut is exact, not {exact}");
        assert_eq!(cut(0.1, true, 0.0, &six), None, "case {case}: without the rule the slip trips the gate");
        floor += cut(0.1, false, 6.0, &rectangle_program(&five)).expect("five good marks").powi(2);
        let dropped = cut(0.1, true, 6.0, &six).expect("the displaced mark is dropped");
        recovered += dropped.powi(2);
        worst = worst.max(dropped);
    }
    // Root mean square over the cases: the two runs draw different noise, so compare the spread.
    let n = (cases.end - cases.start) as f64;
    let (floor, recovered) = ((floor / n).sqrt(), (recovered / n).sqrt());
    println!(
        "six marks, one displaced 0.05 in: rms cut {recovered:.6} in (worst {worst:.6}); five good marks alone {floor:.6} in"
    );
    assert!(recovered <= 1.2 * floor && worst < 2e-3, "{recovered} vs {floor}");
}

/// A similarity part printed 0.5 % large in X only is refused with advice; a rectangle part
/// 1.5 in off nominal is aligned.
#[test]
fn the_gates_refuse_what_cannot_cut_and_accept_the_manuals_workflow() {
    for case in 500..508 {
        let mut rig = aligned_rig(case, 0.1, |w| {
            let part = &mut w.fixtures[2];
            part.scale = [1.005, 1.0];
            part.rotation_deg = part.rotation_deg.clamp(-1.0, 1.0);
            w.fixtures.iter_mut().for_each(|f| f.present = f.name == "similarity part");
        });
        let e = last_fit(&rig.run_to_refusal(EX5)).expect_err("refused");
        assert!(e.contains("M280 P4"), "case {case}: {e}");

        let mut rig = aligned_rig(case, 0.1, |w| {
            let part = &mut w.fixtures[1];
            part.shift = [1.5 * (case as f64).cos(), 1.5 * (case as f64).sin()];
            part.rotation_deg = part.rotation_deg.clamp(-0.5, 0.5);
            w.fixtures.iter_mut().for_each(|f| f.present = f.name == "rectangle part");
        });
        let records = rig.run(EX4);
        last_fit(&records).expect("a 1.5 in offset is accepted");
        let cut = rig.max_cut_error(&records, "rectangle part", &grid(6.0, 4.0));
        assert!(cut < 2e-3, "case {case}: cut {cut}");
    }
}

/// A random world calibrated (perfectly) at the reference working distance, the camera now at
/// `height` × it (a thicker part, a resurfaced spoilboard), only `present` on the table.
fn rig_at_height(case: u64, height: f64, present: &str) -> Rig {
    rig_at(random_world(case, 0.1, 1.0), height, present)
}

/// [`rig_at_height`] for any world `w`.
fn rig_at(mut w: World, height: f64, present: &str) -> Rig {
    w.machine.camera_table_offset = None;
    w.camera.reference_working_distance = Some(w.camera.working_distance);
    let params = Rig::new(w.clone(), true).handler.session().module().params().clone();
    w.camera.working_distance *= height;
    w.fixtures.iter_mut().for_each(|f| f.present = f.name == present);
    let mut rig = Rig::new(w, false);
    for (name, value) in params.config_values() {
        rig.handler.session_mut().module_mut().set_param(name, value).expect("calibration");
    }
    rig
}

/// The worst cut error of a rectangle and a similarity run at `height` (see [`rig_at_height`])
/// with `VisionRecenterPasses` = `passes`.
fn cut_at_height(case: u64, height: f64, passes: i64) -> f64 {
    let mut worst: f64 = 0.0;
    for (fixture, program, size) in [("rectangle part", EX4, (6.0, 4.0)), ("similarity part", EX5, (8.0, 6.0))] {
        let mut rig = rig_at_height(case, height, fixture);
        rig.handler.session_mut().module_mut().set_param("VisionRecenterPasses", passes).expect("set");
        let records = rig.run(program);
        worst = worst.max(rig.max_cut_error(&records, fixture, &grid(size.0, size.1)));
    }
    worst
}

/// Calibrate at one working distance, align at ±4 %: with re-centring every cut is within
/// 0.002 in; read in one shot, many are not.
#[test]
fn recentring_keeps_the_cut_when_the_part_is_higher_or_lower_than_calibrated() {
    let (mut one_shot_misses, mut runs, mut worst_one_shot, mut worst) = (0u32, 0u32, 0.0f64, 0.0f64);
    for case in 600..624 {
        for height in [0.96, 1.04] {
            let one_shot = cut_at_height(case, height, 0);
            let recentred = cut_at_height(case, height, 2);
            runs += 1;
            one_shot_misses += u32::from(one_shot > 2e-3);
            worst_one_shot = worst_one_shot.max(one_shot);
            worst = worst.max(recentred);
            assert!(recentred <= 2e-3, "case {case} height ×{height}: cut {recentred} in with re-centring");
        }
    }
    println!(
        "±4 % height: one shot misses 0.002 in in {one_shot_misses} of {runs} runs (worst {worst_one_shot:.5} in); \
         re-centred worst {worst:.5} in"
    );
    assert!(one_shot_misses > 0, "the scenario must be one the seed fails");
}

/// The height check: with the part 4 % farther or closer than at calibration, every capture of
/// the 0.25 in marks warns with the implied working-distance change; at the calibration height
/// none does.
#[test]
fn the_mark_size_tells_a_height_change() {
    for (height, expected) in [(1.0, None), (1.04, Some("farther")), (0.96, Some("closer"))] {
        let mut rig = rig_at_height(700, height, "rectangle part");
        rig.handler.session_mut().module_mut().set_param("VisionMarkDiameter", 0.25).expect("set");
        let records = rig.run(EX4);
        let warnings: Vec<Option<String>> = records
            .iter()
            .filter_map(|r| match &r.result {
                Ok(Outcome::Capture(reply)) => Some(reply.report.warning.clone()),
                _ => None,
            })
            .collect();
        assert_eq!(warnings.len(), 4);
        for w in &warnings {
            match expected {
                None => assert_eq!(w, &None, "height ×{height}"),
                Some(word) => {
                    let w = w.as_deref().unwrap_or_default();
                    assert!(w.contains(word) && w.contains("VisionMarkDiameter"), "height ×{height}: {w}");
                }
            }
        }
    }
}

/// A camera that reports its frame size (the simulator's) is calibrated at its own resolution
/// (issue 33): with the profile's default 1776 × 1776 and a 4096 × 3072 camera, M283 takes the
/// camera's size as `VisionCameraResX/Y`, records it with K, and calibrates exactly, with no
/// warning; set right by hand, the same. (A camera that reports only positions, a Keyence, is
/// still warned about a reading outside the image: `outside_image_note`.)
#[test]
fn a_camera_that_reports_its_frames_is_calibrated_at_its_own_resolution() {
    for profile_res in [None, Some([4096, 3072])] {
        let mut w = World::default_world();
        w.camera.resolution = [4096, 3072];
        w.camera.units_per_pixel = 0.001;
        w.fixtures[0].marks.clear();
        let mut rig = Rig::new(w, false);
        if let Some([x, y]) = profile_res {
            rig.handler.session_mut().module_mut().set_param("VisionCameraResX", x).expect("set");
            rig.handler.session_mut().module_mut().set_param("VisionCameraResY", y).expect("set");
        }
        let s = sheet_report(&rig.run(EX1));
        let module = rig.handler.session().module();
        let status = module.telemetry().last_status().to_string();
        let e = rig.calibration_error();
        assert!(e.k_relative < 2e-3 && e.remap_matches, "{profile_res:?}: {e:?}");
        assert_eq!((s.warning, status.as_str()), (None, "OK"), "{profile_res:?}");
        let p = module.params();
        assert_eq!((p.camera_res_x(), p.camera_res_y()), (4096, 3072));
        assert_eq!(p.calibration.recorded_resolution(), Some((4096, 3072)));
    }
}

/// The cut error at the calibration height over its least-squares floor, root mean square over
/// the rectangle and similarity fits of `cases` with `VisionRecenterPasses` = `passes`: the
/// statistic is `√mean((cut / floor)²)` and the count of fits. Each fit's floor is M282's
/// predicted 1σ at the worst corner for the camera's noise alone (`sigma × camera_noise /
/// noise`: the prediction is linear in σ), so worlds of every geometry weigh alike and the
/// floor is not itself a noisy estimate. The camera is calibrated perfectly, or by walking the
/// sheet (example 1) when `walk` (the same calibration for both settings: the walk's triggers
/// come first).
fn floor_ratio(cases: std::ops::Range<u64>, passes: i64, walk: bool) -> (f64, u32) {
    let (mut sum, mut fits) = (0.0, 0u32);
    for case in cases {
        let mut rig = if walk { Rig::new(random_world(case, 0.1, 1.0), false) } else { rig_at_height(case, 1.0, "") };
        if walk {
            rig.run(EX1);
        }
        rig.handler.session_mut().module_mut().set_param("VisionRecenterPasses", passes).expect("set");
        for (fixture, program, size) in [("rectangle part", EX4, (6.0, 4.0)), ("similarity part", EX5, (8.0, 6.0))] {
            for name in ["sheet", "rectangle part", "similarity part"] {
                rig.sim.set_present(name, name == fixture).expect("fixture");
            }
            let records = rig.run(program);
            let p = last_fit(&records).expect("accepted").predicted;
            let cut = rig.max_cut_error(&records, fixture, &grid(size.0, size.1));
            sum += (cut / (p.sigma * p.camera_noise / p.noise)).powi(2);
            fits += 1;
        }
    }
    ((sum / f64::from(fits)).sqrt(), fits)
}

/// Re-centring costs nothing where the one-shot cut is already at the floor (the part at the
/// calibration height): over `cases`, the cut error over its floor with re-centring on (2
/// passes) stays within 1.1× of the same with it off (`VisionRecenterPasses` 0).
fn recentring_stays_at_the_floor(cases: std::ops::Range<u64>, walk: bool) {
    let (off, fits) = floor_ratio(cases.clone(), 0, walk);
    let (on, _) = floor_ratio(cases, 2, walk);
    let how = if walk { "calibrated by the sheet walk" } else { "calibrated perfectly" };
    println!(
        "calibration height, {how}, {fits} fits each: rms cut / floor {off:.4} one shot, {on:.4} re-centred \
         (ratio {:.4})",
        on / off
    );
    assert!(on <= 1.1 * off, "re-centring costs accuracy at the floor: {on} vs {off}");
}

/// The quick form: 200 worlds, 400 fits each way (the ratio's own spread is about 3 %).
#[test]
fn recentring_keeps_the_floor_at_the_calibration_height() {
    recentring_stays_at_the_floor(1000..1200, false);
}

/// The README's figures: 4000 worlds calibrated perfectly and 1000 calibrated by the sheet walk
/// (`cargo test -p vision-cli --test it acceptance:: -- --ignored --nocapture`).
#[test]
#[ignore = "about 10 s in a debug build; the quick form runs always"]
fn recentring_keeps_the_floor_at_the_calibration_height_over_many_worlds() {
    recentring_stays_at_the_floor(2000..6000, false);
    recentring_stays_at_the_floor(6000..7000, true);
}

// Issue 28: the part at another height than the calibration's. Calibrated by the sheet walk at
// 6.00 in (calibration error included), aligned at 5.75, 6.06 and 6.25 in and at 6.00 in itself.

/// The heights of issue 28, as working distance over the calibration's (6.00 in).
const HEIGHTS: [(&str, f64); 4] =
    [("6.00 in", 1.0), ("5.75 in", 5.75 / 6.0), ("6.06 in", 6.06 / 6.0), ("6.25 in", 6.25 / 6.0)];

/// How a part lies: `near` nominal (shift ±0.02 in, rotation ±0.1°: most marks are seen a few
/// pixels off centre) or `any` (shift ±0.5 in, rotation ±5°).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Placement {
    Near,
    Any,
}

/// Where the camera's optical axis meets the image: `Off` by up to ±5 px per axis from the
/// image centre (as in every random world), or `Known` (on the image centre, as
/// `VisionPxCenterOffset` 0 assumes). Either way the sheet walk's calibration lift (on by
/// default) measures it: a walk at one height would absorb an error into the camera offset,
/// and no camera move could measure it at another height.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Centre {
    Off,
    Known,
}

/// M281's and M282's settings: issue 28's defaults, or issue 25's (`VisionRecenterTolerance`
/// 16 px, no probe, no height correction), which reproduce the cuts from before issue 28.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Settings {
    Default,
    Issue25,
}

/// One world calibrated by the sheet walk at 6.00 in: its parameters and the camera tool's
/// offset as the walk left it in the tool table (world unit, the world's sign convention).
struct Walked {
    world: World,
    params: Vec<(&'static str, vision_core::ParamValue)>,
    camera_offset: [f64; 2],
}

fn walked(case: u64, centre: Centre) -> Walked {
    let mut world = random_world(case, 0.1, 1.0);
    if centre == Centre::Known {
        world.camera.center_bias_px = [0.0, 0.0];
    }
    world.camera.working_distance = 6.0;
    world.camera.reference_working_distance = Some(6.0);
    let mut rig = Rig::new(world.clone(), false);
    rig.run(EX1);
    let interp = rig.machine.interpreter();
    let sign = world.machine.controller().tool_table_sign();
    let table = interp.tool_offset(world.machine.camera_tool).expect("camera tool").xy();
    let params = rig.handler.session().module().params().config_values();
    Walked { world, params, camera_offset: [table.x / sign, table.y / sign] }
}

/// `walked`'s world with the part placed by `placement` (drawn from `case`), the camera at
/// `height` × the calibration's working distance, only `present` on the table.
fn walked_rig(w: &Walked, case: u64, height: f64, placement: Placement, present: &str, settings: Settings) -> Rig {
    let mut world = w.world.clone();
    let mut rng = Lcg(case ^ 0x5DEE_CE66_D1CE_4E5B);
    let (shift, turn) = match placement {
        Placement::Near => (0.02, 0.1),
        Placement::Any => (0.5, 5.0),
    };
    for f in &mut world.fixtures {
        f.present = f.name == present;
        if f.sheet.is_none() {
            f.shift = [rng.within(shift), rng.within(shift)];
            f.rotation_deg = rng.within(turn);
        }
    }
    world.camera.working_distance = 6.0 * height;
    world.machine.camera_table_offset = Some(w.camera_offset);
    let mut rig = Rig::new(world, false);
    let module = rig.handler.session_mut().module_mut();
    for (name, value) in &w.params {
        module.set_param(name, value.clone()).expect("calibration");
    }
    if settings == Settings::Issue25 {
        module.set_param("VisionRecenterTolerance", 16.0).expect("set");
        module.set_param("VisionHeightProbePx", 0.0).expect("set");
        module.set_param("VisionHeightCorrection", false).expect("set");
    }
    rig
}

/// One alignment at a height: the true cut error and the predicted 99 % bound, inches.
#[derive(Debug, Clone, Copy)]
struct HeightFit {
    cut: f64,
    bound: f64,
}

/// The rectangle and similarity fits of `worlds` (calibrated by the walk with `centre`) with
/// the part placed by `placement`, at `height` × the calibration's working distance.
fn height_fits(
    worlds: std::ops::Range<u64>,
    height: f64,
    placement: Placement,
    centre: Centre,
    settings: Settings,
) -> Vec<HeightFit> {
    let mut out = Vec::new();
    for case in worlds {
        let w = walked(case, centre);
        for (fixture, program, size) in [("rectangle part", EX4, (6.0, 4.0)), ("similarity part", EX5, (8.0, 6.0))] {
            let mut rig = walked_rig(&w, case, height, placement, fixture, settings);
            let records = rig.run(program);
            let fit = last_fit(&records).expect("accepted");
            let p = fit.predicted;
            let cut = rig.max_cut_error(&records, fixture, &grid(size.0, size.1));
            out.push(HeightFit { cut, bound: p.bound99 });
        }
    }
    out
}

/// The 95th percentile of `v`.
pub(crate) fn p95(v: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = v.collect();
    v.sort_by(f64::total_cmp);
    let i = ((v.len() as f64) * 0.95).ceil() as usize;
    v[i.clamp(1, v.len()) - 1]
}

/// What one case measured: cut p95 over the calibration height's (same worlds, marks and
/// settings), the share of fits inside the predicted 99 % bound, and the root-mean-square cut.
#[derive(Debug, Clone, Copy)]
struct CaseFigures {
    p95_ratio: f64,
    coverage: f64,
    rms: f64,
}

fn case_figures(fits: &[HeightFit], floor95: f64) -> CaseFigures {
    let coverage = fits.iter().filter(|f| f.cut <= f.bound).count() as f64 / fits.len() as f64;
    let rms = (fits.iter().map(|f| f.cut * f.cut).sum::<f64>() / fits.len() as f64).sqrt();
    CaseFigures { p95_ratio: p95(fits.iter().map(|f| f.cut)) / floor95, coverage, rms }
}

/// Issue 28's figures over `worlds`: per optical centre, placement and height, the cut error's
/// p95 against the p95 of the same worlds and marks at the calibration height (the floor of the
/// same marks and noise), and the share of fits whose true cut error lies inside the predicted
/// 99 % bound; with `before`, the same under issue 25's settings. The bound must cover ≥
/// `coverage` and the p95 stay within `slack` × 1.2 the floor everywhere: the calibration lift
/// measured the optical centre, so what is left of the shift ε × centre error × K is the lift's
/// noise (before the lift, at ±4 % with the centre off: 1.4–1.7×; before issue 28: 3.2–3.6×).
fn height_cases(worlds: std::ops::Range<u64>, coverage: f64, slack: f64, before: bool) {
    let mut failures = Vec::new();
    for centre in [Centre::Off, Centre::Known] {
        for placement in [Placement::Near, Placement::Any] {
            let mut settings = vec![Settings::Default];
            if before {
                settings.push(Settings::Issue25);
            }
            let mut floors = Vec::new();
            for s in &settings {
                let at = height_fits(worlds.clone(), 1.0, placement, centre, *s);
                floors.push((at.clone(), p95(at.iter().map(|f| f.cut))));
            }
            for (name, height) in HEIGHTS {
                let mut line = format!("height {name}, centre {centre:?}, part {placement:?}:");
                for (s, (at, floor95)) in settings.iter().zip(&floors) {
                    let fits = if height == 1.0 {
                        at.clone()
                    } else {
                        height_fits(worlds.clone(), height, placement, centre, *s)
                    };
                    let f = case_figures(&fits, *floor95);
                    line += &format!(
                        " {s:?}: cut p95 {:.3} × {floor95:.6} in, rms {:.6} in, covered {:.1} % of {};",
                        f.p95_ratio,
                        f.rms,
                        f.coverage * 100.0,
                        fits.len()
                    );
                    if *s == Settings::Default && (f.p95_ratio > slack * 1.2 || f.coverage < coverage) {
                        failures.push(format!("{name} {centre:?} {placement:?}: {f:?}"));
                    }
                }
                println!("{line}");
            }
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// The quick form, always run: 12 worlds, 24 fits per case. The p95 of 24 is their second
/// largest and one miss is 4 %, so the limits allow for it (before issue 28: ×3–4, 17–40 %).
#[test]
fn a_height_change_is_measured_corrected_and_predicted() {
    height_cases(3000..3012, 0.95, 1.25, false);
}

/// The README's figures: 60 worlds, 120 fits per case, with issue 25's settings beside
/// (`cargo test --release -p vision-cli --test it acceptance::height -- --ignored --nocapture`).
#[test]
#[ignore = "about 3 s in a release build; the quick form runs always"]
fn a_height_change_is_measured_corrected_and_predicted_over_many_worlds() {
    height_cases(3100..3160, 0.98, 1.0, true);
}

/// Nothing changes at the calibration height: over 1000 walked worlds × (rectangle +
/// similarity) per placement, the root-mean-square cut error with issue 28's settings within
/// 1.05× of issue 25's (the captures are the same one-shot or re-centred readings; only the
/// noise draws differ, by the probe's extra trigger).
#[test]
#[ignore = "about 10 s in a release build"]
fn the_calibration_height_cuts_as_before() {
    for placement in [Placement::Near, Placement::Any] {
        let rms = |s| case_figures(&height_fits(5000..6000, 1.0, placement, Centre::Off, s), 1.0).rms;
        let (before, after) = (rms(Settings::Issue25), rms(Settings::Default));
        println!(
            "calibration height, part {placement:?}, 2000 fits: rms cut {before:.6} in with issue 25's settings, \
             {after:.6} in now (×{:.4})",
            after / before
        );
        assert!(after <= 1.05 * before, "{placement:?}: {after} vs {before}");
    }
}

/// Issue 28's property: over random height changes (±6 %), camera noise (0.05–0.3 px, told to
/// M282 through `VisionCameraNoisePx`) and worlds, calibrated perfectly at the reference height,
/// the working-distance change M282 reports is unbiased and its stated 1σ honest: the z-scores
/// `(reported − true) / reported σ` have mean ≈ 0 and spread ≈ 1.
#[test]
fn the_measured_height_change_is_unbiased_and_its_sigma_honest() {
    let (mut sum, mut sum2, mut n, mut worst) = (0.0, 0.0, 0u32, 0.0f64);
    for case in 4000..4100 {
        let mut rng = Lcg(case ^ 0x0028_0028);
        let height = 1.0 + rng.within(0.06);
        let noise = 0.05 + 0.25 * rng.unit();
        for (fixture, program) in [("rectangle part", EX4), ("similarity part", EX5)] {
            let mut rig = rig_at(random_world(case, noise, 1.0), height, fixture);
            rig.handler.session_mut().module_mut().set_param("VisionCameraNoisePx", noise).expect("set");
            let h = last_fit(&rig.run(program)).expect("accepted").height.expect("measured");
            let z = (h.change_pct - (height - 1.0) * 100.0) / h.sigma_pct;
            sum += z;
            sum2 += z * z;
            n += 1;
            worst = worst.max(z.abs());
        }
    }
    let mean = sum / f64::from(n);
    let spread = (sum2 / f64::from(n) - mean * mean).sqrt();
    println!("height change over {n} fits: z-scores mean {mean:.3}, spread {spread:.3}, worst |z| {worst:.2}");
    // 200 fits: the mean's own 1σ is 0.07, the spread's 0.05.
    assert!(mean.abs() < 0.25 && (spread - 1.0).abs() < 0.2, "mean {mean}, spread {spread}");
}

// Issue 38: example 5 run right after example 4 in one session. Example 4 ends its demo cut at
// Z0.25, so example 5 captures its three marks with the camera 0.25 in higher (6.25 in over the
// calibration's 6.00 in: +4.2 %) unless something moves it back.

/// How the camera of a chained run was calibrated at 6.00 in: by the sheet walk (example 1 with
/// its lift, as [`walked`]); perfectly (`Sim::calibrated_params`: the true K, camera offset and
/// optical centre, the pixel the image shrinks about); or `AtOneHeight` (the true K, the
/// optical centre taken at the image centre and the camera offset absorbing it: exact at 6.00 in
/// only, as a calibration without the lift).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Calibrated {
    Walk,
    Perfect,
    AtOneHeight,
}

/// A random world of `case` calibrated as `how`, the head at its start height, both parts placed
/// by `placement` and only `present` on the table.
fn chained_rig(case: u64, how: Calibrated, placement: Placement, present: &str) -> Rig {
    if how == Calibrated::Walk {
        return walked_rig(&walked(case, Centre::Off), case, 1.0, placement, present, Settings::Default);
    }
    let mut w = random_world(case, 0.1, 1.0);
    w.camera.working_distance = 6.0;
    if placement == Placement::Near {
        let mut rng = Lcg(case ^ 0x5DEE_CE66_D1CE_4E5B);
        for f in w.fixtures.iter_mut().filter(|f| f.sheet.is_none()) {
            f.shift = [rng.within(0.02), rng.within(0.02)];
            f.rotation_deg = rng.within(0.1);
        }
    }
    if how == Calibrated::Perfect {
        return rig_at(w, 1.0, present);
    }
    // At one height: the centre taken at the image centre, the camera offset solved there.
    w.camera.reference_working_distance = Some(w.camera.working_distance);
    let offset = Sim::new(w.clone()).expect("valid world").true_camera_offset(Vector2::zeros(), LengthUnit::Inch);
    w.machine.camera_table_offset = Some([offset.x, offset.y]);
    w.fixtures.iter_mut().for_each(|f| f.present = f.name == present);
    let mut rig = Rig::new(w, true);
    let module = rig.handler.session_mut().module_mut();
    for name in ["VisionPxCenterOffsetX", "VisionPxCenterOffsetY", "VisionPxCenterSigmaPx"] {
        module.set_param(name, 0.0).expect("set");
    }
    rig
}

/// Runs `program` from wherever the head is (no move back to the start height, as one
/// `mach-vision run` of several programs does); returns the Vision records.
fn run_from_here(rig: &mut Rig, program: &str) -> Vec<Record> {
    let mut ignore = |_: &Event| {};
    if let Err(e) = rig.machine.run_program(program, Some(&mut rig.handler), &mut ignore) {
        panic!("program failed: {e}\n{program}");
    }
    rig.handler.take_records()
}

/// The examples of a chained run: fixture, program, part size (inches).
const CHAINED: [(&str, &str, (f64, f64)); 2] =
    [("rectangle part", EX4, (6.0, 4.0)), ("similarity part", EX5, (8.0, 6.0))];

/// One fit of a chained run: the true cut error and the predicted 99 % bound (inches), the true
/// working-distance change (percent) and the z-score of the one M282 reported,
/// `(reported − true) / reported 1σ`.
#[derive(Debug, Clone, Copy)]
struct ChainedFit {
    cut: f64,
    bound: f64,
    true_pct: f64,
    z: f64,
}

/// Over `worlds` calibrated as `how` with the parts placed by `placement`: per example (4, 5),
/// its fits run first from the start height (its floor) and its fits run second, right after
/// the other example, from Z0.25 where the other's demo cut left the head.
fn chained_fits(
    worlds: std::ops::Range<u64>,
    how: Calibrated,
    placement: Placement,
) -> [(Vec<ChainedFit>, Vec<ChainedFit>); 2] {
    let mut out: [(Vec<ChainedFit>, Vec<ChainedFit>); 2] = Default::default();
    for case in worlds {
        for first in 0..2 {
            let second = 1 - first;
            let mut rig = chained_rig(case, how, placement, CHAINED[first].0);
            let mut fits = Vec::new();
            for i in [first, second] {
                let (fixture, program, size) = CHAINED[i];
                for (name, _, _) in CHAINED {
                    rig.sim.set_present(name, name == fixture).expect("fixture");
                }
                // Where the captures are made: a fresh rig starts at the calibration height.
                let true_pct = (rig.sim.working_distance() / 6.0 - 1.0) * 100.0;
                let records = if i == first { rig.run(program) } else { run_from_here(&mut rig, program) };
                let fit = last_fit(&records).expect("accepted");
                let h = fit.height.expect("measured");
                fits.push(ChainedFit {
                    cut: rig.max_cut_error(&records, fixture, &grid(size.0, size.1)),
                    bound: fit.predicted.bound99,
                    true_pct,
                    z: (h.change_pct - true_pct) / h.sigma_pct,
                });
            }
            // The first from the calibration height, the second from 0.25 in above it.
            let (at, above) = (fits[0].true_pct, fits[1].true_pct);
            assert!(at.abs() < 1e-9 && (above - 25.0 / 6.0).abs() < 1e-9, "case {case}: {fits:?}");
            out[first].0.push(fits[0]);
            out[second].1.push(fits[1]);
        }
    }
    out
}

/// The median of `v`.
fn median(v: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = v.collect();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

/// What one chained case measured: example 5 after example 4 calibrated by the walk or
/// perfectly (`held`), its cut errors run second and their floor run first (inches), and the
/// share of the second inside the predicted 99 % bound.
struct ChainedCase {
    name: String,
    held: bool,
    floor: Vec<f64>,
    after: Vec<f64>,
    covered: f64,
}

/// Example 5 right after example 4 (and example 4 right after example 5) in one session, over
/// `worlds` per calibration and placement, printed. An example's floor is the p95 (and the
/// median) of its cut errors over the same worlds, calibration and placement, run first, from
/// the start height (the calibration's working distance). Example 5 after example 4 calibrated
/// by the walk or perfectly is held to the floor; `AtOneHeight` is printed only: its optical
/// centre is unknown, and at +4.2 % every capture shifts by 0.042 × the centre's distance from
/// the image centre × K, which no camera move can tell from the part's own shift.
fn chained_cases(worlds: std::ops::Range<u64>) -> Vec<ChainedCase> {
    let mut cases = Vec::new();
    for placement in [Placement::Near, Placement::Any] {
        for how in [Calibrated::Walk, Calibrated::Perfect, Calibrated::AtOneHeight] {
            let fits = chained_fits(worlds.clone(), how, placement);
            for (example, (floor, after)) in ["example 4", "example 5"].into_iter().zip(&fits) {
                let cuts = |v: &[ChainedFit]| v.iter().map(|f| f.cut).collect::<Vec<f64>>();
                let (floor, cut) = (cuts(floor), cuts(after));
                let (floor95, floor50) = (p95(floor.iter().copied()), median(floor.iter().copied()));
                let covered = after.iter().filter(|f| f.cut <= f.bound).count() as f64 / after.len() as f64;
                let n = after.len() as f64;
                let z_mean = after.iter().map(|f| f.z).sum::<f64>() / n;
                let z_spread = (after.iter().map(|f| (f.z - z_mean).powi(2)).sum::<f64>() / n).sqrt();
                println!(
                    "{example} after the other, part {placement:?}, calibrated {how:?}, {} fits: cut p95 {:.3} × \
                     {floor95:.6} in, median {:.3} × {floor50:.6} in, covered {:.1} %; height z-scores mean \
                     {z_mean:.2}, spread {z_spread:.2}",
                    after.len(),
                    p95(cut.iter().copied()) / floor95,
                    median(cut.iter().copied()) / floor50,
                    covered * 100.0
                );
                cases.push(ChainedCase {
                    name: format!("{example} {placement:?} {how:?}"),
                    held: example == "example 5" && how != Calibrated::AtOneHeight,
                    floor,
                    after: cut,
                    covered,
                });
            }
        }
    }
    cases
}

/// The root mean square of `v`.
fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

/// The quick form, always run: 40 worlds per case. A p95 of 40, their second largest, moves by
/// ±20 % between seed ranges; the root-mean-square cut of the 160 held fits over their floor's
/// is held instead (1.08–1.15 per case over 200 worlds; without the height correction about 3,
/// with the optical centre unknown about 1.7), and the coverage with two misses' slack.
#[test]
fn example_5_after_example_4_reaches_the_floor() {
    let cases = chained_cases(3800..3840);
    let held: Vec<&ChainedCase> = cases.iter().filter(|c| c.held).collect();
    let pooled =
        |f: fn(&ChainedCase) -> &Vec<f64>| rms(&held.iter().flat_map(|c| f(c).iter().copied()).collect::<Vec<_>>());
    let ratio = pooled(|c| &c.after) / pooled(|c| &c.floor);
    let fits: usize = held.iter().map(|c| c.after.len()).sum();
    println!("example 5 after example 4, {fits} fits: rms cut over the floor's {ratio:.3}");
    assert!(ratio <= 1.3, "rms cut ×{ratio:.3} of the floor");
    for c in held {
        assert!(c.covered >= 0.95, "{}: covered {}", c.name, c.covered);
    }
}

/// The full form: 200 worlds per case (`cargo test --release -p vision-cli --test it
/// acceptance::example_5_after_example_4 -- --ignored --nocapture`). The p95 of 40 worlds, the
/// second largest cut, moves by ±20 % between seed ranges on its own; 200 hold it to a few.
#[test]
#[ignore = "about 2 s in a release build; the quick form runs always"]
fn example_5_after_example_4_reaches_the_floor_over_many_worlds() {
    let mut failures = Vec::new();
    for c in chained_cases(3800..4000).iter().filter(|c| c.held) {
        println!("{}: rms ×{:.3}", c.name, rms(&c.after) / rms(&c.floor));
        let ratio = p95(c.after.iter().copied()) / p95(c.floor.iter().copied());
        if ratio > 1.2 || c.covered < 0.98 {
            failures.push(format!("{}: p95 ×{ratio:.3}, covered {:.3}", c.name, c.covered));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}
