//! `mach-vision locate` through the built binary, on images rendered with known truth.

use std::path::PathBuf;
use std::process::{Command, Output};

use vision_locate::render::{render, Depth, PlacedMark, Scene, Shape};
use vision_locate::OwnedPixels;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mach-vision"))
}

fn dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("locate_cli");
    std::fs::create_dir_all(&d).expect("scratch dir");
    d
}

/// Renders a 200 × 150 image, with a dark dot of 40 px at (`x`, `y`) when given, and saves it
/// as `name` (the extension picks the format; `rgb` stores it as colour).
fn save(name: &str, mark: Option<(f64, f64)>, depth: Depth, rgb: bool) -> PathBuf {
    let scene = Scene {
        marks: mark
            .map(|(x, y)| PlacedMark { shape: Shape::Dot { diameter: 40.0 }, x, y, reflectance: 0.1 })
            .into_iter()
            .collect(),
        blur_sigma: 1.0,
        noise_sigma: if depth == Depth::Eight { 1.5 } else { 1.5 * 257.0 },
        seed: 9,
        ..Scene::blank(200, 150, depth)
    };
    let path = dir().join(name);
    match render(&scene).expect("scene").into_pixels() {
        OwnedPixels::Gray8(px) if rgb => {
            let rgb: Vec<u8> = px.iter().flat_map(|&v| [v, v, v]).collect();
            image::RgbImage::from_raw(200, 150, rgb).expect("size").save(&path).expect("save");
        }
        OwnedPixels::Gray8(px) => image::GrayImage::from_raw(200, 150, px).expect("size").save(&path).expect("save"),
        OwnedPixels::Gray16(px) => {
            image::ImageBuffer::<image::Luma<u16>, _>::from_raw(200, 150, px).expect("size").save(&path).expect("save");
        }
    }
    path
}

fn run(args: &[&str]) -> Output {
    bin().arg("locate").args(args).output().expect("run mach-vision")
}

fn json_lines(out: &Output) -> Vec<serde_json::Value> {
    String::from_utf8(out.stdout.clone())
        .expect("utf-8")
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON"))
        .collect()
}

#[test]
fn finds_the_dot_in_png_jpeg_pgm_bmp_16_bit_and_colour() {
    let files = [
        save("dot.png", Some((101.3, 70.6)), Depth::Eight, false),
        save("dot.pgm", Some((101.3, 70.6)), Depth::Eight, false),
        save("dot.bmp", Some((101.3, 70.6)), Depth::Eight, true),
        save("dot16.png", Some((101.3, 70.6)), Depth::Sixteen, false),
        save("dot_rgb.png", Some((101.3, 70.6)), Depth::Eight, true),
        save("dot.jpg", Some((101.3, 70.6)), Depth::Eight, false),
    ];
    let mut args = vec!["--diameter", "40", "--json"];
    args.extend(files.iter().map(|p| p.to_str().expect("utf-8 path")));
    let out = run(&args);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let lines = json_lines(&out);
    assert_eq!(lines.len(), files.len());
    for o in &lines {
        assert_eq!(o["found"], true, "{o}");
        let (x, y) = (o["x"].as_f64().unwrap(), o["y"].as_f64().unwrap());
        assert!((x - 101.3).abs() < 0.05 && (y - 70.6).abs() < 0.05, "{o}");
        assert!((o["diameter"].as_f64().unwrap() - 40.0).abs() < 0.5, "{o}");
        assert!(o["score"].as_f64().unwrap() > 0.8, "{o}");
    }
    // The readable form says the same.
    let out = run(&["--diameter", "40", files[0].to_str().unwrap()]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("found x=101.3") && text.contains("y=70.6"), "{text}");
}

/// A profile for the 200 × 150 images of [`save`], its optical centre (3, −2) px off the
/// image's, with `lens` (the `[vision]` lines) added.
fn lens_profile(name: &str, lens: &str) -> PathBuf {
    let path = dir().join(name);
    let text = format!(
        "[vision]\nVisionCameraResX = 200\nVisionCameraResY = 150\nVisionPxCenterOffsetX = 3.0\n\
         VisionPxCenterOffsetY = -2.0\n{lens}"
    );
    std::fs::write(&path, text).expect("write profile");
    path
}

