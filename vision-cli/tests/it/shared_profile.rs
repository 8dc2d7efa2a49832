//! Two processes on one profile: `mach-vision run` calibrates (M283) while a session of this
//! process, opened before, still holds the old K; the session's M284 then saves its job
//! without writing back the stale K (issue 26, "calibration lost").

use std::path::PathBuf;
use std::process::Command;

use vision_core::ProfileStore;
use vision_driver_sim::{Sim, SimMachine, World};
use vision_host::{cameras, ProgramHandler, Session};

#[test]
fn a_stale_session_keeps_the_calibration_another_process_saved() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("shared_profile");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let path = dir.join("vision.toml");
    let sim = Sim::new(World::default_world()).expect("the built-in world");
    let registry = cameras(Some(&sim));
    let mut start = registry.params();
    start.set("VisionEnabled", true).expect("yes/no");
    start.set("VisionDriver", "Sim").expect("text");
    start.set("VisionCameraToolNumber", i64::from(sim.world().machine.camera_tool)).expect("tool");
    ProfileStore::new(&path).save(&start).expect("a fresh, uncalibrated profile");

    // This process's session reads K = 0 …
    let session = Session::open(&path, &registry).expect("open");
    // … another process calibrates and saves …
    let program = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/programs/01-calibrate-sheet.nc");
    let out = Command::new(env!("CARGO_BIN_EXE_mach-vision"))
        .args(["run", "--profile", path.to_str().expect("utf-8"), program.to_str().expect("utf-8")])
        .output()
        .expect("run");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let calibrated = ProfileStore::new(&path).with_defaults(registry.params()).load().expect("load");
    assert!(calibrated.cal_k() != start.cal_k() && !calibrated.cal_date().is_empty(), "the run calibrated");

    // … and this session, still holding K = 0, switches the job.
    let mut handler = ProgramHandler::new(session, &vision_host::controller::Mach4, vision_host::system_clock());
    let mut machine = SimMachine::new(&sim).expect("machine");
    let end = machine.run_program("M284 P2\nM30\n", Some(&mut handler), &mut |_: &vision_gcode::Event| {});
    assert!(end.is_ok(), "{end:?}");
    let file = ProfileStore::new(&path).with_defaults(registry.params()).load().expect("load");
    assert_eq!(file.calibration, calibrated.calibration, "the other process's calibration is kept");
    assert_eq!(file.active_job(), 2, "this session's job is saved");
    assert_eq!(handler.session().module().params().calibration, calibrated.calibration, "and taken in memory");
    let _ = std::fs::remove_dir_all(&dir);
}
