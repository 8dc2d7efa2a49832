//! M280, M281 and M282: runs, slots, units, the program frame, partial modes, gates.

use vision_math::{fit_rectangle, AlignmentChain, LengthUnit, Matrix2, Point2, Vector2};

use super::fakes::{Rig, World, CANCEL_LINE};
use crate::driver::{Judgment, Reading};
use crate::error::VisionError;
use crate::machine::Machine;
use crate::module::{Dot, Pieces, Run, RunMode};
use crate::params::ParamValue;

const PART: [(f64, f64); 4] = [(0.0, 0.0), (6.0, 0.0), (6.0, 4.0), (0.0, 4.0)];

/// Where the part really lies: nominal → rotated 0.4° about (3, 2), scaled 1.001, shifted.
fn true_part() -> AlignmentChain {
    AlignmentChain {
        scale: Vector2::new(1.001, 1.001),
        center: Point2::new(3.0, 2.0),
        rotation_deg: 0.4,
        shift: Vector2::new(0.05, -0.03),
    }
}

fn rig_with_part() -> Rig {
    let part = true_part();
    let world =
        World { marks: PART.iter().map(|(x, y)| part.apply(Point2::new(*x, *y))).collect(), ..World::default() };
    Rig::with_world(world)
}

fn capture_all(rig: &mut Rig, points: &[(f64, f64)]) {
    for (x, y) in points {
        rig.go(*x, *y);
        rig.module.m281(&mut rig.machine, false).expect("capture");
    }
}

fn slot(rig: &Rig, s: u32) -> [f64; 8] {
    let w = rig.world();
    std::array::from_fn(|f| {
        w.pounds.get(&(500 + 8 * s + u32::try_from(f).expect("small"))).copied().unwrap_or(f64::NAN)
    })
}

#[test]
fn m280_starts_a_run_and_cancels_alignment() {
    let mut rig = Rig::new();
    // A previous run's captures are dropped by the next M280.
    rig.module.run.dots = vec![
        Dot {
            commanded: Point2::origin(),
            observed: Point2::origin(),
            unit: LengthUnit::Inch,
            reach: vision_math::Vector2::zeros(),
            mark_size: 0.0,
            lens_along: [vision_math::Vector2::zeros(); 4],
        };
        7
    ];
    let r = rig.module.m280(&mut rig.machine, RunMode::Similarity).expect("m280");
    assert_eq!(r.gcode, vec![CANCEL_LINE.to_string()]);
    assert_eq!(r.gcode[0], "G69 G50 G52 X0 Y0");
    assert_eq!(
        rig.module.run(),
        &Run {
            mode: RunMode::Similarity,
            active: true,
            dots: Vec::new(),
            scale: vision_math::ScaleEvidence::default()
        }
    );
    let t = rig.module.telemetry();
    assert_eq!((t.run_active(), t.run_mode(), t.run_dot_count()), (1, 3, 0));
    assert_eq!(rig.module.param("visionrun_mode"), Ok(ParamValue::Int(3)));
}

#[test]
fn m280_and_m282_commit_only_after_the_machine_took_their_lines() {
    let mut rig = rig_with_part();
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
    capture_all(&mut rig, &PART);
    let run = rig.module.run().clone();
    rig.world().fail_gcode_after = Some(0);
    let e = rig.module.m282(&mut rig.machine, Pieces::All).expect_err("e-stop");
    // A host tells an e-stop from a refused word without reading text.
    let VisionError::Machine(machine) = &e else { panic!("{e}") };
    assert_eq!(machine.kind(), crate::MachineErrorKind::Stopped);
    assert_eq!(e.to_string(), "machine: emergency stop");
    assert_eq!(rig.module.run(), &run, "the run stays open");
    assert_eq!(rig.module.telemetry().run_active(), 1);
    assert_eq!(rig.module.telemetry().run_sx(), 1.0);
    let e = rig.module.m280(&mut rig.machine, RunMode::Similarity).expect_err("e-stop");
    assert!(matches!(e, VisionError::Machine(_)), "{e}");
    assert_eq!(rig.module.run(), &run, "the dots survive a refused M280");
}

