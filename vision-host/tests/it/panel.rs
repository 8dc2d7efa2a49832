//! The panel folder: a session running a program with a profile publishes its state beside the
//! profile, the reader reads it back, and garbage is refused with a typed error.

use std::path::{Path, PathBuf};
use std::time::Duration;

use proptest::prelude::*;
use vision_core::{ParamValue, ProfileStore};
use vision_driver_sim::{Sim, SimMachine};
use vision_host::panel::{self, PanelReadError, PanelState, PanelValue, Publisher};
use vision_host::testkit::{clock, example, sim, sim_params};
use vision_host::{cameras, HostError, ProgramHandler, Session};

/// A fresh folder under the system's temp folder.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vision-host-panel-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("tmp");
    dir
}

/// A publishing session of profile `path` (the simulated world, calibrated) in a program handler.
fn handler(sim: &Sim, path: &Path) -> ProgramHandler {
    let mut session = Session::open(path, &cameras(Some(sim))).expect("open");
    assert_eq!(session.publish(), Some(panel::panel_dir(path).as_path()));
    ProgramHandler::new(session, &vision_host::controller::Mach4, clock())
}

/// Runs `program` through `handler`, then waits for the publisher and reads the folder.
fn run(sim: &Sim, handler: &mut ProgramHandler, program: &str, dir: &Path) -> PanelState {
    let mut machine = SimMachine::new(sim).expect("machine");
    let end = machine.run_program(program, Some(handler), &mut |_: &vision_gcode::Event| {});
    assert!(end.is_ok(), "{end:?}");
    let publisher = handler.session().publisher().expect("publishing");
    assert!(publisher.flush(Duration::from_secs(10)), "the writer caught up");
    panel::read(dir).expect("the published state reads back")
}

#[test]
fn a_session_with_a_profile_publishes_its_state_beside_it_and_the_sequence_grows() {
    let sim = sim();
    let tmp = scratch("publish");
    let path = tmp.join("shop.toml");
    ProfileStore::new(&path).save(&sim_params(&sim)).expect("profile");
    let dir = tmp.join("shop.panel");

    let mut h = handler(&sim, &path);
    let state = run(&sim, &mut h, &example("04-rectangle-fit.nc"), &dir);
    assert_eq!(state.format, panel::FORMAT);
    assert!(state.seq > 0 && state.time_unix > 1.0e9, "{} {}", state.seq, state.time_unix);
    assert_eq!(state.profile, path.display().to_string());
    assert_eq!(state.telemetry.get("VisionLastStatus"), Some(&PanelValue::Text("OK".to_string())));
    assert_eq!(state.telemetry.get("VisionRun_Active"), Some(&PanelValue::Int(0)));
    assert_eq!(state.params.get("VisionEnabled"), Some(&PanelValue::Bool(true)));
    let last = state.last.as_ref().expect("the last call");
    assert!(last.ok && last.mcode == 282 && last.message.starts_with("M282:"), "{last:?}");
    assert!(last.gcode.iter().any(|l| l.contains("G68")), "{:?}", last.gcode);
    assert!(last.report.is_some());
    assert_eq!(state.dots.len(), 4);
    assert_eq!(state.frame, None, "the simulator keeps no image without M281 D1");

    // The getter reads what the state shows, telemetry included.
    let session = h.session();
    assert_eq!(session.param("visionlaststatus"), Ok(ParamValue::Text("OK".to_string())));
    assert_eq!(session.param("VisionRun_DotCount"), Ok(ParamValue::Int(4)));
    assert_eq!(session.param("VisionEnabled"), Ok(ParamValue::Bool(true)));
    let unknown = session.param("VisionNoSuch").expect_err("unknown");
    assert!(matches!(unknown, HostError::Param(_)) && unknown.to_string().contains("VisionNoSuch"), "{unknown}");

    // A refusal is published too: its message as the status, the call as failed.
    let program = "G90 G20\nT98 M6\nG0 X20.0 Y20.0\nM281\nM30\n";
    let mut machine = SimMachine::new(&sim).expect("machine");
    let end = machine.run_program(program, Some(&mut h), &mut |_: &vision_gcode::Event| {});
    assert!(end.is_err());
    assert!(h.session().publisher().expect("publishing").flush(Duration::from_secs(10)));
    let refused = panel::read(&dir).expect("state");
    assert!(refused.seq > state.seq, "{} after {}", refused.seq, state.seq);
    let last = refused.last.expect("the refusal");
    assert!(!last.ok && last.mcode == 281, "{last:?}");
    let Some(PanelValue::Text(status)) = refused.telemetry.get("VisionLastStatus") else { panic!("no status") };
    assert!(status != "OK" && last.message.contains(status.as_str()), "{status:?} / {:?}", last.message);

    // A new session on the profile goes on from the folder's number.
    drop(h);
    let mut again = handler(&sim, &path);
    let next = run(&sim, &mut again, "T98 M6\nM280\nM30\n", &dir);
    assert!(next.seq > refused.seq, "{} after {}", next.seq, refused.seq);
    let _ = std::fs::remove_dir_all(&tmp);
}

