//! What survives: images kept by M281 D1, the profile written by M283 and M284, the registry.

use std::fs::{self, File};
use std::path::PathBuf;
use std::time::{Duration, UNIX_EPOCH};

use vision_math::{Matrix2, Point2};

use super::fakes::{FakeCamera, Rig, World};
use crate::calibrate::Calibrate;
use crate::driver::{DriverError, DriverErrorKind};
use crate::error::VisionError;
use crate::module::VisionModule;
use crate::params::Params;
use crate::profile::ProfileStore;
use crate::registry::DriverRegistry;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("vision-core-module-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&d);
    fs::create_dir_all(&d).expect("tmp");
    d
}

#[test]
fn m281_d1_keeps_the_fresh_image_and_warns_when_none_comes() {
    let root = tmp("d1");
    let watch = root.join("watch");
    fs::create_dir_all(&watch).expect("watch");
    let mut rig = Rig::with_world(World { marks: vec![Point2::new(0.0, 0.0)], ..World::default() });
    rig.module.set_images_dir(root.join("Images"));
    rig.module.set_param("VisionImageWatchDir", watch.to_string_lossy().as_ref()).expect("dir");
    rig.module.set_param("VisionImageGrabTimeout", 0.05).expect("timeout");

    // Nothing pushed: a warning, the capture still counts.
    let c = rig.module.m281(&mut rig.machine, true).expect("capture").report;
    assert_eq!(c.image, None);
    let w = c.warning.expect("warning");
    assert!(w.starts_with("image not saved: no image newer than the trigger"), "{w}");
    assert!(rig.module.telemetry().last_status().starts_with("OK (warning: image not saved"));

    // The camera pushed an image after the trigger (the fake clock reads 1_700_000_000 s).
    let img = watch.join("IMG_0001.bmp");
    fs::write(&img, b"BM...").expect("write");
    File::options()
        .write(true)
        .open(&img)
        .and_then(|f| f.set_modified(UNIX_EPOCH + Duration::from_secs(1_700_000_001)))
        .expect("mtime");
    let c = rig.module.m281(&mut rig.machine, true).expect("capture").report;
    let kept = c.image.expect("kept");
    assert_eq!(kept, root.join("Images").join("vision_20231114_231320_000.bmp"));
    assert_eq!(fs::read(&kept).expect("read"), b"BM...");
    assert_eq!(c.warning, None);
    assert_eq!(rig.module.telemetry().last_status(), "OK");
    // D0 never touches the folder.
    rig.module.m281(&mut rig.machine, false).expect("capture");
    assert_eq!(fs::read_dir(root.join("Images")).expect("dir").count(), 1);
    // Empty watch folder: a warning, no wait.
    rig.module.set_param("VisionImageWatchDir", "").expect("dir");
    let c = rig.module.m281(&mut rig.machine, true).expect("capture").report;
    assert!(c.warning.expect("warning").contains("VisionImageWatchDir is empty"));
    let _ = fs::remove_dir_all(&root);
}

#[test]
fn m283_and_m284_persist_to_the_profile() {
    let root = tmp("profile");
    let path = root.join("vision.toml");
    let mut rig = Rig::with_world(World { marks: vec![Point2::new(0.2, 0.1)], ..World::default() });
    rig.module.params.set_cal_k(Matrix2::zeros()).expect("zero");
    let module = std::mem::replace(&mut rig.module, VisionModule::new(Params::default()));
    rig.module = module.with_profile(ProfileStore::new(&path));
    rig.module.m283(&mut rig.machine, Calibrate::Quick { diameter: 0.5 }).expect("quick");
    rig.module.m284(Some(12)).expect("job");
    let saved = ProfileStore::new(&path).load().expect("load");
    assert_eq!(saved.cal_k(), rig.module.params().cal_k());
    assert_eq!(saved.active_job(), 12);
    assert_eq!(saved.cal_date(), "2023-11-14T23:13:20+01:00");
    assert!(saved.camera_invert_y());
    assert!(!fs::read_to_string(&path).expect("text").contains("VisionLast"), "telemetry is not persisted");
    let text = fs::read_to_string(&path).expect("text");
    assert!(text.contains("VisionCal_K11 = ") && text.contains("VisionCal_K22 = "), "{text}");
    let _ = fs::remove_dir_all(&root);
}

#[test]
fn the_registry_builds_the_driver_vision_driver_names() {
    let rig = Rig::new();
    let shared = rig.shared.clone();
    let mut registry = DriverRegistry::new();
    registry.register("Fake", move |_params: &Params| Ok(Box::new(FakeCamera(shared.clone())) as _));
    registry.register("Broken", |p: &Params| {
        Err(DriverError::new(DriverErrorKind::InvalidArgument, format!("cannot use {}:{}", p.ip(), p.port())))
    });
    assert_eq!(registry.names(), vec!["Fake", "Broken"]);
    assert!(registry.contains("fake"));

    let mut params = Params::default();
    // Disabled: no driver is loaded, whatever VisionDriver says.
    let module = VisionModule::from_registry(params.clone(), &registry).expect("disabled");
    assert!(module.driver().is_none());
    params.set("VisionEnabled", true).expect("set");
    let e = VisionModule::from_registry(params.clone(), &registry).expect_err("Keyence is not registered");
    assert_eq!(e, VisionError::UnknownDriver { name: "Keyence".into(), known: "Fake, Broken".into() });
    params.set("VisionDriver", "fake").expect("set");
    let module = VisionModule::from_registry(params.clone(), &registry).expect("fake");
    assert_eq!(module.driver().map(|d| d.name()), Some("Fake"));
    params.set("VisionDriver", "Broken").expect("set");
    let e = VisionModule::from_registry(params, &registry).expect_err("factory error");
    assert_eq!(e.to_string(), "cannot use 192.168.208.80:8500");
}
