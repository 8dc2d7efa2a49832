//! The calibration's record (issue 33): what M283 calibrated with, and M280–M282 refusing when
//! it changed.

use vision_math::{Matrix2, Point2, Vector2};

use super::fakes::{Optics, Rig, World};
use crate::calibrate::Calibrate;
use crate::error::VisionError;
use crate::machine::Machine;
use crate::module::RunMode;

/// A rig calibrated by M283 Q with a camera reporting `frame`, one mark in view at the start.
fn calibrated(frame: Option<(u32, u32)>) -> Rig {
    let world = World { marks: vec![Point2::new(0.2, 0.1)], frame, ..World::default() };
    let mut rig = Rig::with_world(world);
    rig.module.params.set_cal_k(Matrix2::zeros()).expect("zero");
    rig.module.m283(&mut rig.machine, Calibrate::Quick { diameter: 0.5 }).expect("quick");
    rig
}

fn changed(e: VisionError) -> (&'static str, String) {
    match e {
        VisionError::CalibrationChanged { what, .. } => (what, e.to_string()),
        other => panic!("expected CalibrationChanged, got {other:?}"),
    }
}

#[test]
fn m283_records_the_resolution_driver_and_camera_tool_offset_it_calibrated_with() {
    let rig = calibrated(None);
    let cal = &rig.module.params().calibration;
    assert_eq!(cal.recorded_resolution(), Some((1776, 1776)));
    assert_eq!(cal.recorded_driver(), Some("Fake"));
    assert_eq!(cal.recorded_tool(), Some((98, Vector2::zeros())));
    // A camera that reports its frames is calibrated at their size.
    let rig = calibrated(Some((1280, 960)));
    let p = rig.module.params();
    assert_eq!((p.camera_res_x(), p.camera_res_y()), (1280, 960));
    assert_eq!(p.calibration.recorded_resolution(), Some((1280, 960)));
}

#[test]
fn a_changed_camera_tool_offset_is_refused_until_it_is_put_back() {
    let mut rig = calibrated(None);
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("unchanged: runs");
    rig.machine.set_tool_offset(98, Vector2::new(0.003, 0.0)).expect("touch off");
    let e = rig.module.m281(&mut rig.machine, false).expect_err("refused");
    let (what, text) = changed(e);
    assert_eq!(what, "the camera tool's offset");
    assert!(
        text.contains("the tool table holds X0.00300 Y0.00000 in for T98, M283 wrote X0.00000 Y0.00000 in"),
        "{text}"
    );
    assert!(text.contains("read 0.00300 in off") && text.contains("run M283 C1"), "{text}");
    assert!(rig.module.telemetry().last_status().contains("the camera tool's offset changed"));
    for m in [
        rig.module.m280(&mut rig.machine, RunMode::Rectangle).map(|_| ()),
        rig.module.m282(&mut rig.machine, crate::module::Pieces::All).map(|_| ()),
    ] {
        assert!(matches!(m, Err(VisionError::CalibrationChanged { .. })), "{m:?}");
    }
    // Within a tool table's rounding it passes; put back, it runs.
    rig.machine.set_tool_offset(98, Vector2::new(0.00005, 0.0)).expect("rounded");
    rig.module.m281(&mut rig.machine, false).expect("within the tolerance");
    rig.machine.set_tool_offset(98, Vector2::zeros()).expect("put back");
    rig.module.m281(&mut rig.machine, false).expect("put back: captures");
}

#[test]
fn a_camera_whose_frames_changed_size_is_refused_and_an_uncalibrated_one_adopts_them() {
    let mut rig = calibrated(Some((1776, 1776)));
    rig.world().frame = Some((1280, 960));
    let (what, text) = changed(rig.module.m281(&mut rig.machine, false).expect_err("refused"));
    assert_eq!(what, "the camera's resolution");
    assert!(
        text.contains("the camera is now 1280 x 960 px") && text.contains("calibrated at 1776 x 1776 px"),
        "{text}"
    );

    // The setting edited by hand after M283: the same refusal.
    let mut rig = calibrated(None);
    rig.module.set_param("VisionCameraResX", 1600).expect("set");
    let (what, _) = changed(rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect_err("refused"));
    assert_eq!(what, "the camera's resolution");

    // A calibration made before the record existed was made at the resolution it is used with.
    let mut rig =
        Rig::with_world(World { marks: vec![Point2::new(0.0, 0.0)], frame: Some((640, 480)), ..World::default() });
    assert_eq!(rig.module.params().calibration.recorded_resolution(), None);
    let (what, text) = changed(rig.module.m281(&mut rig.machine, false).expect_err("refused"));
    assert_eq!(what, "the camera's resolution");
    assert!(text.contains("calibrated at 1776 x 1776 px"), "{text}");

    // Not calibrated: the camera's frames are the resolution, nothing to refuse.
    let mut rig = Rig::with_world(World { frame: Some((640, 480)), ..World::default() });
    rig.module.params.set_cal_k(Matrix2::zeros()).expect("zero");
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("adopts");
    assert_eq!((rig.module.params().camera_res_x(), rig.module.params().camera_res_y()), (640, 480));
}

