//! `mach-vision run --dialect` and the world's `machine.dialect` choose the control's G-code
//! rules (issue 14): a comment whose inner `(` is never closed ends at its first `)` for Mach4
//! (the default), and is an unclosed comment for seed 002 (whose comments nest).

use std::path::PathBuf;
use std::process::Command;

fn run(args: &[&str], dir: &str) -> String {
    let d = std::env::temp_dir().join(format!("mach-vision-dialect-{dir}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch dir");
    let program = d.join("nested.nc");
    std::fs::write(&program, "G90 G0 Y0 (outer (inner) X0\nM30\n").expect("write");
    let world_text =
        vision_driver_sim::DEFAULT_WORLD_TOML.replace("dialect = \"mach4\"", "dialect = \"machinemotion\"");
    let world: PathBuf = d.join("world.toml");
    std::fs::write(&world, world_text).expect("write");
    let args: Vec<String> =
        args.iter().map(|a| if *a == "WORLD" { world.display().to_string() } else { (*a).to_string() }).collect();
    let out =
        Command::new(env!("CARGO_BIN_EXE_mach-vision")).arg("run").args(&args).arg(&program).output().expect("spawn");
    String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr)
}

#[test]
fn the_dialect_comes_from_the_option_or_the_world() {
    let ended = "ended by M30 at line 2";
    let failed = "failed at line 1";
    let default = run(&[], "default");
    assert!(default.contains(ended), "{default}");
    let seed = run(&["--dialect", "machinemotion"], "option");
    assert!(seed.contains(failed), "{seed}");
    let world = run(&["--world", "WORLD"], "world");
    assert!(world.contains(failed), "{world}");
    let back = run(&["--world", "WORLD", "--dialect", "mach4"], "override");
    assert!(back.contains(ended), "{back}");
}
