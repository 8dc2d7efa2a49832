//! Two sessions on one profile file (two Python sessions, the CLI beside Mach4): in every
//! interleaving of their M283 calibrations and M284 job switches, the file ends with the last
//! calibration and the last job, and no save writes back a stale K.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use vision_core::{ProfileStore, Timestamp};
use vision_host::testkit::{sim, uncalibrated_params};
use vision_host::Clock;
use vision_host::{cameras, ProgramHandler, Session};

/// One Vision call of a session.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Op {
    /// `M283 C1` over the sheet.
    Calibrate,
    /// `M284 P<job>`.
    Job(u32),
}

/// Every interleaving of `a` and `b` (each keeps its order), as (session, op) pairs.
fn interleavings(a: &[Op], b: &[Op]) -> Vec<Vec<(usize, Op)>> {
    match (a.split_first(), b.split_first()) {
        (None, None) => vec![Vec::new()],
        (Some((x, rest)), None) => interleavings(rest, b).into_iter().map(|t| [vec![(0, *x)], t].concat()).collect(),
        (None, Some((y, rest))) => interleavings(a, rest).into_iter().map(|t| [vec![(1, *y)], t].concat()).collect(),
        (Some((x, ra)), Some((y, rb))) => {
            let mut all: Vec<_> = interleavings(ra, b).into_iter().map(|t| [vec![(0, *x)], t].concat()).collect();
            all.extend(interleavings(a, rb).into_iter().map(|t| [vec![(1, *y)], t].concat()));
            all
        }
    }
}

#[test]
fn no_interleaving_of_two_sessions_loses_a_calibration_or_a_job() {
    let sim = sim();
    let registry = cameras(Some(&sim));
    let dir = std::env::temp_dir().join(format!("vision-host-shared-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("tmp");
    let path = dir.join("vision.toml");
    // Each call has its own time, so each calibration its own VisionCal_Date.
    let seconds = Arc::new(AtomicU64::new(1_800_000_000));
    let clock: Clock = {
        let seconds = seconds.clone();
        Arc::new(move || Timestamp::from_unix(seconds.load(Ordering::SeqCst), 0))
    };
    let programs =
        [vec![Op::Calibrate], vec![Op::Job(2)], vec![Op::Calibrate, Op::Job(1)], vec![Op::Job(2), Op::Calibrate]];
    let mut runs = 0;
    for a in &programs {
        for b in &programs {
            for order in interleavings(a, b) {
                ProfileStore::new(&path).save(&uncalibrated_params(&sim)).expect("a fresh profile");
                let mut handlers = [0, 1].map(|_| {
                    let session = Session::open(&path, &registry).expect("open");
                    ProgramHandler::new(session, &vision_host::controller::Mach4, clock.clone())
                });
                let (mut last_date, mut last_job) = (String::new(), 0);
                for (who, op) in &order {
                    seconds.fetch_add(60, Ordering::SeqCst);
                    let program = match op {
                        Op::Calibrate => "G90 G20 G54\nT98 M6\nG0 X-2.5 Y-4.0\nM283 C1\nM30\n".to_string(),
                        Op::Job(j) => format!("M284 P{j}\nM30\n"),
                    };
                    let mut machine = vision_driver_sim::SimMachine::new(&sim).expect("machine");
                    let end =
                        machine.run_program(&program, Some(&mut handlers[*who]), &mut |_: &vision_gcode::Event| {});
                    assert!(end.is_ok(), "{order:?}: {op:?}: {end:?}");
                    let params = handlers[*who].session().module().params().clone();
                    match op {
                        Op::Calibrate => last_date = params.cal_date().to_string(),
                        Op::Job(j) => last_job = i64::from(*j),
                    }
                    let file = ProfileStore::new(&path).with_defaults(registry.params()).load().expect("load");
                    assert_eq!(file.cal_date(), last_date, "{order:?}: after {who}'s {op:?}");
                    assert_eq!(file.active_job(), last_job, "{order:?}: after {who}'s {op:?}");
                    assert_eq!(file.cal_k() == uncalibrated_params(&sim).cal_k(), last_date.is_empty(), "{order:?}");
                    assert_eq!(&params, &file, "{order:?}: the session that saved holds the file");
                    runs += 1;
                }
            }
        }
    }
    assert!(runs > 100, "{runs}");
    let _ = std::fs::remove_dir_all(&dir);
}
