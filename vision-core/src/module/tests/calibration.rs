//! M283 against a fake camera with a known true geometry: every mounting, both units.

use std::path::Path;

use vision_math::chain::fixed;
use vision_math::{AlignmentChain, LengthUnit, Matrix2, Point2, Remap, Vector2};

use super::fakes::{Optics, Rig, World};
use crate::calibrate::{CalReport, Calibrate, SheetReport};
use crate::driver::Reading;
use crate::error::VisionError;
use crate::machine::Machine;
use crate::profile::{ProfileFs, ProfileStore, StdFs};
use crate::sheets::cal_sheet;

/// A camera mounted `quarter_turns` × 90° + 1.5° round, optionally mirrored, with pixels 1 %
/// longer along the sensor's y axis.
fn tilted(quarter_turns: u8, mirrored: bool) -> Optics {
    Optics {
        rotation_deg: 1.5 + 90.0 * f64::from(quarter_turns),
        pitch_in: Vector2::new(0.00203, 0.00203 * 1.01),
        ..Optics::square(0.0, mirrored)
    }
}

/// The K a correct calibration of `optics` holds, inches per pixel.
fn true_k(optics: Optics) -> Matrix2<f64> {
    optics.calibration().0
}

/// The sheet taped down rotated 0.3° (and optionally mis-printed) about the spindle zero.
fn sheet_marks(rotation_deg: f64, print: Vector2<f64>) -> Vec<Point2<f64>> {
    let pose = AlignmentChain { scale: print, rotation_deg, ..AlignmentChain::IDENTITY };
    cal_sheet(1).expect("sheet 1").dots(LengthUnit::Inch).into_iter().map(|p| pose.apply(p)).collect()
}

const CAMERA: Vector2<f64> = Vector2::new(3.2, -1.7);

/// A rig whose camera (`optics`, 3.2/−1.7 in from the spindle) sits with
/// dot 1 somewhere in view; the camera tool's table offset is `o0` (inches).
fn sheet_rig(optics: Optics, units: LengthUnit, o0: Vector2<f64>, marks: Vec<Point2<f64>>) -> Rig {
    let dot1 = marks[0];
    let start = dot1 + Vector2::new(0.3, -0.2) + o0 - CAMERA;
    let mut world = World { optics, cam_offset: CAMERA, units, program: start, marks, ..World::default() };
    world.offsets.insert(98, o0);
    let mut rig = Rig::with_world(world);
    // Start uncalibrated with the default remap flags.
    rig.module.params.set_cal_k(Matrix2::zeros()).expect("zero");
    rig.module.params.set_remap(Remap::IDENTITY);
    rig
}

/// The sheet 0.3° on the table, identity flags, the camera tool's offset (3, −1.5) in, inches.
fn standard_rig() -> Rig {
    sheet_rig(tilted(0, false), LengthUnit::Inch, Vector2::new(3.0, -1.5), sheet_marks(0.3, Vector2::new(1.0, 1.0)))
}

/// `rig` with a profile store in place of none.
fn with_store(rig: &mut Rig, store: ProfileStore) {
    let module = std::mem::replace(&mut rig.module, crate::module::VisionModule::new(Default::default()));
    rig.module = module.with_profile(store);
}

fn sheet_report(r: CalReport) -> SheetReport {
    match r {
        CalReport::Sheet(s) => s,
        CalReport::Quick(q) => panic!("expected a sheet report, got {q:?}"),
    }
}