#[test]
fn an_unwritable_folder_is_reported_once_and_never_stops_a_program() {
    let sim = sim();
    let tmp = scratch("unwritable");
    let path = tmp.join("shop.toml");
    ProfileStore::new(&path).save(&sim_params(&sim)).expect("profile");
    // A file where the folder should be.
    std::fs::write(tmp.join("shop.panel"), "not a folder").expect("file");
    let mut h = handler(&sim, &path);
    for _ in 0..2 {
        let mut machine = SimMachine::new(&sim).expect("machine");
        let end = machine.run_program(&example("04-rectangle-fit.nc"), Some(&mut h), &mut |_: &vision_gcode::Event| {});
        assert!(end.is_ok(), "{end:?}");
    }

    let publisher = Publisher::start(tmp.join("shop.panel"), &path);
    publisher.record(h.session().module(), None);
    assert!(publisher.flush(Duration::from_secs(10)));
    let problem = publisher.take_problem().expect("the failure is told");
    assert!(problem.contains("shop.panel") && problem.contains("cannot be written"), "{problem}");
    publisher.record(h.session().module(), None);
    assert!(publisher.flush(Duration::from_secs(10)));
    assert_eq!(publisher.take_problem(), None, "told once");
    let _ = std::fs::remove_dir_all(&tmp);
}

#[test]
fn the_reader_names_what_is_wrong() {
    let tmp = scratch("reader");
    assert!(matches!(panel::read(&tmp), Err(PanelReadError::Missing { .. })));
    let state = tmp.join(panel::STATE_FILE);
    for (text, want) in
        [("", "Malformed"), ("{\"format\": 2}", "Format"), ("{\"format\": 1}", "Malformed"), ("[1, 2]", "Malformed")]
    {
        std::fs::write(&state, text).expect("write");
        let e = panel::read(&tmp).expect_err(text);
        assert!(format!("{e:?}").starts_with(want), "{text:?}: {e:?}");
    }
    let big = vec![b' '; usize::try_from(panel::MAX_STATE_BYTES).expect("fits") + 1];
    std::fs::write(&state, big).expect("write");
    assert!(matches!(panel::read(&tmp), Err(PanelReadError::TooLarge { .. })));
    let _ = std::fs::remove_dir_all(&tmp);
}

/// A state the writer could write: the base for the mutations below.
fn good_state() -> String {
    r#"{"format":1,"seq":7,"time_unix":1800000000.5,"profile":"/p.toml",
"params":{"VisionEnabled":true,"VisionActiveJob":2,"VisionCal_K11":0.002,"VisionCal_Units":"in"},
"telemetry":{"VisionLastStatus":"OK"},"last":{"mcode":281,"ok":true,"message":"M281: mark captured",
"gcode":[],"report":{"score":0.9}},"dots":[{"commanded":[0,0],"observed":[0.01,-0.02],"unit":"in"}],
"frame":"frame.png"}"#
        .to_string()
}

#[test]
fn a_good_state_parses() {
    let state = panel::parse(good_state().as_bytes(), "state.json").expect("parses");
    assert_eq!(state.seq, 7);
    assert_eq!(state.params.get("VisionActiveJob"), Some(&PanelValue::Int(2)));
    assert_eq!(state.frame.as_deref(), Some(panel::FRAME_FILE));
    let elsewhere = good_state().replace("\"frame.png\"", "\"../../etc/passwd\"");
    assert!(matches!(panel::parse(elsewhere.as_bytes(), "s"), Err(PanelReadError::Invalid { .. })));
    let negative = good_state().replace("1800000000.5", "-1");
    assert!(matches!(panel::parse(negative.as_bytes(), "s"), Err(PanelReadError::Invalid { .. })));
}

proptest! {
    /// Any bytes, and any cut or byte change of a good state, read as a state or a typed
    /// error: never a panic.
    #[test]
    fn garbage_is_refused_without_a_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        let _ = panel::parse(&bytes, "state.json");
    }

    #[test]
    fn a_damaged_state_is_refused_without_a_panic(cut in 0usize..600, at in 0usize..600, byte in any::<u8>()) {
        let good = good_state().into_bytes();
        let mut damaged = good[..cut.min(good.len())].to_vec();
        if !damaged.is_empty() {
            let i = at % damaged.len();
            damaged[i] = byte;
        }
        match panel::parse(&damaged, "state.json") {
            Ok(state) => prop_assert!(state.time_unix.is_finite()),
            Err(e) => prop_assert!(!e.to_string().is_empty()),
        }
    }
}