#[test]
fn m280_refuses_a_reserved_pound_base() {
    let mut rig = Rig::new();
    // Bypass set() validation to model a profile written by an older version.
    rig.module.params.config.pound_var_base = 5070;
    let before = rig.module.params().clone();
    let e = rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect_err("reserved");
    assert_eq!(e, VisionError::PoundBaseReserved { base: 5070, end: 5109 });
    assert!(e.to_string().starts_with("VisionPoundVarBase is in reserved range"));
    assert_eq!(rig.module.params(), &before);
    assert!(matches!(rig.module.m281(&mut rig.machine, false), Err(VisionError::PoundBaseReserved { .. })));
}

#[test]
fn m281_outside_a_run_writes_slot_zero_and_telemetry_only() {
    let mut rig = Rig::new();
    rig.world().marks = vec![Point2::new(1.1, 0.9)];
    rig.module.set_param("VisionRecenterPasses", 0).expect("one shot, as the seed");
    rig.go(1.0, 1.0);
    let c = rig.module.m281(&mut rig.machine, false).expect("capture").report;
    assert!((c.observed - Point2::new(1.1, 0.9)).norm() < 1e-12, "{c:?}");
    assert_eq!(c.commanded, Point2::new(1.0, 1.0));
    assert_eq!((c.dot_index, c.slot), (None, None));
    assert!(rig.module.dots().is_empty());
    let s0 = slot(&rig, 0);
    assert!((s0[0] - 1.1).abs() < 1e-12 && (s0[1] - 0.9).abs() < 1e-12);
    assert!((s0[2] - 0.5).abs() < 1e-12 && (s0[3] - 0.5).abs() < 1e-12, "{s0:?}");
    assert_eq!((s0[4], s0[5]), (1.5, 0.97));
    assert!(s0[6].is_nan() && s0[7].is_nan(), "reserved fields untouched");
    assert!(slot(&rig, 1)[0].is_nan());
    let p = rig.module.telemetry();
    assert_eq!(p.last_status(), "OK");
    assert_eq!(p.last_judgment(), 1);
    assert!((p.last_offset_x() - 0.1).abs() < 1e-12 && (p.last_offset_y() + 0.1).abs() < 1e-12);
    // InvertY: the mark is 0.1 in below, i.e. +y pixels (down) in the native image.
    assert!((p.last_offset_px_y() - 0.1 / 0.00203).abs() < 1e-9);
    assert_eq!(p.run_dot_count(), 0);
}

#[test]
fn a_run_fills_slots_in_order_and_mirrors_slot_zero() {
    let mut rig = rig_with_part();
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
    capture_all(&mut rig, &PART);
    let part = true_part();
    for (i, (x, y)) in PART.iter().enumerate() {
        let s = slot(&rig, u32::try_from(i + 1).expect("small"));
        let truth = part.apply(Point2::new(*x, *y));
        assert!((s[0] - truth.x).abs() < 1e-12 && (s[1] - truth.y).abs() < 1e-12, "slot {}", i + 1);
    }
    assert_eq!(slot(&rig, 0)[..6], slot(&rig, 4)[..6]);
    assert_eq!(rig.module.telemetry().run_dot_count(), 4);
    assert_eq!(rig.module.dots().len(), 4);
    // A fifth capture feeds the fit and slot 0 but leaves slots 1–4 alone.
    let before: Vec<_> = (1..=4).map(|s| slot(&rig, s)[..6].to_vec()).collect();
    rig.go(6.0, 4.0);
    let c = rig.module.m281(&mut rig.machine, false).expect("fifth").report;
    assert_eq!((c.dot_index, c.slot), (Some(5), None));
    assert_eq!((1..=4).map(|s| slot(&rig, s)[..6].to_vec()).collect::<Vec<_>>(), before);
    assert_eq!(rig.module.telemetry().run_dot_count(), 5);
}

#[test]
fn a_three_mark_run_leaves_slot_four_untouched() {
    let mut rig = rig_with_part();
    rig.world().pounds.insert(532, 42.0);
    rig.module.m280(&mut rig.machine, RunMode::Similarity).expect("m280");
    capture_all(&mut rig, &PART[..3]);
    assert_eq!(slot(&rig, 4)[0], 42.0);
    let r = rig.module.m282(&mut rig.machine, Pieces::All).expect("m282");
    assert_eq!(r.report.mode, RunMode::Similarity);
    assert!(r.report.fit.max_residual < 1e-9);
    assert_eq!(slot(&rig, 4)[0], 42.0);
}