#[test]
fn sheet_walk_recovers_k_and_offset_for_all_eight_mountings() {
    for i in 0..8u8 {
        let optics = tilted(i / 2, i % 2 == 1);
        let units = if i % 2 == 0 { LengthUnit::Inch } else { LengthUnit::Millimetre };
        let f = LengthUnit::Inch.factor_to(units);
        let o0 = if i % 3 == 0 { Vector2::zeros() } else { Vector2::new(3.0, -1.5) };
        let mut rig = sheet_rig(optics, units, o0, sheet_marks(0.3, Vector2::new(1.0, 1.0)));
        let r = rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect("calibrates");
        // The reply lists exactly the lines the module ran on the machine.
        assert_eq!(r.gcode, rig.world().log);
        let rep = sheet_report(r.report);
        let p = rig.module.params();
        // The camera's physics: K·R maps centred pixels onto the table.
        let kr = p.cal_k() * p.remap().matrix();
        assert!(
            (kr - optics.table_per_pixel() * f).amax() < 1e-9,
            "mounting {i}: K·R {kr} vs {}",
            optics.table_per_pixel()
        );
        // And the remap leaves K turned by the mount's 1.5° only (positive diagonal).
        assert_eq!(p.remap(), optics.calibration().1, "mounting {i}");
        assert!(p.cal_k()[(0, 0)] > 0.0 && p.cal_k()[(1, 1)] > 0.0, "mounting {i}: {}", p.cal_k());
        assert!((p.cal_k() - true_k(optics) * f).amax() < 1e-9, "mounting {i}: K {}", p.cal_k());
        assert_eq!(p.cal_units(), units);
        let offset = rig.machine.tool_offset(98).expect("tool");
        assert!((offset - CAMERA * f).amax() < 1e-9, "mounting {i}: offset {offset:?}");
        assert!((rep.offset_written - offset).amax() < 1e-12, "mounting {i}");
        assert!((rep.offset_before - o0 * f).amax() < 1e-12);
        assert!((rep.sheet_rotation_deg - 0.3).abs() < 1e-9);
        assert!((rep.sheet_scale - Vector2::new(1.0, 1.0)).amax() < 1e-9);
        assert!(rep.verify_max < 1e-9 && rep.verify_rms < 1e-9 && rep.walk_rms < 1e-9 && rep.k_rms < 1e-9);
        assert_eq!(rep.verify.len(), 5);
        assert!((rep.camera_rotation_deg - 1.5).abs() < 0.3);
        assert!((rep.scale.x - true_k(optics).column(0).norm() * f).abs() < 1e-12 * f, "mounting {i}");
        assert_eq!(p.cal_date(), "2023-11-14T23:13:20+01:00");
        assert_eq!(rig.module.telemetry().last_status(), "OK");
        // The DRO shows the walk's last trigger (the verify re-walk's dot 5, read through the
        // new K): a mark, its size, almost on the camera axis.
        let t = rig.module.telemetry();
        assert_eq!(t.last_judgment(), 1, "mounting {i}");
        assert!(t.last_width() > 0.0 && t.last_score() > 0.0, "mounting {i}: {t:?}");
        assert!(t.last_offset_x().hypot(t.last_offset_y()) < 0.05 * f, "mounting {i}: {t:?}");
        // With the new offset the camera lands on what it is commanded to: dot 5 at 0, 0.
        assert!((rig.world().camera_axis() - Point2::origin()).norm() < 1e-9);
        // The bump was 0.1 in (2.54 mm) and settling was dwelt after every move.
        assert!((rep.axis.bump - 0.1 * f).abs() < 1e-12);
        assert!(rig.world().dwell_s > 0.0);
        assert!(rig.world().log.iter().any(|l| l.starts_with("G91 G0 X")));
        // The verify walk ran before the offset was written, so it commanded dot 5 (at 0, 0)
        // compensated by o₀ − a (current units).
        let b = (o0 - CAMERA) * f;
        let verify_5 = format!("G90 G0 X{} Y{}", fixed(b.x, 7), fixed(b.y, 7));
        assert_eq!(rig.world().log.iter().rfind(|l| l.starts_with("G90 G0 X")), Some(&verify_5));
    }
}

#[test]
fn a_square_sheet_and_a_mis_printed_sheet_do_not_fool_k() {
    // Square sheet, square camera: every dot lands on the same pixel; the probes carry K.
    let square_k = Matrix2::new(0.00203, 0.0, 0.0, 0.00203);
    let mut rig = sheet_rig(
        Optics::square(0.0, true),
        LengthUnit::Inch,
        Vector2::zeros(),
        sheet_marks(0.0, Vector2::new(1.0, 1.0)),
    );
    rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect("square sheet");
    assert!((rig.module.params().cal_k() - square_k).amax() < 1e-12);

    // Printed 1 % short in Y: K stays true, the sheet's scale shows the misprint.
    let mut rig =
        sheet_rig(tilted(0, true), LengthUnit::Inch, Vector2::zeros(), sheet_marks(-0.2, Vector2::new(1.0, 0.99)));
    let rep = sheet_report(rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect("cal").report);
    assert!((rig.module.params().cal_k() - true_k(tilted(0, true))).amax() < 1e-12);
    assert!((rep.sheet_scale - Vector2::new(1.0, 0.99)).amax() < 1e-9, "{:?}", rep.sheet_scale);
    assert!((rep.sheet_rotation_deg + 0.2).abs() < 1e-9);
    assert!((rig.machine.tool_offset(98).expect("tool") - CAMERA).amax() < 1e-9);
}

