//! What survives: images kept by M281 D1, the profile written by M283 and M284, the registry.

use std::fs;
use std::path::PathBuf;
use std::time::UNIX_EPOCH;

use vision_math::{Matrix2, Point2};

use super::fakes::{FakeCamera, Rig, World};
use crate::calibrate::Calibrate;
use crate::driver::{CameraDriver as _, DriverError, DriverErrorKind};
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
fn m281_d1_asks_the_driver_for_the_image_and_warns_when_it_has_none() {
    let root = tmp("d1");
    let mut rig = Rig::with_world(World { marks: vec![Point2::new(0.0, 0.0)], ..World::default() });
    rig.module.set_images_dir(root.join("Images"));

    // The driver has no image: its words are the warning, the capture still counts.
    let c = rig.module.m281(&mut rig.machine, true).expect("capture").report;
    assert_eq!(c.image, None);
    let w = c.warning.expect("warning");
    assert_eq!(w, "image not saved: the fake camera kept no image — give it one");
    assert!(rig.module.telemetry().last_status().starts_with("OK (warning: image not saved"));

    // The driver keeps the trigger's image where the module says (the fake clock reads
    // 1_700_000_000 s).
    rig.shared.lock().expect("world").image = Some(b"BM...".to_vec());
    let c = rig.module.m281(&mut rig.machine, true).expect("capture").report;
    let kept = c.image.expect("kept");
    assert_eq!(kept, root.join("Images").join("vision_20231114_231320_000.bmp"));
    assert_eq!(fs::read(&kept).expect("read"), b"BM...");
    assert_eq!(c.warning, None);
    assert_eq!(rig.module.telemetry().last_status(), "OK");
    assert_eq!(rig.shared.lock().expect("world").grabs.last(), Some(&(1_700_000_000, "20231114_231320_000".into())));
    // D0 never asks.
    rig.module.m281(&mut rig.machine, false).expect("capture");
    assert_eq!(rig.shared.lock().expect("world").grabs.len(), 2);
    let _ = fs::remove_dir_all(&root);
}

/// A driver without `grab_image`.
struct NoImages;

impl crate::driver::CameraDriver for NoImages {
    fn name(&self) -> &str {
        "Plain"
    }
    fn capabilities(&self) -> crate::driver::Capabilities {
        crate::driver::Capabilities::default()
    }
    fn trigger(&mut self) -> Result<crate::driver::Reading, DriverError> {
        Ok(crate::driver::Reading::position(888.0, 888.0))
    }
    fn select_job(&mut self, _job: u32) -> Result<(), DriverError> {
        Err(DriverError::new(DriverErrorKind::Unsupported, "no jobs"))
    }
    fn test_connection(&mut self) -> Result<String, DriverError> {
        Ok(String::new())
    }
}

#[test]
fn m281_d1_on_a_driver_that_cannot_keep_images_is_a_warning() {
    let mut rig = Rig::with_world(World { marks: vec![Point2::new(0.0, 0.0)], ..World::default() });
    rig.module.set_driver(Some(Box::new(NoImages)));
    let c = rig.module.m281(&mut rig.machine, true).expect("capture").report;
    assert_eq!(c.warning.as_deref(), Some("image not saved: camera driver Plain cannot keep images"));
    let e = NoImages.grab_image(&crate::driver::ImageRequest {
        dir: std::path::Path::new("."),
        since: UNIX_EPOCH,
        stamp: "s",
    });
    assert_eq!(e.map_err(|e| e.kind()), Err(DriverErrorKind::Unsupported));
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
    registry.register_with_settings("Broken", &crate::params::tests::PROBE, |p: &Params| {
        let level = p.get("VisionProbeLevel").map_err(|e| DriverError::new(DriverErrorKind::Other, e))?;
        Err(DriverError::new(DriverErrorKind::InvalidArgument, format!("cannot use level {level}")))
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
    assert_eq!(module.driver().map(crate::driver::CameraDriver::name), Some("Fake"));
    params.set("VisionDriver", "Broken").expect("set");
    let e = VisionModule::from_registry(params, &registry).expect_err("factory error");
    assert_eq!(e.to_string(), "cannot use level 5", "the factory sees its settings, at their defaults");
    assert_eq!(registry.name("broken"), Some("Broken"));
    assert!(registry.settings("Fake").is_none());
    assert_eq!(registry.settings("BROKEN").map(|t| t.table), Some("probe"));
    let mut params = registry.params();
    params.set("VisionProbeLevel", 2).expect("a registered driver's setting");
    params.set("VisionEnabled", true).expect("set");
    params.set("VisionDriver", "Broken").expect("set");
    let e = VisionModule::from_registry(params, &registry).expect_err("factory error");
    assert_eq!(e.to_string(), "cannot use level 2");
}