#[test]
fn m282_emits_the_chain_that_carries_commanded_onto_observed() {
    let mut rig = rig_with_part();
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
    capture_all(&mut rig, &PART);
    let r = rig.module.m282(&mut rig.machine, Pieces::All).expect("m282");
    let chain = r.report.chain;
    assert_eq!(r.gcode.len(), 4);
    let commands = crate::controller::modal_commands(&chain).expect("finite");
    assert_eq!(r.gcode, commands.iter().flat_map(|c| rig.machine.gcode(c).expect("text")).collect::<Vec<_>>());
    assert_eq!(r.gcode[0], CANCEL_LINE);
    assert!(r.gcode[1].starts_with("G52 X") && r.gcode[2].starts_with("G68 X") && r.gcode[3].starts_with("G51 X"));
    let part = true_part();
    for (x, y) in PART {
        let n = Point2::new(x, y);
        assert!((chain.apply(n) - part.apply(n)).norm() < 1e-9);
    }
    let p = rig.module.telemetry();
    assert_eq!(p.run_active(), 0);
    assert!(!rig.module.run().active);
    assert!((p.run_theta() - 0.4f64.to_radians()).abs() < 1e-9);
    assert!((p.run_sx() - 1.001).abs() < 1e-9 && (p.run_sy() - 1.001).abs() < 1e-9);
    assert_eq!((p.run_tx(), p.run_ty()), (chain.shift.x, chain.shift.y));
    assert_eq!((p.run_center_x(), p.run_center_y()), (3.0, 2.0));
}

#[test]
fn captures_after_m282_are_in_the_program_frame() {
    let mut rig = rig_with_part();
    let centre = true_part().apply(Point2::new(3.0, 2.0));
    rig.world().marks.push(centre);
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
    capture_all(&mut rig, &PART);
    let r = rig.module.m282(&mut rig.machine, Pieces::All).expect("m282");
    // M282 ran its modals on the machine: the fake now applies the emitted chain.
    let active = rig.world().alignment.expect("alignment active");
    assert!((active.apply(Point2::new(6.0, 4.0)) - r.report.chain.apply(Point2::new(6.0, 4.0))).norm() < 1e-9);
    let log = rig.world().log.clone();
    assert_eq!(log[log.len() - 4..], r.gcode[..]);
    rig.go(3.0, 2.0);
    let c = rig.module.m281(&mut rig.machine, false).expect("verify").report;
    assert!((c.observed - Point2::new(3.0, 2.0)).norm() < 1e-9, "{c:?}");
    assert!((slot(&rig, 0)[0] - 3.0).abs() < 1e-9 && (slot(&rig, 0)[1] - 2.0).abs() < 1e-9);
}

#[test]
fn more_marks_than_the_minimum_are_solved_by_least_squares() {
    let mut rig = rig_with_part();
    let part = true_part();
    let extra = [(3.0, 0.0), (3.0, 4.0)];
    for (x, y) in extra {
        let m = part.apply(Point2::new(x, y)) + Vector2::new(0.002, -0.001);
        rig.world().marks.push(m);
    }
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
    let all: Vec<_> = PART.iter().chain(extra.iter()).copied().collect();
    capture_all(&mut rig, &all);
    let r = rig.module.m282(&mut rig.machine, Pieces::All).expect("m282");
    assert_eq!(r.report.fit.len, 6);
    assert_eq!(r.report.residuals.len(), 6);
    let (n, o): (Vec<_>, Vec<_>) = rig.module.dots().iter().map(|d| (d.commanded, d.observed)).unzip();
    assert_eq!(r.report.fit, fit_rectangle(&n, &o).expect("fit"));
    assert!(r.report.fit.rms > 0.0);
}

#[test]
fn too_few_marks_emit_nothing_and_keep_the_run() {
    let mut rig = rig_with_part();
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
    capture_all(&mut rig, &PART[..3]);
    let e = rig.module.m282(&mut rig.machine, Pieces::All).expect_err("3 of 4");
    assert_eq!(e, VisionError::TooFewDots { mode: "rectangle", needed: 4, got: 3 });
    assert_eq!(rig.module.telemetry().run_active(), 1);
    capture_all(&mut rig, &PART[3..]);
    assert!(rig.module.m282(&mut rig.machine, Pieces::All).is_ok());
    // Collinear marks are a math error, not NaN.
    let mut line = Rig::new();
    line.world().marks = (0..4).map(|i| Point2::new(f64::from(i), 0.0)).collect();
    line.module.m280(&mut line.machine, RunMode::Rectangle).expect("m280");
    capture_all(&mut line, &[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (3.0, 0.0)]);
    assert!(matches!(line.module.m282(&mut line.machine, Pieces::All), Err(VisionError::Math(_))));
}