#[test]
fn quick_calibration_for_plain_and_swapped_mountings() {
    // Worked by hand from the optics: a mirrored image square to the table needs InvertY; a
    // camera turned 90° counter-clockwise sees table +X along its −y and +Y along its +x, so
    // SwapXY with InvertX, and its x pitch becomes K22.
    let k = Matrix2::new(0.00203, 0.0, 0.0, 0.00207);
    for (optics, remap) in [
        (
            Optics { pitch_in: Vector2::new(0.00203, 0.00207), ..Optics::square(0.0, true) },
            Remap { swap_xy: false, invert_x: false, invert_y: true },
        ),
        (
            Optics { pitch_in: Vector2::new(0.00207, 0.00203), ..Optics::square(90.0, false) },
            Remap { swap_xy: true, invert_x: true, invert_y: false },
        ),
    ] {
        let mut world = World { optics, marks: vec![Point2::new(0.2, 0.1)], ..World::default() };
        world.program = Point2::origin();
        let mut rig = Rig::with_world(world);
        rig.module.params.set_cal_k(Matrix2::zeros()).expect("zero");
        let r = rig.module.m283(&mut rig.machine, Calibrate::Quick { diameter: 0.5 }).expect("quick");
        let CalReport::Quick(q) = r.report else { panic!("quick report") };
        assert_eq!(rig.module.params().remap(), remap);
        assert!((rig.module.params().cal_k() - k).amax() < 1e-12, "{remap:?}: {}", rig.module.params().cal_k());
        assert!(q.size_error < 1e-12 && q.bump_error < 1e-12);
        assert!((q.confirm_size - Vector2::new(0.5, 0.5)).amax() < 1e-12);
        // Moved back to where it started.
        assert_eq!(rig.machine.program_position().expect("a position"), Point2::origin());
        assert_eq!(rig.machine.tool_offset(98).expect("tool"), Vector2::zeros());
    }
    // A camera job without width/height cannot do Q.
    let mut rig = Rig::with_world(World { marks: vec![Point2::new(0.2, 0.1)], ..World::default() });
    let k_before = rig.module.params().cal_k();
    for (x, y) in [(988.0, 938.0), (938.7, 938.0), (938.7, 987.3), (988.0, 938.0)] {
        rig.world().script.push_back(Ok(Reading::position(x, y)));
    }
    let e = rig.module.m283(&mut rig.machine, Calibrate::Quick { diameter: 0.5 }).expect_err("no size");
    assert!(e.to_string().contains("width and height"), "{e}");
    assert_eq!(rig.module.params().cal_k(), k_before);
}

fn assert_untouched(rig: &Rig, start: Point2<f64>) {
    let p = rig.module.params();
    assert_eq!(p.cal_k(), Matrix2::zeros());
    assert_eq!(p.remap(), Remap::IDENTITY);
    assert_eq!(p.cal_date(), "");
    assert_eq!(rig.machine.tool_offset(98).expect("tool"), Vector2::new(3.0, -1.5));
    assert!((rig.machine.program_position().expect("a position") - start).norm() < 1e-6);
}

#[test]
fn a_camera_tool_missing_from_the_table_is_an_unknown_tool_and_moves_nothing() {
    let mut rig = standard_rig();
    let start = rig.machine.program_position().expect("a position");
    rig.world().offsets.remove(&98);
    let e = rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect_err("no tool 98");
    let VisionError::Machine(machine) = &e else { panic!("{e}") };
    assert_eq!(machine.kind(), crate::MachineErrorKind::UnknownTool, "{e}");
    assert_eq!(rig.module.params().cal_k(), Matrix2::zeros());
    // Only M283's return to its start ran: the walk failed before its first move.
    let log = rig.world().log.clone();
    assert_eq!(log.len(), 1, "{log:?}");
    assert!((rig.machine.program_position().expect("a position") - start).norm() < 1e-6);
}

#[test]
fn a_failed_walk_restores_k_flags_offset_and_position() {
    let mut marks = sheet_marks(0.3, Vector2::new(1.0, 1.0));
    marks.remove(2); // dot 3 is missing
    let mut rig = sheet_rig(tilted(0, false), LengthUnit::Inch, Vector2::new(3.0, -1.5), marks);
    let start = rig.machine.program_position().expect("a position");
    let e = rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect_err("lost dot 3");
    assert!(matches!(e, VisionError::Calibration { .. }), "{e}");
    assert!(e.to_string().contains("lost the mark"), "{e}");
    assert!(e.to_string().ends_with("the tool offsets were left unchanged"), "{e}");
    assert_untouched(&rig, start);
    assert_eq!(rig.module.telemetry().last_status(), e.to_string());
    // The trigger that lost the mark is on the DRO: no mark, nothing stale.
    let t = rig.module.telemetry();
    assert_eq!((t.last_judgment(), t.last_width(), t.last_offset_x()), (0, 0.0, 0.0), "{t:?}");
}

#[test]
fn a_failed_verify_writes_nothing() {
    let mut rig = standard_rig();
    let start = rig.machine.program_position().expect("a position");
    // 3 bumps + 5 × (5 + 5) walk moves = the verify's first move fails.
    rig.world().fail_gcode_after = Some(3 + 25);
    let e = rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect_err("e-stop");
    assert!(matches!(e, VisionError::Machine(_)), "{e}");
    rig.world().fail_gcode_after = None;
    // The restore move could not run while the machine refused G-code; run it now.
    let p = rig.machine.program_position().expect("a position");
    assert!((p - start).norm() > 1e-3);
    let p = rig.module.params();
    assert_eq!(p.cal_k(), Matrix2::zeros());
    assert_eq!(rig.machine.tool_offset(98).expect("tool"), Vector2::new(3.0, -1.5));
}

