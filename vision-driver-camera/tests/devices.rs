//! Smoke test on the machine's real video devices: runs only where `/dev/video*` exists (none
//! does on the machines this was built on; see the README, *Use a USB or network camera*).

use vision_driver_camera::{v4l2, CameraError, FrameDriver};

#[test]
fn every_video_device_is_named_and_explained() {
    let devices: Vec<_> =
        std::fs::read_dir("/dev").map(|d| d.filter_map(Result::ok).map(|e| e.path()).collect()).unwrap_or_default();
    let devices: Vec<_> = devices
        .into_iter()
        .filter(|p| p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with("video")))
        .collect();
    if devices.is_empty() {
        eprintln!("no /dev/video* here: the V4L2 smoke test has nothing to open");
        return;
    }
    for path in devices {
        // This build has no capture backend: an existing device is said to exist, with what to
        // do instead, through the registry's path too.
        let Err(e) = v4l2::open(&path) else { panic!("{} opened without a backend", path.display()) };
        assert!(
            matches!(&e, CameraError::DeviceOpen { reason, .. } if reason.contains("no V4L2 capture backend")),
            "{e}"
        );
        let mut params = vision_core::Params::default().with_driver_settings(&vision_driver_camera::settings::SETTINGS);
        params.set("VisionCameraSource", path.display().to_string()).expect("a device path");
        let Err(e) = FrameDriver::from_params(&params) else { panic!("a driver without a backend") };
        assert!(e.to_string().contains("mjpg-streamer"), "{e}");
    }
}