#[test]
fn with_a_profile_each_mark_is_also_given_with_the_lens_undone() {
    let image = save("lens.png", Some((160.3, 40.6)), Depth::Eight, false);
    let lens = "VisionLensK1 = -0.1\nVisionLensK2 = 0.01\nVisionLensP1 = 0.002\nVisionLensP2 = -0.001\n\
                VisionLensFocalPx = 150.0\n";
    let with_lens = lens_profile("lens.toml", lens);
    let without = lens_profile("no-lens.toml", "VisionLensK1 = -0.1\n");
    let i = image.to_str().unwrap();
    let json = |profile: &PathBuf| {
        let out = run(&["--diameter", "40", "--json", "--profile", profile.to_str().unwrap(), i]);
        assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
        json_lines(&out).remove(0)
    };
    let xy = |v: &serde_json::Value| (v["x"].as_f64().unwrap(), v["y"].as_f64().unwrap());

    // The reading's native pixel (corner origin, half a pixel from locate's) less the optical
    // centre, undone through the lens and put back.
    let o = json(&with_lens);
    let (x, y) = xy(&o);
    assert_eq!(xy(&o["distorted"]), (x, y), "{o}");
    let l = vision_math::Lens::new([-0.1, 0.01, 0.002, -0.001], 150.0).unwrap();
    let origin = vision_math::Vector2::new(103.0, 73.0);
    let want = l.undistort(vision_math::Vector2::new(x + 0.5, y + 0.5) - origin) + origin;
    let (ux, uy) = xy(&o["undistorted"]);
    // Within what the chain's fitted chord steps are exact to.
    let tolerance = vision_math::lens::FIELD_TOLERANCE_PX;
    assert!((ux + 0.5 - want.x).abs() < tolerance && (uy + 0.5 - want.y).abs() < tolerance, "{o} vs {want}");
    assert!((ux - x).hypot(uy - y) > 0.5, "the lens moves this mark by more than half a pixel: {o}");

    // VisionLensFocalPx 0 is no lens: the same pixel twice, and no text added.
    let o = json(&without);
    assert_eq!((xy(&o["distorted"]), xy(&o["undistorted"])), (xy(&o), xy(&o)), "{o}");
    let text = |profile: &PathBuf| {
        let out = run(&["--diameter", "40", "--profile", profile.to_str().unwrap(), i]);
        String::from_utf8(out.stdout).unwrap()
    };
    assert!(!text(&without).contains("undistorted"), "{}", text(&without));
    let t = text(&with_lens);
    assert!(t.trim_end().ends_with(&format!(" undistorted ({ux:.4}, {uy:.4})")), "{t}");

    // Without --profile the JSON is as before.
    let out = run(&["--diameter", "40", "--json", i]);
    assert!(json_lines(&out)[0].get("undistorted").is_none());
}