/// A profile path in a fresh folder of this test's own (a save reads and locks beside it).
fn broken_disk_path(test: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("vision-core-broken-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("tmp");
    dir.join("vision.toml")
}

/// Fails every save.
struct BrokenDisk;
impl ProfileFs for BrokenDisk {
    fn write_synced(&mut self, _: &Path, _: &[u8]) -> std::io::Result<()> {
        Err(std::io::Error::other("read-only file system"))
    }
    fn rename(&mut self, a: &Path, b: &Path) -> std::io::Result<()> {
        StdFs.rename(a, b)
    }
    fn remove(&mut self, _: &Path) -> std::io::Result<()> {
        Ok(())
    }
    fn sync_dir(&mut self, _: &Path) -> std::io::Result<()> {
        Ok(())
    }
}

#[test]
fn a_failed_save_undoes_the_calibration() {
    let mut rig = standard_rig();
    let start = rig.machine.program_position().expect("a position");
    with_store(&mut rig, ProfileStore::with_fs(broken_disk_path("undo"), Box::new(BrokenDisk)));
    let e = rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect_err("save fails");
    assert!(matches!(e, VisionError::Profile { .. }), "{e}");
    assert_untouched(&rig, start);
}

#[test]
fn a_failed_save_whose_offset_restore_fails_says_what_to_set_by_hand() {
    let mut rig = standard_rig();
    with_store(&mut rig, ProfileStore::with_fs(broken_disk_path("restore"), Box::new(BrokenDisk)));
    // The offset write succeeds, the save fails, the restoring write fails.
    rig.world().fail_offset_after = Some(1);
    let e = rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect_err("save fails");
    assert!(matches!(e, VisionError::Machine(_)), "{e}");
    let text = e.to_string();
    assert!(
        text.contains("read-only file system") && text.contains("set its X/Y offset back to X3.000000 Y-1.500000"),
        "{text}"
    );
    // The module kept its calibration; the machine kept the new offset (that is what the message is for).
    assert_eq!(rig.module.params().cal_k(), Matrix2::zeros());
    assert!((rig.machine.tool_offset(98).expect("tool") - CAMERA).amax() < 1e-9);
    assert_eq!(rig.module.telemetry().last_status(), text);
}

#[test]
fn a_refused_offset_write_commits_nothing() {
    let mut rig = standard_rig();
    let dir = std::env::temp_dir().join(format!("vision-core-cal-offset-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("tmp");
    let path = dir.join("vision.toml");
    with_store(&mut rig, ProfileStore::new(&path));
    let start = rig.machine.program_position().expect("a position");
    rig.world().fail_offset_after = Some(0);
    let e = rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect_err("tool table locked");
    assert!(e.to_string().contains("tool table is locked"), "{e}");
    assert_untouched(&rig, start);
    assert!(!path.exists(), "the profile is not written when the tool table refuses");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn refusals_before_any_motion() {
    let marks = sheet_marks(0.0, Vector2::new(1.0, 1.0));
    let mut rig = sheet_rig(tilted(0, false), LengthUnit::Inch, Vector2::new(3.0, -1.5), marks);
    let m = &mut rig.machine;
    assert_eq!(
        rig.module.m283(m, Calibrate::Sheet { n: 7 }).map(|_| ()),
        Err(VisionError::UnknownSheet { sheet: 7, known: "1".into() })
    );
    // An alignment the module's M282 left (a Mach4 machine reports only that one is active).
    let turned = AlignmentChain { rotation_deg: 0.5, ..AlignmentChain::IDENTITY };
    rig.world().alignment = Some(turned);
    rig.module.alignment = Some(turned);
    assert_eq!(
        rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).map(|_| ()),
        Err(VisionError::AlignmentActive)
    );
    rig.world().alignment = Some(AlignmentChain::IDENTITY);
    rig.module.alignment = Some(AlignmentChain::IDENTITY);
    rig.world().tool = 1;
    assert_eq!(
        rig.module.m283(&mut rig.machine, Calibrate::Quick { diameter: 0.5 }).map(|_| ()),
        Err(VisionError::WrongTool { camera: 98, active: 1 })
    );
    rig.module.params.config.enabled = false;
    assert_eq!(rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).map(|_| ()), Err(VisionError::NotEnabled));
    assert_eq!(rig.world().triggers, 0);
    assert!(rig.world().log.is_empty());
}

#[test]
fn a_mark_that_does_not_move_fails_the_axis_detect() {
    let mut rig = sheet_rig(
        tilted(0, false),
        LengthUnit::Inch,
        Vector2::new(3.0, -1.5),
        sheet_marks(0.0, Vector2::new(1.0, 1.0)),
    );
    let start = rig.machine.program_position().expect("a position");
    for _ in 0..3 {
        rig.world().script.push_back(Ok(Reading::position(900.0, 900.0)));
    }
    let e = rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect_err("stuck mark");
    assert!(e.to_string().contains("axis detect"), "{e}");
    assert_untouched(&rig, start);
}

#[test]
fn pixel_noise_averages_out_in_the_least_squares_solves() {
    let marks = sheet_marks(0.3, Vector2::new(1.0, 1.0));
    let mut rig = sheet_rig(tilted(1, true), LengthUnit::Inch, Vector2::zeros(), marks);
    rig.world().noise_px = 0.5;
    let rep = sheet_report(rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect("noisy").report);
    let k = rig.module.params().cal_k();
    // ±0.5 px on 355 px probes: K within 0.2 %, offset and verify within a few thousandths.
    assert!((k - true_k(tilted(1, true))).amax() < 2e-3 * 0.00203, "{k}");
    // The lift found the optical centre (the image centre here) to within its stated noise, and
    // the offset is solved at the pixel it found: less what that pixel sees, the true one.
    let p = rig.module.params();
    let (delta, sigma) = (p.calibration.center_offset(), p.px_center_sigma_px());
    assert!(rep.centre.measured && sigma > 0.5 && delta.amax() < 4.0 * sigma, "{:?}", rep.centre);
    let kr = k * p.remap().matrix();
    assert!((rig.machine.tool_offset(98).expect("tool") - kr * delta - CAMERA).amax() < 0.003);
    assert!(rep.verify_rms < 0.005 && rep.verify_rms > 0.0, "{}", rep.verify_rms);
    assert!(rep.k_rms > 0.0);
}

#[test]
fn manual_examples_one_and_two_calibrate_then_verify_at_the_centre() {
    let marks = sheet_marks(0.3, Vector2::new(1.0, 1.0));
    let mut rig = sheet_rig(tilted(3, false), LengthUnit::Inch, Vector2::zeros(), marks);
    rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect("example 1");
    // Example 2: 4-point run over the corners, M282, then capture the centre in the aligned frame.
    rig.module.m280(&mut rig.machine, crate::module::RunMode::Rectangle).expect("M280");
    for (x, y) in [(-2.5, -4.0), (-2.5, 4.0), (2.5, 4.0), (2.5, -4.0)] {
        rig.go(x, y);
        rig.module.m281(&mut rig.machine, false).expect("M281");
    }
    let r = rig.module.m282(&mut rig.machine, crate::module::Pieces::All).expect("M282");
    assert!((r.report.chain.rotation_deg - 0.3).abs() < 1e-9);
    rig.go(0.0, 0.0);
    rig.module.m281(&mut rig.machine, false).expect("centre");
    let (x, y) = (rig.machine.pound(500).expect("#500"), rig.machine.pound(501).expect("#501"));
    assert!(x.abs() < 1e-9 && y.abs() < 1e-9, "#500 = {x}, #501 = {y}");
}

#[test]
fn the_fake_optics_follow_the_hand_worked_geometry() {
    let p = 0.00203;
    // Mirrored, square to the table: +X to the right of the image, +Y up (rows count down).
    let o = Optics::square(0.0, true);
    assert!((o.pixel(Vector2::new(p, 0.0)) - Point2::new(889.0, 888.0)).norm() < 1e-9);
    assert!((o.pixel(Vector2::new(0.0, p)) - Point2::new(888.0, 887.0)).norm() < 1e-9);
    // Turned 90° counter-clockwise, not mirrored: table +X is the sensor's −y, table +Y its +x.
    let o = Optics::square(90.0, false);
    assert!((o.pixel(Vector2::new(p, 0.0)) - Point2::new(888.0, 887.0)).norm() < 1e-9);
    assert!((o.pixel(Vector2::new(0.0, p)) - Point2::new(889.0, 888.0)).norm() < 1e-9);
    // The truth matrix maps the centred pixel back onto the offset.
    let o = tilted(2, true);
    let d = Vector2::new(0.31, -0.17);
    assert!((o.table_per_pixel() * (o.pixel(d) - Point2::from(o.centre_px)) - d).norm() < 1e-12);
}

#[test]
fn a_quick_diameter_in_the_wrong_unit_is_refused_naming_the_mix_up() {
    for (diameter, hint) in
        [(12.7, Some("a millimetre value in an inch program (Q0.5 in inches)")), (1e300, None), (0.05, None)]
    {
        let mut world = World { marks: vec![Point2::new(0.2, 0.1)], ..World::default() };
        world.program = Point2::origin();
        let mut rig = Rig::with_world(world);
        let before = rig.module.params().clone();
        let e = rig.module.m283(&mut rig.machine, Calibrate::Quick { diameter }).expect_err("wrong diameter");
        let text = e.to_string();
        assert!(text.contains("axis-detect bump"), "{text}");
        if let Some(hint) = hint {
            assert!(text.contains(hint), "{text}");
        }
        assert_eq!(rig.module.params(), &before, "nothing saved");
        assert_eq!(rig.machine.program_position().expect("a position"), Point2::origin());
    }
}

#[test]
fn an_unwritable_profile_is_found_before_the_calibration_moves() {
    let dir = std::env::temp_dir().join(format!("vision-core-m283-nowrite-{}", std::process::id()));
    let mut world = World { marks: vec![Point2::new(0.2, 0.1)], ..World::default() };
    world.program = Point2::origin();
    let mut rig = Rig::with_world(world);
    rig.module.profile = Some(crate::ProfileStore::new(dir.join("missing").join("v.toml")));
    let e = rig.module.m283(&mut rig.machine, Calibrate::Quick { diameter: 0.5 }).expect_err("cannot save");
    assert!(e.to_string().contains("create the folder"), "{e}");
    assert_eq!(rig.world().triggers, 0, "refused before the first trigger");
}

/// What a telemetry sink saw: each write, with how many triggers the camera had made by then.
type Seen = std::sync::Arc<std::sync::Mutex<Vec<(usize, crate::params::Telemetry)>>>;

/// Records every telemetry write of `rig`'s module with the trigger count at that moment.
fn watch(rig: &mut Rig) -> Seen {
    let seen: Seen = Seen::default();
    let (log, world) = (seen.clone(), rig.shared.clone());
    rig.module.set_telemetry_sink(Some(Box::new(move |t| {
        let triggers = world.lock().map_or(0, |w| w.triggers);
        log.lock().expect("log").push((triggers, t.clone()));
    })));
    seen
}

/// The DRO during M283 (SPEC §5, "written after every trigger"): each trigger is on it before
/// the next one — the axis-detect bumps of an uncalibrated camera in pixels only, every later
/// shot through the K solved so far, so a probe shot shows the mark about one probe move
/// (a fifth of the field, ≈ 0.72 in, plus up to 0.04 in from the sheet's 0.3° over the 8 in
/// between dots) off — and the end shows the last verify dot, centred.
#[test]
fn every_calibration_trigger_reaches_the_dro_as_it_happens() {
    let mut rig = standard_rig();
    let seen = watch(&mut rig);
    let r = rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect("calibrates");
    let triggers = sheet_report(r.report).triggers;
    let seen = seen.lock().expect("log").clone();
    // The write each trigger made, taken before the camera triggered again.
    let at: Vec<&crate::params::Telemetry> = (1..=triggers)
        .map(|n| &seen.iter().find(|(t, _)| *t == n).unwrap_or_else(|| panic!("trigger {n} never reached the DRO")).1)
        .collect();
    for t in &at[..3] {
        assert_eq!((t.last_judgment(), t.last_offset_x(), t.last_width()), (1, 0.0, 0.0), "no K yet: {t:?}");
        assert!(t.last_offset_px_x().hypot(t.last_offset_px_y()) > 50.0, "dot 1 sits off centre: {t:?}");
    }
    let offset = |t: &crate::params::Telemetry| t.last_offset_x().hypot(t.last_offset_y());
    // The walk's shots, 5 per dot on sheet 1's five (the lens grid's and the lift's 5 × 5
    // grids after them reach the diagonals).
    let walk_end = 3 + 5 * 5;
    let largest = at[3..walk_end].iter().map(|t| offset(t)).fold(0.0, f64::max);
    assert!((0.71..0.78).contains(&largest), "a probe shot is one probe move off: {largest}");
    // At the calibration height the dots measure their 0.5 in through K; lifted 0.25 in (over
    // a 6 in working distance) they look 4 % smaller.
    let lift = walk_end + 25..walk_end + 75;
    let size = |range: std::ops::Range<usize>, d: f64| at[range].iter().all(|t| (t.last_width() - d).abs() < 0.01);
    assert!(size(3..lift.start, 0.5) && size(lift.end..at.len(), 0.5), "the 0.5 in dots through K");
    let grid = at[walk_end..lift.start].iter().map(|t| offset(t)).fold(0.0, f64::max);
    assert!((1.8..1.95).contains(&grid), "the lens grid reads out to 0.75 of the half-image: {grid}");
    assert!(at[lift].iter().filter(|t| (t.last_width() - 0.5 * 6.0 / 6.25).abs() < 0.005).count() == 25, "lifted");
    let end = rig.module.telemetry();
    assert!(offset(end) < 1e-3 && end.last_status() == "OK", "{end:?}");
}

/// M283 tells the host where its walk is as it gets there: each of sheet 1's five dots in
/// order before that dot's triggers, the lift after the last dot's, then the verify pass.
#[test]
fn the_walk_tells_its_progress_dot_by_dot_as_it_goes() {
    use crate::module::WalkProgress;
    let mut rig = standard_rig();
    let log: std::sync::Arc<std::sync::Mutex<Vec<(usize, WalkProgress)>>> = std::sync::Arc::default();
    let (seen, world) = (log.clone(), rig.shared.clone());
    rig.module.set_progress_sink(Some(Box::new(move |p| {
        let triggers = world.lock().map_or(0, |w| w.triggers);
        seen.lock().expect("log").push((triggers, p));
    })));
    rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect("calibrates");
    let log = log.lock().expect("log").clone();
    let stages: Vec<WalkProgress> = log.iter().map(|(_, p)| *p).collect();
    let mut want: Vec<WalkProgress> = (1..=5).map(|dot| WalkProgress::SheetDot { dot, dots: 5 }).collect();
    want.extend([WalkProgress::Lens, WalkProgress::Lift]);
    want.extend((1..=5).map(|dot| WalkProgress::Verify { dot, dots: 5 }));
    assert_eq!(stages, want);
    // Told before the dot's triggers: after the axis detect's 3, then 5 more per dot.
    let at: Vec<usize> = log.iter().take(5).map(|(t, _)| *t).collect();
    assert_eq!(at, [3, 8, 13, 18, 23]);
    assert_eq!(WalkProgress::SheetDot { dot: 3, dots: 25 }.to_string(), "M283: dot 3 of 25");
}

/// A trigger that loses the mark clears the previous mark's values on the DRO at once, and
/// M283 refused before any trigger still writes `LastStatus`.
#[test]
fn a_lost_mark_and_a_refusal_reach_the_dro() {
    let mut marks = sheet_marks(0.3, Vector2::new(1.0, 1.0));
    marks.remove(2); // dot 3 is missing
    let mut rig = sheet_rig(tilted(0, false), LengthUnit::Inch, Vector2::new(3.0, -1.5), marks);
    let seen = watch(&mut rig);
    let e = rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect_err("lost dot 3");
    let lost = rig.shared.lock().expect("world").triggers;
    let seen = seen.lock().expect("log").clone();
    let before = &seen.iter().rfind(|(n, _)| *n == lost - 1).expect("the shot before").1;
    let at = &seen.iter().find(|(n, _)| *n == lost).expect("the lost shot").1;
    assert!(before.last_width() > 0.4 && before.last_judgment() == 1, "{before:?}");
    assert_eq!((at.last_judgment(), at.last_width(), at.last_offset_x(), at.last_offset_px_x()), (0, 0.0, 0.0, 0.0));
    assert_eq!(at.last_status(), e.to_string());

    let triggers = rig.shared.lock().expect("world").triggers;
    let e = rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 7 }).expect_err("no sheet 7");
    assert!(matches!(e, VisionError::UnknownSheet { .. }), "{e}");
    assert_eq!(rig.module.telemetry().last_status(), e.to_string());
    rig.module.set_param("VisionEnabled", false).expect("set");
    let e = rig.module.m283(&mut rig.machine, Calibrate::Quick { diameter: 0.5 }).expect_err("disabled");
    assert_eq!(rig.module.telemetry().last_status(), e.to_string());
    assert_eq!(rig.shared.lock().expect("world").triggers, triggers, "nothing triggered");
}

