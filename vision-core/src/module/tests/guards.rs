//! The checks every entry point shares, and M284.

use super::fakes::Rig;
use crate::driver::{DriverError, DriverErrorKind, Judgment, Reading};
use crate::error::VisionError;
use crate::module::{Pieces, RunMode};

#[test]
fn disabled_refuses_all_five_and_changes_nothing() {
    let mut rig = Rig::new();
    rig.module.params.config.enabled = false;
    let before = rig.module.params().clone();
    let m = &mut rig.machine;
    assert_eq!(rig.module.m280(m, RunMode::Rectangle).map(|_| ()), Err(VisionError::NotEnabled));
    assert_eq!(rig.module.m281(m, false).map(|_| ()), Err(VisionError::NotEnabled));
    assert_eq!(rig.module.m282(m, Pieces::All).map(|_| ()), Err(VisionError::NotEnabled));
    assert_eq!(rig.module.m284(Some(3)).map(|_| ()), Err(VisionError::NotEnabled));
    assert_eq!(VisionError::NotEnabled.to_string().split(" —").next(), Some("Vision is not enabled"));
    assert_eq!(rig.module.params(), &before);
    assert_eq!(rig.world().triggers, 0);
    assert!(rig.world().pounds.is_empty());
}

#[test]
fn wrong_tool_refuses_m280_to_m282_but_not_m284() {
    let mut rig = Rig::new();
    rig.world().tool = 1;
    let m = &mut rig.machine;
    let wrong = Err(VisionError::WrongTool { camera: 98, active: 1 });
    assert_eq!(rig.module.m280(m, RunMode::Rectangle).map(|_| ()), wrong);
    assert_eq!(rig.module.m281(m, false).map(|_| ()), wrong);
    assert_eq!(rig.module.m282(m, Pieces::All).map(|_| ()), wrong);
    assert!(rig.module.m284(Some(2)).is_ok());
    assert_eq!(rig.world().triggers, 0);
    // 0 disables the check.
    rig.module.set_param("VisionCameraToolNumber", 0).expect("set");
    assert!(rig.module.m280(&mut rig.machine, RunMode::Rectangle).is_ok());
}

#[test]
fn m284_switches_jobs_only_with_select_job() {
    let mut rig = Rig::new();
    let r = rig.module.m284(Some(5)).expect("switch");
    assert_eq!((r.report.job, r.report.switched), (5, true));
    assert_eq!(rig.module.params().active_job(), 5);
    // Omitted or P0 re-applies the stored job.
    let r = rig.module.m284(None).expect("re-apply");
    assert_eq!(r.report.job, 5);
    rig.module.m284(Some(0)).expect("P0");
    assert_eq!(rig.world().jobs, vec![5, 5, 5]);
    assert!(matches!(rig.module.m284(Some(1000)), Err(VisionError::InvalidParam { .. })));
    // A camera-side refusal leaves ActiveJob alone.
    rig.world().select_job = true;
    let mut fresh = Rig::new();
    fresh.world().select_job = false;
    let e = fresh.module.m284(Some(2)).expect_err("unsupported");
    assert_eq!(e, VisionError::SelectJobUnsupported { driver: "Fake".into() });
    assert!(e.to_string().contains("select_job"));
    assert_eq!(fresh.module.params().active_job(), 0);
    // Stored job 0: nothing to apply, the camera is not contacted.
    let mut idle = Rig::new();
    let r = idle.module.m284(None).expect("nothing to do");
    assert!(!r.report.switched);
    assert!(idle.world().jobs.is_empty());
}

#[test]
fn no_driver_is_a_clear_error() {
    let mut rig = Rig::new();
    rig.module.set_driver(None);
    let e = rig.module.m281(&mut rig.machine, false).expect_err("no driver");
    assert!(matches!(e, VisionError::NoDriver { .. }), "{e}");
    assert_eq!(rig.module.telemetry().last_status(), e.to_string(), "the DRO says why nothing was read");
    let e = rig.module.m283(&mut rig.machine, crate::calibrate::Calibrate::Quick { diameter: 0.5 }).expect_err("none");
    assert!(matches!(e, VisionError::NoDriver { .. }), "{e}");
    assert_eq!(rig.module.telemetry().last_status(), e.to_string());
    assert!(matches!(rig.module.m284(Some(1)), Err(VisionError::NoDriver { .. })));
}

