//! Issue 27 end to end: the image-mode simulated camera (`SimImage`: rendered frames searched
//! by vision-locate through the `Camera` driver) beside the reading-mode one (`Sim`) on the same
//! worlds, and the `Camera` driver reading HTTP snapshots from a loopback server this test
//! starts, which renders what the simulated machine's camera sees where the machine is.
//!
//! The figures in `benches/README.md` come from
//! `cargo test --release -p vision-cli --test it image_camera:: -- --nocapture`.

use vision_core::{Params, Timestamp, VisionModule};
use vision_driver_camera::server::{Encoding, SnapshotServer};
use vision_driver_camera::FrameSource;
use vision_driver_sim::{ImageLook, MarkKind, Sim, SimMachine, World};
use vision_gcode::Event;
use vision_host::fixed_clock;
use vision_host::{ProgramHandler, Record, Session, SimFrames};
use vision_math::Point2;

const EX4: &str = include_str!("../../../examples/programs/04-rectangle-fit.nc");

/// The demo part's area, inches: where the cut error is measured.
fn grid() -> Vec<Point2<f64>> {
    (0..=6).flat_map(|i| (0..=4).map(move |j| Point2::new(f64::from(i), f64::from(j)))).collect()
}

/// Runs example 4 on `world` with the camera `driver` (`settings` adds its settings) and
/// returns the worst cut error over the demo part, inches, how many M281 it ran and how many
/// frames the simulator rendered.
fn example4(world: World, driver: &str, settings: impl FnOnce(&Sim, &mut Params)) -> (f64, u64, u64) {
    let sim = Sim::new(world).expect("valid world");
    let registry = vision_host::cameras(Some(&sim));
    let mut params = sim.calibrated_params(&registry.params()).expect("calibrated");
    params.set("VisionDriver", driver).expect("set");
    settings(&sim, &mut params);
    let module = VisionModule::from_registry(params, &registry).expect("driver");
    let clock = fixed_clock(Timestamp::from_unix(1_800_000_000, 0));
    let mut handler = ProgramHandler::new(Session::new(module), sim.world().machine.controller(), clock);
    let mut machine = SimMachine::new(&sim).expect("machine");
    let mut ignore = |_: &Event| {};
    if let Err(e) = machine.run_program(EX4, Some(&mut handler), &mut ignore) {
        panic!("example 4 with {driver} failed: {e}");
    }
    let records: Vec<Record> = handler.take_records();
    let captures = records.iter().filter(|r| r.mcode == 281).count() as u64;
    let setup = records.iter().rev().find_map(Record::applied_gcode).expect("M282 ran").to_vec();
    let worst = grid().iter().map(|p| machine.cut_error(&setup, "demo target", *p).expect("cut")).fold(0.0, f64::max);
    (worst, captures, sim.frames_rendered())
}

/// The worlds compared: the built-in one, and variations of the part, the camera, the focus,
/// the light, the print and the clutter.
fn worlds() -> Vec<(&'static str, World)> {
    let base = World::default_world();
    let mut moved = base.clone();
    moved.seed = 7;
    moved.camera.rotation_deg = 1.5;
    moved.fixtures[0].rotation_deg = 2.0;
    moved.fixtures[0].shift = [0.1, -0.05];
    let mut defocused = base.clone();
    defocused.seed = 11;
    // 5 % farther than the focus: σ = 0.8 + 0.5 × 5 = 3.3 px of blur.
    defocused.camera.working_distance = 6.3;
    defocused.camera.image = Some(ImageLook { light_gradient_pct: 30.0, noise_grey: 4.0, ..ImageLook::default() });
    let mut rings = base.clone();
    rings.seed = 13;
    rings.camera.image = Some(ImageLook { mark: MarkKind::Ring, clutter: 12, ..ImageLook::default() });
    let mut crosses = base.clone();
    crosses.seed = 17;
    crosses.fixtures[0].rotation_deg = 4.0;
    crosses.camera.image =
        Some(ImageLook { mark: MarkKind::Cross, ink: 0.9, ground: 0.25, light: 0.8, ..ImageLook::default() });
    vec![
        ("built-in (dot, 20 % light gradient, σ 2 grey)", base),
        ("part turned 2°, camera 1.5°, seed 7", moved),
        ("defocused σ 3.3 px, 30 % gradient, σ 4 grey", defocused),
        ("rings, 12 clutter items", rings),
        ("light crosses on a dark part, part turned 4°", crosses),
    ]
}