/// The calibration lift measures the optical centre where the camera really has it, and the
/// camera offset is solved at that pixel: the pair sees the truth at the calibration height.
#[test]
fn the_lift_measures_the_optical_centre_and_the_offset_refers_to_it() {
    let mut optics = tilted(1, false);
    optics.centre_px = Vector2::new(891.5, 884.0);
    let mut rig =
        sheet_rig(optics, LengthUnit::Inch, Vector2::new(3.0, -1.5), sheet_marks(0.3, Vector2::new(1.0, 1.0)));
    let rep = sheet_report(rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect("calibrates").report);
    let p = rig.module.params();
    assert!(rep.centre.measured && rep.centre.pairs == 25, "{:?}", rep.centre);
    assert!((p.calibration.center_offset() - Vector2::new(3.5, -4.0)).norm() < 1e-6, "{:?}", rep.centre);
    assert!((rep.centre.working_distance - 6.0).abs() < 1e-6, "{:?}", rep.centre);
    // No noise: the σ floor is the camera's 0.1 px, over 25 pairs and a 4 % change.
    assert!(p.px_center_sigma_px() > 0.3 && p.px_center_sigma_px() < 1.5, "{}", p.px_center_sigma_px());
    assert!((rig.machine.tool_offset(98).expect("tool") - CAMERA).amax() < 1e-6);
    assert!(rep.verify_max < 1e-6 && rep.warning.is_none(), "{rep:?}");
    let w = rig.world();
    assert!(w.z.abs() < 1e-12 && w.absolute && w.saved_modal.is_empty(), "Z back, G90, modal state restored");
}

