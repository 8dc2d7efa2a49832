//! Smoke test on the machine's real video devices: runs only where `/dev/video*` exists (none
//! does on the machines this was built on; see the README, *Use a USB or network camera*).

use vision_driver_camera::{v4l2, CameraError};

fn video_devices() -> Vec<std::path::PathBuf> {
    let entries: Vec<_> =
        std::fs::read_dir("/dev").map(|d| d.filter_map(Result::ok).map(|e| e.path()).collect()).unwrap_or_default();
    entries
        .into_iter()
        .filter(|p| p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with("video")))
        .collect()
}

/// Without the backend, an existing device is named and the way out is given.
#[cfg(not(feature = "v4l2"))]
#[test]
fn every_video_device_is_named_and_explained() {
    let devices = video_devices();
    if devices.is_empty() {
        eprintln!("no /dev/video* here: the V4L2 smoke test has nothing to open");
        return;
    }
    for path in devices {
        let Err(e) = v4l2::open(&path) else { panic!("{} opened without a backend", path.display()) };
        assert!(matches!(&e, CameraError::DeviceOpen { reason, .. } if reason.contains("mjpg-streamer")), "{e}");
    }
}

/// With the backend: every capture node negotiates a format and delivers one decoded frame
/// (other nodes, e.g. metadata, are refused as such).
#[cfg(feature = "v4l2")]
#[test]
fn every_capture_device_gives_a_frame() {
    use vision_driver_camera::FrameSource;
    let devices = video_devices();
    if devices.is_empty() {
        eprintln!("no /dev/video* here: the V4L2 smoke test has nothing to open");
        return;
    }
    for path in devices {
        match v4l2::open(&path) {
            Ok(device) => {
                let mut source = v4l2::V4l2Source::new(device, None, None, std::time::Duration::from_secs(5));
                let frame = source.frame().unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                assert!(frame.width() > 0 && frame.height() > 0);
                eprintln!("{}: {}", path.display(), source.describe());
            }
            Err(CameraError::DeviceOpen { reason, .. }) => eprintln!("{}: {reason}", path.display()),
            Err(e) => panic!("{}: {e}", path.display()),
        }
    }
}