#[test]
fn partial_modes_emit_one_piece_in_the_same_four_lines() {
    let mut rig = rig_with_part();
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
    capture_all(&mut rig, &PART);
    let shift = rig.module.m282(&mut rig.machine, Pieces::Shift).expect("P1").report.chain;
    assert_eq!((shift.rotation_deg, shift.scale), (0.0, Vector2::new(1.0, 1.0)));
    let part = true_part();
    let centroid_shift = part.apply(Point2::new(3.0, 2.0)) - Point2::new(3.0, 2.0);
    assert!((shift.shift - centroid_shift).norm() < 1e-12);
    let rot = rig.module.m282(&mut rig.machine, Pieces::Rotation).expect("P2");
    assert!((rot.report.chain.rotation_deg - 0.4).abs() < 1e-9);
    assert_eq!(rot.report.chain.shift, Vector2::zeros());
    assert_eq!(rot.gcode.len(), 4);
    assert_eq!(rot.gcode[3], "G51 X1.0000000000 Y1.0000000000");
    let scale = rig.module.m282(&mut rig.machine, Pieces::Scale).expect("P3").report.chain;
    assert!((scale.scale.x - 1.001 * 0.4f64.to_radians().cos()).abs() < 1e-6);
    assert!((scale.apply(Point2::new(3.0, 2.0)) - Point2::new(3.0, 2.0)).norm() < 1e-12);
}

#[test]
fn quality_gates_refuse_bad_fits_and_zero_disables_them() {
    // Scale 3 % off: refused by the default 2 % gate.
    let scaled = AlignmentChain { scale: Vector2::new(1.03, 1.03), ..AlignmentChain::IDENTITY };
    let world =
        World { marks: PART.iter().map(|(x, y)| scaled.apply(Point2::new(*x, *y))).collect(), ..World::default() };
    let mut rig = Rig::with_world(world);
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
    capture_all(&mut rig, &PART);
    let before = rig.module.params().clone();
    let e = rig.module.m282(&mut rig.machine, Pieces::All).expect_err("scale gate");
    assert!(e.to_string().contains("VisionFitMaxScaleDev"), "{e}");
    assert!(e.to_string().contains("wrong mark"), "{e}");
    assert_eq!(rig.module.params(), &before);
    rig.module.set_param("VisionFitMaxScaleDev", 0.0).expect("disable");
    assert!(rig.module.m282(&mut rig.machine, Pieces::All).is_ok());

    // Shift 1.5 in (the manual's "within roughly two inches") passes the default 2.5 in gate,
    // not a 1.2 in one.
    let shifted = AlignmentChain { shift: Vector2::new(1.5, 0.0), ..AlignmentChain::IDENTITY };
    let world =
        World { marks: PART.iter().map(|(x, y)| shifted.apply(Point2::new(*x, *y))).collect(), ..World::default() };
    let mut rig = Rig::with_world(world);
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
    capture_all(&mut rig, &PART);
    assert!(rig.module.m282(&mut rig.machine, Pieces::All).is_ok());
    rig.module.set_param("VisionFitMaxShift", 1.2).expect("set");
    let e = rig.module.m282(&mut rig.machine, Pieces::All).expect_err("shift gate");
    assert!(e.to_string().contains("VisionFitMaxShift"), "{e}");

    // One mark 0.05 in off: worst residual over 0.020 in.
    let mut marks: Vec<_> = PART.iter().map(|(x, y)| Point2::new(*x, *y)).collect();
    marks[2] += Vector2::new(0.05, 0.0);
    let mut rig = Rig::with_world(World { marks, ..World::default() });
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
    capture_all(&mut rig, &PART);
    let e = rig.module.m282(&mut rig.machine, Pieces::All).expect_err("residual gate");
    assert!(e.to_string().contains("VisionFitMaxResidual"), "{e}");
    assert_eq!(rig.module.telemetry().run_active(), 1);
}

