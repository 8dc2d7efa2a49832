//! What a distorting lens costs the linear pixel chain today: a measurement, not a gate.
//!
//! Run: `cargo test -p vision-cli --test it lens -- --ignored --nocapture`.
//! For each lens and each noise seed of the built-in world (`seed` = 1..=SEEDS, the world
//! otherwise unchanged), `mach-vision run --world W --profile P --json` runs example 1 then
//! example 4, and in a fresh profile example 1 then example 5; each fit's cut error (the
//! report's `cut_error.max`, inches) and its ratio to the least-squares floor (the fit's
//! predicted 1σ for the camera's noise alone, `sigma × camera_noise / noise`, as in
//! `acceptance.rs`) are printed as median, p95 and worst.

use std::path::{Path, PathBuf};

/// Noise seeds per lens.
const SEEDS: u64 = 40;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// `(cut error in inches, cut over the floor)` of the last fit of example 1 then `program`.
fn measure(dir: &Path, world: &Path, program: &str) -> (f64, f64) {
    let profile = dir.join("P.toml");
    for f in ["P.toml", "P.machine.toml"] {
        let _ = std::fs::remove_file(dir.join(f));
    }
    let programs = root().join("examples/programs");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_mach-vision"))
        .args(["run", "--json", "--world"])
        .arg(world)
        .arg("--profile")
        .arg(&profile)
        .arg(programs.join("01-calibrate-sheet.nc"))
        .arg(programs.join(program))
        .output()
        .expect("spawn");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON report");
    let steps = report["programs"][1]["steps"].as_array().expect("steps");
    let fit = steps.iter().rev().find(|s| s["type"] == "fit").expect("a fit");
    let cut = fit["cut_error"]["max"].as_f64().expect("cut error");
    let p = &fit["predicted"];
    let floor = p["sigma"].as_f64().expect("sigma") * p["camera_noise"].as_f64().expect("camera noise")
        / p["noise"].as_f64().expect("noise");
    (cut, cut / floor)
}

/// Median, p95 (nearest rank) and worst of `v`.
fn spread(mut v: Vec<f64>) -> (f64, f64, f64) {
    v.sort_by(f64::total_cmp);
    let at = |pct: usize| v[(pct * v.len()).div_ceil(100).clamp(1, v.len()) - 1];
    (at(50), at(95), v[v.len() - 1])
}

#[test]
#[ignore = "a measurement (320 runs of the binary), not a gate; run it by hand"]
fn what_a_distorting_lens_costs_the_linear_chain() {
    let dir = std::env::temp_dir().join(format!("mach-vision-lens-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let text = std::fs::read_to_string(root().join("vision-driver-sim/src/default_world.toml")).expect("world");
    let lenses = [
        ("none", None),
        ("k1 -0.10", Some("[-0.10, 0.0, 0.0, 0.0, 0.0]")),
        ("k1 +0.08, k2 -0.02", Some("[0.08, -0.02, 0.0, 0.0, 0.0]")),
        ("k1 -0.10, p1/p2 0.002/-0.001", Some("[-0.10, 0.0, 0.002, -0.001, 0.0]")),
    ];
    println!("| lens | example | cut median / p95 / worst (in) | cut / floor median / p95 / worst |");
    println!("| --- | --- | --- | --- |");
    for (name, lens) in lenses {
        for program in ["04-rectangle-fit.nc", "05-similarity-fit.nc"] {
            let (mut cuts, mut ratios) = (Vec::new(), Vec::new());
            for seed in 1..=SEEDS {
                let mut world = text.replacen("seed = 1 ", &format!("seed = {seed} "), 1);
                if let Some(d) = lens {
                    world =
                        world.replacen("# distortion = [-0.10, 0.0, 0.0, 0.0, 0.0]", &format!("distortion = {d}"), 1);
                }
                assert_eq!(world.contains("\ndistortion = "), lens.is_some(), "the world edit took");
                let path = dir.join("W.toml");
                std::fs::write(&path, world).expect("write world");
                let (cut, ratio) = measure(&dir, &path, program);
                cuts.push(cut);
                ratios.push(ratio);
            }
            let (c, r) = (spread(cuts), spread(ratios));
            println!(
                "| {name} | {} | {:.5} / {:.5} / {:.5} | {:.2} / {:.2} / {:.2} |",
                &program[..2],
                c.0,
                c.1,
                c.2,
                r.0,
                r.1,
                r.2
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