#[test]
fn the_image_m281_d1_keeps_becomes_the_folders_frame() {
    let sim = sim();
    let tmp = scratch("frame");
    let path = tmp.join("shop.toml");
    let mut params = sim_params(&sim);
    params.set("VisionDriver", vision_host::SIM_IMAGE).expect("a driver name");
    ProfileStore::new(&path).save(&params).expect("profile");
    let mut h = handler(&sim, &path);
    h.session_mut().module_mut().set_images_dir(tmp.join("Images"));
    let state = run(&sim, &mut h, "G90 G20\nT98 M6\nG0 X0 Y0\nM281 D1\nM30\n", &tmp.join("shop.panel"));
    assert_eq!(state.frame.as_deref(), Some(panel::FRAME_FILE), "{:?}", state.last);
    let frame = std::fs::read(tmp.join("shop.panel").join(panel::FRAME_FILE)).expect("frame.png");
    assert!(frame.starts_with(b"\x89PNG"), "a PNG");
    let _ = std::fs::remove_dir_all(&tmp);
}

/// Each calibration (another `VisionCal_Date`) joins the folder's history, across sessions, the
/// newest last and at most `MAX_CALIBRATIONS`; the same calibration published again does not.
#[test]
fn the_folder_keeps_the_calibrations_it_has_seen() {
    let sim = sim();
    let tmp = scratch("history");
    let (path, dir) = (tmp.join("shop.toml"), tmp.join("shop.panel"));
    let dated = |date: &str, k11: f64| {
        let mut params = sim_params(&sim);
        params.set("VisionCal_Date", date).expect("date");
        params.set("VisionCal_K11", k11).expect("k11");
        vision_core::VisionModule::new(params)
    };
    let publish = |module: &vision_core::VisionModule| {
        let publisher = Publisher::start(dir.clone(), &path);
        publisher.record(module, None);
        publisher.record(module, None);
        assert!(publisher.flush(Duration::from_secs(10)));
        panel::read(&dir).expect("reads back")
    };
    let first = publish(&dated("2026-11-01 09:00:00+00:00", 0.002));
    assert_eq!(first.calibrations.len(), 1, "{:?}", first.calibrations);
    assert_eq!(first.calibrations[0].date, "2026-11-01 09:00:00+00:00");
    assert_eq!(first.calibrations[0].values.get("VisionCal_K11"), Some(&PanelValue::Number(0.002)));
    let second = publish(&dated("2026-11-02 09:00:00+00:00", 0.0021));
    let dates: Vec<&str> = second.calibrations.iter().map(|c| c.date.as_str()).collect();
    assert_eq!(dates, ["2026-11-01 09:00:00+00:00", "2026-11-02 09:00:00+00:00"]);
    for day in 3..30 {
        publish(&dated(&format!("2026-11-{day:02} 09:00:00+00:00"), 0.002));
    }
    let last = panel::read(&dir).expect("reads back");
    assert_eq!(last.calibrations.len(), panel::MAX_CALIBRATIONS);
    assert_eq!(last.calibrations.last().map(|c| c.date.as_str()), Some("2026-11-29 09:00:00+00:00"));
    // A state listing more than a writer lists is not one of ours.
    let mut text: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join(panel::STATE_FILE)).expect("read")).expect("json");
    let extra = text["calibrations"][0].clone();
    text["calibrations"].as_array_mut().expect("list").push(extra);
    std::fs::write(dir.join(panel::STATE_FILE), text.to_string()).expect("write");
    assert!(matches!(panel::read(&dir), Err(PanelReadError::Invalid { .. })));
    let _ = std::fs::remove_dir_all(&tmp);
}

/// A camera's kept image becomes the folder's PNG frame: a PNG as it is, a JPEG or a BMP (a
/// Keyence camera's) re-encoded with its pixels; anything else is left out, a damaged image is
/// an error.
#[test]
fn a_kept_jpeg_or_bmp_becomes_a_png_frame() {
    let tmp = scratch("formats");
    let img = image::GrayImage::from_fn(40, 30, |x, y| image::Luma([u8::try_from((x * 6 + y) % 256).unwrap_or(0)]));
    for (name, format) in [("a.png", image::ImageFormat::Png), ("a.bmp", image::ImageFormat::Bmp)] {
        let path = tmp.join(name);
        img.save_with_format(&path, format).expect("written");
        let png = panel::frame_png(&path).expect("read").expect("an image");
        assert!(png.starts_with(b"\x89PNG"), "{name}");
        let back = image::load_from_memory(&png).expect("decodes").to_luma8();
        assert_eq!(back, img, "{name}: the same pixels");
    }
    let jpeg = tmp.join("a.jpg");
    img.save_with_format(&jpeg, image::ImageFormat::Jpeg).expect("written");
    let png = panel::frame_png(&jpeg).expect("read").expect("an image");
    assert_eq!(image::load_from_memory(&png).expect("decodes").to_luma8().dimensions(), (40, 30));
    let text = tmp.join("a.txt");
    std::fs::write(&text, "not an image").expect("written");
    assert_eq!(panel::frame_png(&text), Ok(None));
    let damaged = tmp.join("b.bmp");
    let bytes = std::fs::read(tmp.join("a.bmp")).expect("read");
    std::fs::write(&damaged, &bytes[..bytes.len() / 3]).expect("written");
    assert!(panel::frame_png(&damaged).is_err());
    assert!(panel::frame_png(&tmp.join("missing.png")).is_err());
    let _ = std::fs::remove_dir_all(&tmp);
}