#[test]
fn a_similarity_fit_of_a_part_stretched_in_x_is_refused_with_advice() {
    // 0.5 % large in X only: a similarity fit would miss by ~0.01 in at the corners.
    let stretched = |(x, y): (f64, f64)| Point2::new(x * 1.005, y);
    let mut rig = Rig::with_world(World { marks: PART.iter().copied().map(stretched).collect(), ..World::default() });
    rig.module.m280(&mut rig.machine, RunMode::Similarity).expect("m280");
    capture_all(&mut rig, &PART);
    let e = rig.module.m282(&mut rig.machine, Pieces::All).expect_err("axis scale gate");
    assert!(e.to_string().contains("VisionFitMaxAxisScaleError") && e.to_string().contains("M280 P4"), "{e}");
    // The same part in rectangle mode follows the stretch.
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
    capture_all(&mut rig, &PART);
    let fit = rig.module.m282(&mut rig.machine, Pieces::All).expect("rectangle").report.fit;
    assert!((fit.transform.scale.x - 1.005).abs() < 1e-9, "{fit:?}");
    // A uniform 0.5 % is what a similarity fit is for.
    let grown = |(x, y): (f64, f64)| Point2::new(x * 1.005, y * 1.005);
    let mut rig = Rig::with_world(World { marks: PART.iter().copied().map(grown).collect(), ..World::default() });
    rig.module.m280(&mut rig.machine, RunMode::Similarity).expect("m280");
    capture_all(&mut rig, &PART);
    assert!(rig.module.m282(&mut rig.machine, Pieces::All).is_ok());
}

#[test]
fn a_slipped_mark_among_six_is_dropped_and_reported() {
    let nominal = [(0.0, 0.0), (3.0, 0.0), (6.0, 0.0), (6.0, 4.0), (3.0, 4.0), (0.0, 4.0)];
    let part = true_part();
    let mut marks: Vec<_> = nominal.iter().map(|(x, y)| part.apply(Point2::new(*x, *y))).collect();
    marks[4] += Vector2::new(0.03, -0.04);
    let mut rig = Rig::with_world(World { marks, ..World::default() });
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
    capture_all(&mut rig, &nominal);
    let a = rig.module.m282(&mut rig.machine, Pieces::All).expect("m282").report;
    let dropped = a.dropped.expect("mark 5 dropped");
    assert_eq!(dropped.mark, 5);
    assert!((dropped.residual - 0.05).abs() < 1e-6, "{dropped:?}");
    assert_eq!(a.fit.len, 5);
    assert!(a.max_residual < 1e-9 && (a.residuals[4].norm() - 0.05).abs() < 1e-6, "{a:?}");
    assert!((a.chain.apply(Point2::new(6.0, 4.0)) - part.apply(Point2::new(6.0, 4.0))).norm() < 1e-9);
    // Disabled: the slip is fitted with the others, pulls the fit and trips the residual gate.
    rig.module.set_param("VisionOutlierFactor", 0.0).expect("disable");
    let e = rig.module.m282(&mut rig.machine, Pieces::All).expect_err("residual gate");
    assert!(e.to_string().contains("VisionFitMaxResidual"), "{e}");
}

#[test]
fn every_fit_predicts_its_error_from_the_camera_noise_and_the_residuals() {
    let mut rig = Rig::new();
    // Read in one shot: no camera move, so no height term (tested in `height_is_measured_…`).
    rig.module.set_param("VisionRecenterPasses", 0).expect("set");
    rig.world().marks = PART.iter().map(|(x, y)| true_part().apply(Point2::new(*x, *y))).collect();
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
    capture_all(&mut rig, &PART);
    let a = rig.module.m282(&mut rig.machine, Pieces::All).expect("m282").report;
    let k = rig.module.params().cal_k().singular_values().max();
    let p = a.predicted;
    // Exact marks: the camera's 0.1 px is the noise.
    assert!((p.camera_noise - 0.1 * k).abs() < 1e-15 && p.noise == p.camera_noise, "{p:?}");
    assert!(p.sigma > 0.0 && p.bound99 > 2.0 * p.sigma, "{p:?}");
    let t = rig.module.telemetry();
    assert_eq!((t.run_predicted_sigma(), t.run_predicted_bound()), (p.sigma, p.bound99));
    // Twice the noise, twice the prediction.
    rig.module.set_param("VisionCameraNoisePx", 0.2).expect("set");
    let q = rig.module.m282(&mut rig.machine, Pieces::All).expect("m282").report.predicted;
    assert!((q.bound99 / p.bound99 - 2.0).abs() < 1e-9, "{p:?} {q:?}");
}