/// Issue 33: a camera that finds a mark only wholly inside a search window about the image
/// centre (the `Camera` driver's `VisionCameraSearchRadius`; on the built-in world 572 px for a
/// 247 px dot) read every probe of the walk, 355 px from the centre, but not the lift grid's
/// corners, 502 px out: the lift stays within the probes' reach, and measures the centre.
#[test]
fn the_lift_reads_only_where_the_walks_probes_read() {
    let mut optics = tilted(0, false);
    optics.centre_px = Vector2::new(891.5, 884.0);
    let mut rig =
        sheet_rig(optics, LengthUnit::Inch, Vector2::new(3.0, -1.5), sheet_marks(0.3, Vector2::new(1.0, 1.0)));
    rig.world().window_px = Some(500.0);
    let rep = sheet_report(rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect("calibrates").report);
    assert!(rep.centre.measured && rep.centre.pairs == 25, "{:?}", rep.centre);
    // The lens grid's far positions find nothing there: skipped, and what they could not
    // measure is said, with how to measure it.
    assert!(rep.lens.grid_found < rep.lens.grid_asked && rep.lens.reach_px < 500.0, "{:?}", rep.lens);
    assert!(rep.lens.note.as_deref().is_some_and(|n| n.contains("only 5 of the lens grid")), "{:?}", rep.lens);
    assert!(rep.lens.measured[0] && rep.warning.is_none(), "k1 measured: no warning {:?}", rep.lens);
    let p = rig.module.params();
    assert!((p.calibration.center_offset() - Vector2::new(3.5, -4.0)).norm() < 1e-6, "{:?}", rep.centre);
    // Its σ grows by what the smaller spread of positions costs: still about a pixel.
    assert!(p.px_center_sigma_px() > 0.3 && p.px_center_sigma_px() < 1.5, "{}", p.px_center_sigma_px());
}