#[test]
fn another_driver_than_the_one_calibrated_with_is_refused() {
    let mut rig = calibrated(None);
    rig.module.params.set("VisionCal_Driver", "Keyence").expect("set");
    let (what, text) = changed(rig.module.m281(&mut rig.machine, false).expect_err("refused"));
    assert_eq!(what, "the camera driver");
    assert!(text.contains("the loaded driver is Fake, K was calibrated with Keyence"), "{text}");
    rig.module.params.set("VisionCal_Driver", "fake").expect("set");
    rig.module.m281(&mut rig.machine, false).expect("names compare in any case");
}

#[test]
fn a_camera_turned_on_its_mount_is_refused_and_a_slight_turn_is_a_warning() {
    for (turn_deg, refused) in [(90.0, true), (2.0, false), (0.0, false)] {
        let mut rig = Rig::with_world(World { marks: vec![Point2::new(0.02, 0.01)], ..World::default() });
        let optics = rig.world().optics;
        rig.world().optics = Optics { rotation_deg: optics.rotation_deg + turn_deg, ..optics };
        let result = rig.module.m281(&mut rig.machine, false);
        if refused {
            let (what, text) = changed(result.expect_err("refused"));
            assert_eq!(what, "the camera's orientation");
            assert!(text.contains("the mark moved -90.0°") || text.contains("the mark moved +90.0°"), "{text}");
            assert!(rig.module.dots().is_empty(), "nothing is kept");
        } else {
            let c = result.expect("captured").report;
            assert!(c.recentred.is_some(), "the camera moved: the turn is measured");
            let warned = c.warning.as_deref().is_some_and(|w| w.contains("turned or mirrored on its mount"));
            assert_eq!(warned, turn_deg != 0.0, "{turn_deg}: {:?}", c.warning);
        }
    }
}

#[test]
fn the_recorded_offset_is_compared_in_the_machines_units_now() {
    // Calibrated in inches with the camera 0.5, −0.25 in from the spindle; run in mm.
    let mut world =
        World { marks: vec![Point2::new(0.2, 0.1)], cam_offset: Vector2::new(0.5, -0.25), ..World::default() };
    world.offsets.insert(98, Vector2::new(0.5, -0.25));
    let mut rig = Rig::with_world(world);
    rig.module.params.set_cal_k(Matrix2::zeros()).expect("zero");
    rig.module.m283(&mut rig.machine, Calibrate::Quick { diameter: 0.5 }).expect("quick");
    assert_eq!(rig.module.params().calibration.recorded_tool(), Some((98, Vector2::new(0.5, -0.25))));
    rig.world().units = vision_math::LengthUnit::Millimetre;
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("the same offset, in mm");
    // 0.002 mm off is within a table's rounding (0.0001 in); 0.01 in is not.
    rig.machine.set_tool_offset(98, Vector2::new(12.702, -6.35)).expect("mm");
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("within 0.0001 in");
    rig.machine.set_tool_offset(98, Vector2::new(12.954, -6.35)).expect("mm");
    let (what, text) = changed(rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect_err("refused"));
    assert_eq!(what, "the camera tool's offset");
    assert!(text.contains("every mark would be read 0.25400 mm off"), "{text}");
}

#[test]
fn a_driver_name_the_record_cannot_hold_is_not_recorded() {
    for (name, recorded) in [("Fake camera", None), ("Fake-2_b", Some("Fake-2_b")), ("Fake\u{e9}", None)] {
        let world = World { marks: vec![Point2::new(0.2, 0.1)], camera_name: name, ..World::default() };
        let mut rig = Rig::with_world(world);
        rig.module.params.set_cal_k(Matrix2::zeros()).expect("zero");
        rig.module.m283(&mut rig.machine, Calibrate::Quick { diameter: 0.5 }).expect("calibrates whatever the name");
        assert_eq!(rig.module.params().calibration.recorded_driver(), recorded, "{name}");
    }
    let long: &'static str = Box::leak("F".repeat(65).into_boxed_str());
    let world = World { marks: vec![Point2::new(0.2, 0.1)], camera_name: long, ..World::default() };
    let mut rig = Rig::with_world(world);
    rig.module.params.set_cal_k(Matrix2::zeros()).expect("zero");
    rig.module.m283(&mut rig.machine, Calibrate::Quick { diameter: 0.5 }).expect("calibrates");
    assert_eq!(rig.module.params().calibration.recorded_driver(), None);
}

#[test]
fn another_mark_than_the_one_calibrated_with_is_a_warning() {
    let world = World { marks: vec![Point2::new(0.2, 0.1)], mark_spec: Some("dot, dark on light"), ..World::default() };
    let mut rig = Rig::with_world(world);
    rig.module.params.set_cal_k(Matrix2::zeros()).expect("zero");
    rig.module.m283(&mut rig.machine, Calibrate::Quick { diameter: 0.5 }).expect("quick");
    assert_eq!(rig.module.params().calibration.recorded_mark(), Some("dot, dark on light"));
    let same = rig.module.m281(&mut rig.machine, false).expect("captures").report;
    assert!(same.warning.is_none(), "{:?}", same.warning);
    rig.world().mark_spec = Some("ring, dark on light");
    let other = rig.module.m281(&mut rig.machine, false).expect("captures: a warning, not a refusal").report;
    let w = other.warning.expect("a warning");
    assert!(
        w.contains("the camera searches for a ring, dark on light mark, M283 calibrated with a dot, dark on light one"),
        "{w}"
    );
    // A camera that says nothing of its mark (Keyence) is not compared.
    rig.world().mark_spec = None;
    assert!(rig.module.m281(&mut rig.machine, false).expect("captures").report.warning.is_none());
}