/// The lens's uncertainty widens the prediction by what it moves each capture: nothing at the
/// optical centre, more the farther out the marks were read.
#[test]
fn the_lens_uncertainty_widens_the_prediction_of_marks_read_off_centre() {
    let predicted = |focal: f64, sigma: f64, at: Vector2<f64>| {
        let mut rig = Rig::new();
        rig.module.set_param("VisionRecenterPasses", 0).expect("set");
        rig.module.set_param("VisionLensFocalPx", focal).expect("set");
        rig.module.set_param("VisionLensK1Sigma", sigma).expect("set");
        rig.world().marks = PART.iter().map(|(x, y)| Point2::new(*x, *y) + at).collect();
        rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
        capture_all(&mut rig, &PART);
        rig.module.m282(&mut rig.machine, Pieces::All).expect("m282").report.predicted.bound99
    };
    let off = Vector2::new(0.6, 0.4);
    let (plain, lens) = (predicted(0.0, 0.0, off), predicted(3000.0, 0.05, off));
    assert!(lens > 1.1 * plain, "{lens} vs {plain}");
    assert!(predicted(3000.0, 0.0, off) == plain, "no σ, no widening");
    let centred = predicted(3000.0, 0.05, Vector2::zeros());
    assert!((centred - predicted(0.0, 0.0, Vector2::zeros())).abs() < 1e-12, "nothing at the centre");
}

#[test]
fn k_in_inches_reports_millimetres_under_g21() {
    let mut rig = Rig::new();
    rig.world().marks = vec![Point2::new(1.1, 0.9)];
    rig.module.set_param("VisionRecenterPasses", 0).expect("one shot");
    rig.run(&["G21".to_string()]);
    rig.go(25.4, 25.4);
    let c = rig.module.m281(&mut rig.machine, false).expect("capture").report;
    assert_eq!(c.unit, LengthUnit::Millimetre);
    assert!((c.observed - Point2::new(27.94, 22.86)).norm() < 1e-9, "{c:?}");
    assert!((c.width - 12.7).abs() < 1e-9);
    assert!((rig.module.telemetry().last_offset_x() - 2.54).abs() < 1e-9);
    // And K calibrated in mm, machine in inches.
    let mut rig = Rig::new();
    rig.world().marks = vec![Point2::new(1.1, 0.9)];
    rig.module.params.set_cal_k(Matrix2::new(0.00203 * 25.4, 0.0, 0.0, 0.00203 * 25.4)).expect("k");
    rig.module.set_param("VisionCal_Units", "mm").expect("mm");
    rig.go(1.0, 1.0);
    let c = rig.module.m281(&mut rig.machine, false).expect("capture").report;
    assert!((c.observed - Point2::new(1.1, 0.9)).norm() < 1e-12);
}

#[test]
fn failed_captures_change_nothing_but_the_last_status() {
    let mut rig = rig_with_part();
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
    capture_all(&mut rig, &PART[..2]);
    let block = |rig: &Rig| (500..540).map(|a| rig.machine.pound(a).expect("read")).collect::<Vec<_>>();
    let pounds = block(&rig);
    let dots = rig.module.dots().to_vec();

    // NG.
    rig.world().script.push_back(Ok(Reading { judgment: Judgment::Ng, ..Reading::position(1.0, 1.0) }));
    let e = rig.module.m281(&mut rig.machine, false).expect_err("NG");
    assert_eq!(e, VisionError::NoMark { reason: None });
    assert!(e.to_string().starts_with("NG / no mark found"));
    assert_eq!(rig.module.telemetry().last_judgment(), 0);
    assert_eq!(rig.module.telemetry().last_status(), e.to_string());
    // The previous mark's offsets and size are not left on the DRO.
    let t = rig.module.telemetry();
    assert_eq!(
        (t.last_offset_x(), t.last_offset_y(), t.last_offset_px_x(), t.last_width(), t.last_score()),
        (0.0, 0.0, 0.0, 0.0, 0.0)
    );
    // Count 0.
    rig.world().script.push_back(Ok(Reading { count: Some(0), ..Reading::position(1.0, 1.0) }));
    assert_eq!(rig.module.m281(&mut rig.machine, false).map(|_| ()), Err(VisionError::NoMark { reason: None }));
    // A pound write fails half-way: the writes already made are undone.
    rig.world().fail_pound = Some(500 + 8 * 3 + 2);
    rig.go(6.0, 4.0);
    assert!(matches!(rig.module.m281(&mut rig.machine, false), Err(VisionError::Machine(_))));
    rig.world().fail_pound = None;
    assert_eq!(block(&rig), pounds);
    assert_eq!(rig.module.dots(), &dots[..]);
    assert_eq!(rig.module.telemetry().run_dot_count(), 2);

    // Zero K: refused before the trigger.
    let triggers = rig.world().triggers;
    rig.module.params.set_cal_k(Matrix2::zeros()).expect("zero");
    let e = rig.module.m281(&mut rig.machine, false).expect_err("zero K");
    assert_eq!(e, VisionError::NotCalibrated);
    assert_eq!(
        e.to_string(),
        "K matrix is zero — run M283 to calibrate first (M283 C1, on LinuxCNC M283 P1, or M283 Q)"
    );
    assert_eq!(rig.module.telemetry().last_status(), e.to_string(), "a refusal before the trigger is shown too");
    assert_eq!(rig.world().triggers, triggers);
    assert_eq!(block(&rig), pounds);
}