#[test]
fn a_bad_profile_or_an_image_of_another_size_exits_2() {
    let image = save("lens-bad.png", Some((100.0, 75.0)), Depth::Eight, false);
    let folds = lens_profile("folds.toml", "VisionLensK1 = -3.0\nVisionLensFocalPx = 150.0\n");
    let garbled = dir().join("garbled.toml");
    std::fs::write(&garbled, "[vision]\nVisionLensK1 = \"barrel\"\n").unwrap();
    let other_size = dir().join("other-size.toml");
    std::fs::write(&other_size, "[vision]\nVisionLensK1 = -0.1\nVisionLensFocalPx = 2956.0\n").unwrap();
    for (profile, says) in [
        (dir().join("absent.toml"), "no profile"),
        (garbled, "VisionLensK1"),
        (folds, "fold"),
        (other_size, "1776 x 1776"),
    ] {
        let out = run(&["--diameter", "40", "--profile", profile.to_str().unwrap(), image.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{profile:?}: {err}");
        assert!(out.stdout.is_empty() && err.contains(says), "{profile:?}: {err}");
    }
}

#[test]
fn an_image_without_the_mark_exits_1_with_the_reason() {
    let good = save("good.png", Some((100.0, 75.0)), Depth::Eight, false);
    let blank = save("blank.png", None, Depth::Eight, false);
    let cut = save("cut.png", Some((3.0, 75.0)), Depth::Eight, false);
    let out =
        run(&["--diameter", "40", "--json", good.to_str().unwrap(), blank.to_str().unwrap(), cut.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let lines = json_lines(&out);
    assert_eq!(lines[0]["found"], true);
    assert_eq!(lines[1]["found"], false);
    assert_eq!(lines[1]["reason"], "no_candidate");
    assert_eq!(lines[2]["reason"], "clipped");
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("2 of 3 images"), "{err}");
    // Size out of range carries the measured size.
    let out = run(&["--diameter", "25", "--tolerance", "10", "--json", good.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let o = &json_lines(&out)[0];
    assert_eq!(o["reason"], "size_out_of_range");
    assert!((o["diameter"].as_f64().unwrap() - 40.0).abs() < 0.5, "{o}");
}

#[test]
fn bad_input_exits_2() {
    let good = save("ok.png", Some((100.0, 75.0)), Depth::Eight, false);
    let junk = dir().join("junk.png");
    std::fs::write(&junk, b"not an image").unwrap();
    let g = good.to_str().unwrap();
    for args in [
        vec!["--diameter", "40", "/nonexistent/frame.png"],
        vec!["--diameter", "40", junk.to_str().unwrap()],
        vec!["--diameter", "40", "--mark", "hexagon", g],
        vec!["--diameter", "-3", g],
        vec!["--diameter", "NaN", g],
        vec!["--diameter", "40", "--tolerance", "150", g],
        vec!["--diameter", "40", "--polarity", "grey", g],
        vec![g],
        vec!["--diameter", "40"],
    ] {
        let out = run(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
        assert!(out.stdout.is_empty(), "{args:?}");
    }
}

#[test]
fn a_wrong_diameter_names_the_size_seen_and_the_size_expected() {
    // Issue 33: `--diameter 10` on a 40 px dot said "no mark in view — check the position, focus
    // and lighting"; a fitted mark of the wrong size did not say which size was expected.
    let good = save("wrong-size.png", Some((100.0, 75.0)), Depth::Eight, false);
    let g = good.to_str().unwrap();
    let text = |args: &[&str]| {
        let out = run(args);
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        String::from_utf8(out.stdout).expect("utf-8")
    };
    assert_eq!(
        text(&["--diameter", "10", g]),
        format!(
            "{g}: not found: no mark of 7.5–12.5 px in view, but a blob about 39 px across is — check the diameter setting (or the position, focus and lighting)\n"
        )
    );
    assert_eq!(
        text(&["--diameter", "25", "--tolerance", "10", g]),
        format!("{g}: not found: a mark of 39.9 px is in view, but 22.5–27.5 px was expected — check the diameter setting\n")
    );
    let out = run(&["--diameter", "10", "--json", g]);
    let o = &json_lines(&out)[0];
    assert_eq!(
        (o["reason"].as_str(), o["min"].as_f64(), o["max"].as_f64()),
        (Some("other_size"), Some(7.5), Some(12.5))
    );
    assert!((o["about"].as_f64().unwrap() - 40.0).abs() <= 2.0, "{o}");
    // Nothing at all in view keeps its advice.
    let blank = save("wrong-size-blank.png", None, Depth::Eight, false);
    let b = blank.to_str().unwrap();
    assert_eq!(
        text(&["--diameter", "10", b]),
        format!("{b}: not found: no mark in view — check the position, focus and lighting\n")
    );
}

#[test]
fn m281_with_a_wrong_camera_diameter_names_the_size_seen_and_the_settings() {
    // Issue 33: the Camera driver's NG said "no mark in view — check the position, focus and
    // lighting" when VisionCameraMarkDiameterPx was wrong. Calibrate a profile on the simulated
    // camera's rendered frames (the quick M283 Q: K is all M281 needs), then set the diameter to
    // a quarter of the marks' 246 px.
    let profile = dir().join("wrong-diameter.toml");
    let _ = std::fs::remove_file(&profile);
    let p = profile.to_str().unwrap();
    let programs = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/programs/");
    let run_program = |name: &str| {
        bin().args(["run", "--camera", "simimage", "--profile", p, &format!("{programs}{name}")]).output().expect("run")
    };
    let out = run_program("03-quick-diameter-cal.nc");
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&profile).expect("profile");
    assert!(text.contains("VisionCameraMarkDiameterPx = 0.0\n"), "{text}");
    std::fs::write(&profile, text.replace("VisionCameraMarkDiameterPx = 0.0\n", "VisionCameraMarkDiameterPx = 60.0\n"))
        .expect("write");
    let out = run_program("04-rectangle-fit.nc");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(
            "M281 failed: NG / no mark found — the camera job did not find a fiducial in the field of view (the finder: \
             no mark of 45.0–75.0 px in view, but a blob about 248 px across is — check VisionCameraMarkDiameterPx (60 \
             px) and VisionCameraMarkTolerance (25 %) (or the position, focus and lighting)); re-jog"
        ),
        "{err}"
    );
}
