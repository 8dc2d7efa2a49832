//! Issue 26's runaway programs through the built binary: refused at once with their bound's
//! message, in little memory and time.

use std::path::PathBuf;

fn scratch(name: &str, text: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bounded");
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write");
    path
}

use crate::common;

use common::bounded;

#[test]
fn a_canned_cycle_past_the_repeat_bound_is_refused_in_little_memory() {
    // Issue 26: `trace` aborted on a 3 GB allocation, `run` took 1.5 GB at L1000000.
    let program = scratch("cycle-l10m.ngc", "G20 G90 F10\nG0 Z1\nG91 G81 X0.001 Y0 Z-0.1 R0.1 L10000000\nG80\nM2\n");
    let path = program.to_str().expect("utf-8");
    for args in [["trace", "--dialect", "linuxcnc", path], ["run", "--dialect", "linuxcnc", path]] {
        let out = bounded(&args, 512, 60).unwrap_or_else(|| panic!("{args:?} ran out of time"));
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains("line 3: G81: `L10000000` exceeds the 100000 repeat bound"), "{args:?}: {err}");
    }
}

#[test]
fn a_path_past_the_setpoint_bound_is_refused_when_it_is_planned() {
    // Issue 26: a full circle of radius 1e9 was sampled for 45 s before the bound stopped it.
    let program = scratch("huge-circle.ngc", "G20 G90 F100\nG2 X0 Y0 I1000000000 J0\nM2\n");
    let path = program.to_str().expect("utf-8");
    let out = bounded(&["plan", "--accel", "100", path], 512, 20).expect("refused in time");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("line 2: the path runs longer than 1000000000 setpoints"), "{err}");
}

#[test]
fn run_of_a_million_moves_fits_in_a_small_address_space() {
    // Issue 26: `run` held every move, 172 MB for a million; it now streams them into the
    // planner and keeps the first 100 000 for the alignment time (about 80 MB of address space
    // in all, threads and the binary included; the old build needed more than 150 MB).
    let mut text = String::from("G20 G90 F100\no100 repeat [100000]\n");
    for x in 1..=5 {
        text.push_str(&format!("G1 X0.00{x}\nG1 X0\n"));
    }
    text.push_str("o100 endrepeat\nM2\n");
    let program = scratch("loop-1m.ngc", &text);
    let path = program.to_str().expect("utf-8");
    let out = bounded(&["run", "--dialect", "linuxcnc", path], 120, 300).expect("ran in time");
    let report = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(report.contains("ended by M2 at line 14 (1000000 moves, cycle time"), "{report}");
}