/// A lift that cannot measure costs the calibration nothing: refused before it rose, or blind
/// up there, the walk commits with the centre kept and a warning, Z back where it was and the
/// modal state restored. A head that cannot come back down fails the walk, and says by how much.
#[test]
fn a_failed_lift_keeps_the_calibration_and_restores_z_and_the_modal_state() {
    for (refuse, blind, what) in [(Some(0), false, "refused"), (None, true, "lifted height failed")] {
        let mut rig = standard_rig();
        rig.module.params.set("VisionPxCenterOffsetX", 2.0).expect("set");
        rig.world().refuse_z_after = refuse;
        rig.world().blind_above = blind;
        let r = rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect("calibrates anyway");
        let rep = sheet_report(r.report);
        let warning = rep.warning.clone().unwrap_or_default();
        assert!(!rep.centre.measured && warning.contains(what) && warning.contains("kept"), "{warning}");
        // The calibration stands: nothing says it failed or left K unchanged.
        assert!(!warning.contains("calibration failed") && !warning.contains("left unchanged"), "{warning}");
        assert_eq!(rep.centre.lift, if blind { 0.25 } else { 0.0 }, "how far it rose");
        let p = rig.module.params();
        assert!(p.cal_k() != Matrix2::zeros() && p.px_center_offset_x() == 2.0 && p.px_center_sigma_px() == 0.0);
        assert!(rig.module.telemetry().last_status().contains("warning"), "{:?}", rig.module.telemetry());
        let w = rig.world();
        assert!(w.z.abs() < 1e-12 && w.absolute && w.saved_modal.is_empty(), "{what}: z {}", w.z);
    }
    let mut rig = standard_rig();
    let start = rig.machine.program_position().expect("a position");
    rig.world().refuse_z_after = Some(1);
    let e = rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect_err("stuck up");
    assert!(e.to_string().contains("0.25 in above"), "{e}");
    assert_untouched(&rig, start);
    let w = rig.world();
    assert!(w.absolute && w.saved_modal.is_empty(), "the modal state is restored on failure too");
}

