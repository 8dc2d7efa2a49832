//! `mach-vision run --dialect grbl` simulates a Grbl machine behind mach-vision as the sender:
//! the program runs in the host's interpreter, M282 hands the host the whole chain (scale
//! included) and the host maps every later move. The examples are Grbl's versions in
//! `hosts/grbl/examples/`; the truth is the simulator's.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

/// A scratch folder of this test process.
fn scratch(name: &str) -> PathBuf {
    crate::common::scratch("grbl", name)
}

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../hosts/grbl/examples").join(name)
}

/// `mach-vision run --dialect grbl --json PROGRAM` on the built-in world: exit status, stdout,
/// stderr.
fn run(program: &Path) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_mach-vision"))
        .args(["run", "--dialect", "grbl", "--json"])
        .arg(program)
        .output()
        .expect("spawn");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The M282 step of example `name`'s `--json` report.
fn fit_of(name: &str) -> Value {
    let (ok, out, err) = run(&example(name));
    assert!(ok, "{name}: {err}");
    let report: Value = serde_json::from_str(&out).expect("JSON");
    let steps = report["programs"][0]["steps"].as_array().expect("steps").clone();
    steps.into_iter().find(|s| s["type"] == "fit").expect("a fit")
}

/// Example 4 on Grbl: no G-code runs for the alignment, the host applies the whole chain with
/// both scales, and the cut lands on the true part as on Mach4.
#[test]
fn example_4_is_applied_by_the_host_with_the_scale_and_lands_on_the_true_part() {
    let fit = fit_of("04-rectangle-fit.nc");
    assert_eq!(fit["gcode"].as_array().map(Vec::len), Some(0), "{fit}");
    assert_eq!(fit["applied_by"], "host", "{fit}");
    let (sx, sy) = (fit["chain"]["scale"][0].as_f64(), fit["chain"]["scale"][1].as_f64());
    assert!(sx.zip(sy).is_some_and(|(x, y)| x > 1.0005 && y > 1.0008), "the print's scale applied: {fit}");
    let landed = fit["cut_error"]["max"].as_f64().expect("the truth");
    assert!(landed < 0.0005, "example 4 lands {landed} in from the true part");
}

/// Example 5 fits a similarity and the host applies it (its landing is the similarity's, as on
/// Mach4: the print's two scales differ).
#[test]
fn example_5_fits_a_similarity_applied_by_the_host() {
    let fit = fit_of("05-similarity-fit.nc");
    assert_eq!(fit["applied_by"], "host", "{fit}");
    let scale = &fit["chain"]["scale"];
    assert_eq!(scale[0], scale[1], "a similarity: {fit}");
    let landed = fit["cut_error"]["max"].as_f64().expect("the truth");
    assert!(landed < 0.002, "example 5 lands {landed} in from the true part");
}

/// Example 1 on Grbl walks the sheet with the manual's `M283 C1` (the host reads it) and finds
/// the camera's offset.
#[test]
fn example_1_calibrates_with_m283_c1() {
    let (ok, out, err) = run(&example("01-calibrate-sheet.nc"));
    assert!(ok, "{err}");
    let report: Value = serde_json::from_str(&out).expect("JSON");
    let truth = &report["programs"][0]["calibration_truth"];
    assert!(truth["offset_error"].as_f64().expect("the truth") < 0.001, "{truth}");
    assert!(truth["k_relative"].as_f64().expect("the truth") < 0.001, "{truth}");
}

/// G68, G51 and G52 do not exist on Grbl: each is refused naming Grbl, before anything moves.
#[test]
fn rotation_scale_and_local_shift_are_refused_naming_grbl() {
    let dir = scratch("refused");
    for (code, line) in [("G68", "G68 X0 Y0 R30"), ("G51", "G51 X2 Y2"), ("G52", "G52 X1 Y1")] {
        let program = dir.join(format!("{code}.nc"));
        std::fs::write(&program, format!("G20 G90\n{line}\nG0 X1 Y1\nM30\n")).expect("write");
        let (ok, _, err) = run(&program);
        assert!(!ok, "{code} ran");
        assert!(err.contains(&format!("{code} is not supported")), "{code}: {err}");
        assert!(err.contains("Grbl does not have (error:20 on the firmware)"), "{code}: {err}");
    }
}