#[test]
fn m281_recentres_over_a_mark_seen_off_centre() {
    let mut rig = Rig::new();
    rig.world().marks = vec![Point2::new(1.1, 0.9)];
    rig.go(1.0, 1.0);
    let r = rig.module.m281(&mut rig.machine, false).expect("capture");
    let c = r.report;
    assert!((c.observed - Point2::new(1.1, 0.9)).norm() < 1e-9, "{c:?}");
    assert_eq!(c.commanded, Point2::new(1.0, 1.0), "the dot keeps where the program put the camera");
    let recentred = c.recentred.expect("re-centred");
    assert_eq!(recentred.passes, 1);
    assert!((recentred.first_px.norm() - 0.1f64.hypot(0.1) / 0.00203).abs() < 1e-6, "{recentred:?}");
    assert!(c.centred_px.norm() < 1e-6, "{c:?}");
    // Over the mark, then back where the program put the camera, in the program's own modes.
    let want = ["G91 G0 X0.1000000 Y-0.1000000", "G90", "G90 G0 X1.0000000 Y1.0000000"];
    assert_eq!(r.gcode, want.map(str::to_string));
    assert!((rig.machine.program_position().expect("a position") - Point2::new(1.0, 1.0)).norm() < 1e-9);
    assert!(rig.world().saved_modal.is_empty(), "saved and restored");
    // A program in G91 stays in G91.
    rig.world().absolute = false;
    let r = rig.module.m281(&mut rig.machine, false).expect("capture");
    assert!(r.report.recentred.is_some());
    assert!(!rig.world().absolute, "the program's G91 is back");
    // A refused re-centring move: the capture fails, and the modes are put back all the same.
    rig.world().fail_gcode_after = Some(0);
    let e = rig.module.m281(&mut rig.machine, false).expect_err("e-stop");
    assert!(matches!(e, VisionError::Machine(_)), "{e}");
    assert!(!rig.world().absolute && rig.world().saved_modal.is_empty());
    rig.world().fail_gcode_after = None;
    // Within the tolerance: no move.
    rig.module.set_param("VisionRecenterTolerance", 100.0).expect("set");
    rig.go(1.0, 1.0);
    let r = rig.module.m281(&mut rig.machine, false).expect("capture");
    assert_eq!((r.report.recentred, r.gcode.len()), (None, 0));
}