#[test]
fn the_image_camera_lands_within_one_and_a_half_times_the_reading_cameras_cut_error() {
    println!("| world | reading mode (Sim) | image mode (SimImage) | frames |");
    println!("| --- | --- | --- | --- |");
    for (name, world) in worlds() {
        let (reading, ..) = example4(world.clone(), "Sim", |_, _| {});
        let (image, _, frames) = example4(world, "SimImage", |_, _| {});
        println!("| {name} | {reading:.6} in | {image:.6} in | {frames} |");
        assert!(image <= 1.5 * reading, "{name}: image mode {image} in, reading mode {reading} in");
    }
}

#[test]
fn run_goes_through_http_end_to_end() {
    let world = World::default_world();
    let (reading, ..) = example4(world.clone(), "Sim", |_, _| {});
    let mut server = None;
    let (image, captures, frames) = example4(world, "Camera", |sim, params| {
        // The server renders what the camera sees where the simulated machine is now.
        let mut frames = SimFrames(sim.clone());
        let s = SnapshotServer::bind("127.0.0.1:0", Encoding::Png, move || frames.frame().map_err(|e| e.to_string()))
            .expect("a loopback port");
        let config = vision_host::sim_image_config(sim, params).expect("settings");
        params.set("VisionCameraSource", s.url("/?action=snapshot").as_str()).expect("set");
        params.set("VisionCameraMarkDiameterPx", config.mark.diameter_px.expect("diameter")).expect("set");
        params.set("VisionCameraSearchRadius", config.mark.search_radius_pct).expect("set");
        // One stale frame thrown away per trigger, as after a move on a real camera.
        params.set("VisionCameraFlushFrames", 1_i64).expect("set");
        params.set("VisionCameraTimeout", 60.0).expect("set");
        server = Some(s);
    });
    let server = server.expect("started");
    // Every frame rendered was served: one at M280, where the driver learns the camera's frame
    // size (issue 33), then two per trigger (one flushed, one searched), at least one trigger
    // per M281 (re-centring adds more).
    assert_eq!(server.served(), frames);
    assert!(frames % 2 == 1 && frames > 2 * captures && captures == 4, "{frames} frames, {captures} M281");
    assert!(image <= 1.5 * reading, "through HTTP {image} in, reading mode {reading} in");
    let addr = server.addr();
    drop(server);
    // Stopped: nothing listens any more.
    assert!(std::net::TcpStream::connect_timeout(&addr, std::time::Duration::from_millis(200)).is_err());
}

/// The camera settings `run --camera camera` without `--source` sets for its own loopback
/// snapshot server (issue 33): its URL, timeout, flush count and the simulated operator's mark
/// settings.
const LOOPBACK_SETTINGS: [&str; 7] = [
    "VisionCameraSource",
    "VisionCameraTimeout",
    "VisionCameraSearchRadius",
    "VisionCameraFlushFrames",
    "VisionCameraMarkDiameterPx",
    "VisionCameraMark",
    "VisionCameraPolarity",
];

/// Runs example 3 (a quick calibration, which saves the profile) with `run --camera camera`
/// and no `--source` into `profile`, and reads the profile back.
fn calibrate_into(profile: &std::path::Path) -> Params {
    let example =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/programs/03-quick-diameter-cal.nc");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_mach-vision"))
        .args(["run", "--camera", "camera", "--profile"])
        .arg(profile)
        .arg(example)
        .output()
        .expect("spawn");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let registry = vision_host::cameras(None);
    let saved = vision_core::ProfileStore::new(profile).with_defaults(registry.params()).load().expect("saved");
    assert!(saved.get("VisionCal_K11").expect("K11").as_f64().is_some_and(|k| k > 0.0), "M283 saved K");
    // The record of what it was calibrated with (issue 33): the driver and the mark it searched for.
    assert_eq!(saved.get("VisionCal_Driver").expect("driver").to_string(), "\"Camera\"");
    assert_eq!(saved.get("VisionCal_Mark").expect("mark").to_string(), "\"dot, dark on light\"");
    saved
}