/// `VisionCalibrationLift` 0 is the manual's walk at one height: no Z move, the centre kept
/// without a warning.
#[test]
fn no_lift_is_the_manuals_walk() {
    let mut rig = standard_rig();
    rig.module.params.set("VisionCalibrationLift", 0.0).expect("set");
    let r = rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect("calibrates");
    assert!(r.gcode.iter().all(|l| !l.contains('Z')), "{:?}", r.gcode);
    let rep = sheet_report(r.report);
    assert!(!rep.centre.measured && rep.warning.is_none() && rep.triggers == 3 + 25 + 25 + 5, "{rep:?}");
    assert!(rig.module.params.set("VisionCalibrationLift", 2.5).is_err());
    assert!(rig.module.params.set("VisionCalibrationLift", f64::NAN).is_err());
    assert!(rig.module.params.set("VisionPxCenterSigmaPx", -1.0).is_err());
}

/// Each walk measures K at its own height: against the previous calibration's K the report
/// states the working-distance change it implies (none before the first).
#[test]
fn a_walk_reports_the_working_distance_change_against_the_previous_k() {
    let mut rig = standard_rig();
    let first = sheet_report(rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect("first").report);
    assert_eq!(first.k_change, None, "K was zero before");
    // Each walk starts over dot 1 (the manual's setup step 3).
    rig.go(-2.2, -4.2);
    let again = sheet_report(rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect("again").report);
    let c = again.k_change.expect("a previous K");
    assert!(c.change_pct.abs() < 1e-6 && c.change.abs() < 1e-6, "{c:?}");
    // The head 0.06 in higher (1 % of the 6 in working distance): K 1 % larger.
    rig.world().z = 0.06;
    rig.go(-2.2, -4.2);
    let higher = sheet_report(rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect("higher").report);
    let c = higher.k_change.expect("a previous K");
    assert!((c.change_pct - 1.0).abs() < 1e-6 && (c.change - 0.06).abs() < 1e-6, "{c:?}");
    assert!((rig.world().z - 0.06).abs() < 1e-12, "the lift came back to where the walk started");
}

/// A camera that does not ride the Z axis (its image does not change as the head rises) gives
/// no centre: the walk says so and keeps the calibration.
#[test]
fn a_lift_that_changes_nothing_measures_nothing() {
    let mut rig = standard_rig();
    rig.world().working_distance_in = 1e9;
    let rep = sheet_report(rig.module.m283(&mut rig.machine, Calibrate::Sheet { n: 1 }).expect("calibrates").report);
    let warning = rep.warning.unwrap_or_default();
    assert!(!rep.centre.measured && warning.contains("did not change measurably"), "{warning}");
    assert_eq!(rig.module.params().px_center_sigma_px(), 0.0);
    assert!(rig.world().z.abs() < 1e-12);
}