#[test]
fn driver_errors_reach_the_operator_in_the_drivers_words() {
    let mut rig = Rig::new();
    // The driver's explanation as it is, whatever the kind: the core puts no generic advice of
    // its own in front of it.
    let closed = "camera at 192.168.208.80:8500 closed the connection — another client holds the camera";
    rig.world().script.push_back(Err(DriverError::new(DriverErrorKind::Refused, closed)));
    let e = rig.module.m281(&mut rig.machine, false).expect_err("refused");
    assert_eq!(e.to_string(), closed);
    assert_eq!(rig.module.telemetry().last_status(), closed);
    assert_eq!(rig.module.telemetry().last_judgment(), -1);
    let refusal = "camera refused the trigger — switch the camera to Run mode";
    rig.world().script.push_back(Err(DriverError::new(DriverErrorKind::Rejected, refusal)));
    let e = rig.module.m281(&mut rig.machine, false).expect_err("rejected");
    assert_eq!(e.to_string(), refusal);
    assert_eq!(rig.module.telemetry().last_status(), refusal);
    // The driver's typed error survives the trip through the core.
    let VisionError::Driver(d) = e else { panic!("{e:?}") };
    assert_eq!(d.kind(), DriverErrorKind::Rejected);
}

#[test]
fn the_drivers_warning_about_a_reading_reaches_the_operator() {
    let mut rig = Rig::new();
    rig.module.set_param("VisionRecenterPasses", 0).expect("one scripted reading");
    let seen = Reading { judgment: Judgment::Ok, count: Some(1), ..Reading::position(700.0, 650.0) };
    rig.world().script.push_back(Ok(Reading { count: Some(2), ..seen }));
    let capture = rig.module.m281(&mut rig.machine, false).expect("a usable reading").report;
    let warning = "the fake camera saw 2 marks and reported the nearest";
    assert_eq!(capture.warning.as_deref(), Some(warning));
    assert_eq!(rig.module.telemetry().last_status(), format!("OK (warning: {warning})"));
    assert_eq!(rig.module.telemetry().last_judgment(), 1);
    // With the image warning of M281 D1 as well, both are kept.
    rig.world().script.push_back(Ok(Reading { count: Some(2), ..seen }));
    let capture = rig.module.m281(&mut rig.machine, true).expect("a usable reading").report;
    let both = capture.warning.unwrap_or_default();
    assert!(both.starts_with(&format!("{warning}; image not saved")), "{both}");
    // One mark: nothing to say.
    rig.world().script.push_back(Ok(seen));
    assert_eq!(rig.module.m281(&mut rig.machine, false).expect("one mark").report.warning, None);
    assert_eq!(rig.module.telemetry().last_status(), "OK");
}

#[test]
fn a_pound_block_past_the_machines_last_variable_is_refused_before_anything_changes() {
    let mut rig = Rig::new();
    rig.world().last_pound = 5000; // a machine with fewer variables than #9999
    rig.module.set_param("VisionPoundVarBase", 4970).expect("in range");
    let before = rig.module.params().clone();
    let e = rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect_err("runs past #5000");
    assert!(matches!(e, VisionError::PoundBlockMissing { base: 4970, end: 5009, .. }), "{e:?}");
    assert!(e.to_string().starts_with("VisionPoundVarBase 4970 does not fit this machine"), "{e}");
    assert!(e.to_string().contains("#5009 does not exist"), "{e}");
    assert!(matches!(rig.module.m281(&mut rig.machine, false), Err(VisionError::PoundBlockMissing { .. })));
    assert_eq!(rig.module.params(), &before);
    assert_eq!(rig.world().triggers, 0, "refused before the trigger");
    rig.module.set_param("VisionPoundVarBase", 4960).expect("in range");
    rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("#4960..#4999 all exist");
}

/// A controller position past the bound (a units or DRO error) is refused before the trigger:
/// no capture, no re-centring move (at 1e308 it read `G91 G0 X0.0000000 …`).
#[test]
fn a_position_past_the_bound_is_refused_before_anything_is_stored() {
    for far in [1e308, -1.000_000_1e9] {
        let mut rig = Rig::new();
        rig.module.m280(&mut rig.machine, RunMode::Rectangle).expect("m280");
        rig.world().program = vision_math::Point2::new(0.0, far);
        rig.world().script.push_back(Ok(Reading::position(900.0, 880.0)));
        let log = rig.world().log.len();
        let e = rig.module.m281(&mut rig.machine, false).expect_err("far");
        let VisionError::Machine(m) = &e else { panic!("{e}") };
        assert_eq!(m.kind(), crate::MachineErrorKind::OutOfRange, "{e}");
        assert!(
            e.to_string().contains("the controller's Y position is") && e.to_string().contains("beyond ±1e9"),
            "{e}"
        );
        assert!(e.to_string().len() < 200, "{e}");
        assert!(rig.module.dots().is_empty());
        assert_eq!(rig.world().log.len(), log, "no G-code ran");
    }
}