#[test]
fn the_mark_size_and_the_pixel_range_warn_about_height_and_resolution() {
    let mut rig = Rig::new();
    rig.world().marks = vec![Point2::new(1.0, 1.0)];
    rig.go(1.0, 1.0);
    // The fake camera's mark is 0.5 in: within 2 % of 0.5, not of 0.52.
    rig.module.set_param("VisionMarkDiameter", 0.5).expect("set");
    assert_eq!(rig.module.m281(&mut rig.machine, false).expect("capture").report.warning, None);
    rig.module.set_param("VisionMarkDiameter", 0.52).expect("set");
    let w = rig.module.m281(&mut rig.machine, false).expect("capture").report.warning.expect("height warning");
    assert!(w.contains("-3.85 %") && w.contains("4.0 % farther from the camera"), "{w}");
    assert!(rig.module.telemetry().last_status().starts_with("OK (warning: the mark measures"));
    rig.module.set_param("VisionMarkDiameter", 0.0).expect("off");
    // The profile says 1000 × 1000 but the camera reports beyond it (0.3 in ≈ 148 px right
    // of its own 1776-pixel centre).
    rig.module.set_param("VisionCameraResX", 1000).expect("set");
    rig.module.set_param("VisionCameraResY", 1000).expect("set");
    rig.module.set_param("VisionRecenterPasses", 0).expect("one shot");
    rig.world().marks = vec![Point2::new(1.3, 1.0)];
    let w = rig.module.m281(&mut rig.machine, false).expect("capture").report.warning.expect("resolution warning");
    assert!(w.contains("outside the 1000 x 1000 image") && w.contains("VisionCameraResX"), "{w}");
    // Re-centring on: a reading outside the image is no distance to move by.
    rig.module.set_param("VisionRecenterPasses", 2).expect("re-centre");
    let r = rig.module.m281(&mut rig.machine, false).expect("capture");
    assert_eq!((r.report.recentred, r.gcode.len()), (None, 0), "{:?}", r.gcode);
    assert!(r.report.warning.is_some_and(|w| w.contains("outside the 1000 x 1000 image")));
}

/// Issue 28: the part 4 % farther from the camera than at calibration (every pixel spans 4 %
/// more). The first mark, seen about 33 px off centre, is probed; the run measures +4 % exactly
/// (no noise), M282 corrects the captures so the fit lands on the part, warns with the manual's
/// advice, and the mark size agrees. With the correction off the captures are used as read and
/// the prediction, widened by the whole measured error, still holds the true error.
#[test]
fn height_is_measured_corrected_and_reported() {
    let mut rig = Rig::new();
    rig.world().marks = PART.iter().map(|(x, y)| true_part().apply(Point2::new(*x, *y))).collect();
    rig.world().optics.pitch_in *= 1.04;
    rig.module.set_param("VisionMarkDiameter", 0.5).expect("set");
    // A probe longer than the default, so that the first mark (≈ 33 px off) is probed.
    rig.module.set_param("VisionHeightProbePx", 200.0).expect("set");
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
    rig.go(0.0, 0.0);
    let first = rig.module.m281(&mut rig.machine, false).expect("capture").report;
    let moved = first.recentred.expect("moved");
    assert!(moved.probe && moved.passes == 1 && moved.first_px.norm() < 50.0, "{moved:?}");
    assert_eq!(first.centred_px, moved.first_px, "the reading nearer the centre is the capture");
    capture_all(&mut rig, &PART[1..]);
    let a = rig.module.m282(&mut rig.machine, Pieces::All).expect("m282").report;
    let h = a.height.clone().expect("measured");
    assert!((h.change_pct - 4.0).abs() < 1e-6 && h.corrected && h.sigma_pct > 0.0, "{h:?}");
    assert!((h.change - 0.24).abs() < 1e-6, "6 in × 4 %: {h:?}");
    assert!((h.mark_size_pct.expect("configured") - 4.0).abs() < 1e-6, "{h:?}");
    let w = h.warning.expect("above 1 %");
    assert!(w.contains("farther from the camera") && w.contains("re-run M283 C1 at this height"), "{w}");
    assert!(!w.contains("disagree"), "{w}");
    for (x, y) in PART {
        let p = Point2::new(x, y);
        assert!((a.chain.apply(p) - true_part().apply(p)).norm() < 1e-9, "corrected: exact at {p:?}");
    }
    let t = rig.module.telemetry();
    assert_eq!(
        (t.run_height_change_pct(), t.run_height_change(), t.run_height_sigma_pct()),
        (h.change_pct, h.change, h.sigma_pct)
    );
    assert_eq!(t.last_status(), format!("OK (warning: {w})"));

    // Off: the captures as read; the bound is widened by the whole +4 %.
    rig.module.set_param("VisionHeightCorrection", false).expect("set");
    let b = rig.module.m282(&mut rig.machine, Pieces::All).expect("m282").report;
    assert!(!b.height.as_ref().expect("measured").corrected);
    let worst = PART
        .iter()
        .map(|(x, y)| (b.chain.apply(Point2::new(*x, *y)) - true_part().apply(Point2::new(*x, *y))).norm())
        .fold(0.0, f64::max);
    assert!(worst > 1e-5 && worst < b.predicted.bound99, "uncorrected error {worst} within {:?}", b.predicted);
    assert!(b.predicted.bound99 > a.predicted.bound99);
}