/// Issue 33: the CLI's own loopback server settings (a `127.0.0.1` URL that dies with the run,
/// a 60 s timeout, a search radius for the simulated camera) are this session's, never saved:
/// a new profile gets the defaults, an existing one keeps what the user wrote.
#[test]
fn the_loopback_cameras_settings_are_not_saved_into_the_profile() {
    let dir = std::env::temp_dir().join(format!("mach-vision-loopback-profile-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch");
    let defaults = vision_host::cameras(None).params();

    let fresh = calibrate_into(&dir.join("new.toml"));
    for name in LOOPBACK_SETTINGS {
        assert_eq!(fresh.get(name).expect(name), defaults.get(name).expect(name), "{name} in a new profile");
    }
    let text = std::fs::read_to_string(dir.join("new.toml")).expect("read");
    // The loopback server's URL (`http://127.0.0.1:PORT/snapshot`) is the session's, never saved.
    assert!(!text.contains("/snapshot\""), "{text}");

    let user = dir.join("user.toml");
    std::fs::write(
        &user,
        "[vision]\nVisionEnabled = true\nVisionCameraToolNumber = 98\n\n[camera]\n\
         VisionCameraSource = \"/dev/video0\"\nVisionCameraTimeout = 7.5\nVisionCameraSearchRadius = 40.0\n",
    )
    .expect("write");
    let kept = calibrate_into(&user);
    assert_eq!(kept.get("VisionCameraSource").expect("source"), vision_core::ParamValue::Text("/dev/video0".into()));
    assert_eq!(kept.get("VisionCameraTimeout").expect("timeout").as_f64(), Some(7.5));
    assert_eq!(kept.get("VisionCameraSearchRadius").expect("radius").as_f64(), Some(40.0));
    for name in &LOOPBACK_SETTINGS[3..] {
        assert_eq!(kept.get(name).expect(name), defaults.get(name).expect(name), "{name} the user never set");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 33: a V4L2 device path that names no device is reported as a missing device, with
/// its path, not as "connection refused" (there is no connection to a local device).
#[test]
fn a_missing_video_device_is_named_as_missing() {
    let example = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/programs/04-rectangle-fit.nc");
    for device in ["/dev/video-mach-vision-none", "v4l2:/dev/v4l/by-id/mach-vision-none"] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_mach-vision"))
            .args(["run", "--camera", "camera", "--source", device])
            .arg(&example)
            .output()
            .expect("spawn");
        assert!(!out.status.success());
        let stderr = String::from_utf8_lossy(&out.stderr);
        let path = device.trim_start_matches("v4l2:");
        assert!(
            stderr.contains(&format!("the video device {path} does not exist — check the camera is plugged in")),
            "{stderr}"
        );
        assert!(!stderr.contains("connection refused"), "{stderr}");
    }
}

/// Issue 33 item 3: `run --camera camera` (the simulated camera's frames served on loopback
/// and searched by the `Camera` driver, as `--camera simimage` searches them) calibrates with
/// example 1 and its lift measures the optical centre. The search window the image path sets
/// (`VisionCameraSearchRadius`: neighbouring marks outside it) held every probe of the walk
/// but not the corners of the lift's square grid, so every lift reading was lost and the centre
/// kept at (0, 0). A quarter-size camera over the same field (444² px at 0.00812 in/px; the
/// geometry in pixels is the built-in world's / 4) keeps the test's frames small.
#[test]
fn the_image_path_calibration_lift_measures_the_optical_centre() {
    let mut world = World::default_world();
    world.camera.resolution = [444, 444];
    world.camera.units_per_pixel *= 4.0;
    let bias = world.camera.center_bias_px;
    let dir = std::env::temp_dir().join(format!("mach-vision-image-lift-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let path = dir.join("world.toml");
    std::fs::write(&path, world.to_toml().expect("a world")).expect("write");
    let example = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/programs/01-calibrate-sheet.nc");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_mach-vision"))
        .args(["run", "--json", "--camera", "camera", "--world"])
        .arg(&path)
        .arg(example)
        .output()
        .expect("spawn");
    let _ = std::fs::remove_dir_all(&dir);
    assert!(out.status.success(), "stderr: {}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let cal = report["programs"][0]["steps"]
        .as_array()
        .expect("steps")
        .iter()
        .find(|s| s["type"] == "sheet_calibration")
        .expect("the calibration");
    let centre = &cal["centre"];
    assert_eq!((&centre["measured"], &centre["pairs"]), (&serde_json::Value::Bool(true), &25.into()), "{cal}");
    assert!(cal["warning"].is_null(), "{cal}");
    // Where the camera has it, within 3σ.
    let sigma = centre["sigma_px"].as_f64().expect("σ");
    for (axis, truth) in bias.iter().enumerate() {
        let got = centre["offset_px"][axis].as_f64().expect("offset");
        assert!((got - truth).abs() < 3.0 * sigma, "axis {axis}: {got} px, truth {truth} px, σ {sigma} px");
    }
}
