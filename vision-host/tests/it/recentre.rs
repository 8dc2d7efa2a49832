//! Re-centring leaves no trace (issue 25): whatever M281's re-centring moves do to the modal
//! state, the program after M281 runs exactly as it does after a one-shot M281 — same moves,
//! same rapids and feeds, same end point — on the session path every front end runs.

use proptest::prelude::*;
use vision_gcode::Event;
use vision_host::testkit::{clock, Camera, Rig};
use vision_host::{controller, ProgramHandler, Record, Session};
use vision_mcode::Outcome;

/// What a program did: the Vision records, the motion after M281's line, and where it ended
/// (program frame, current units).
struct Run {
    records: Vec<Record>,
    after: Vec<Event>,
    end: (f64, f64),
}

/// Runs `program` on the built-in world with `VisionRecenterPasses` = `passes`; M281 must be
/// on line `m281_line`.
fn run(program: &str, passes: i64, m281_line: u32) -> Run {
    let (rig, mut module) = Rig::new(None, Camera::Sim);
    module.set_param("VisionRecenterPasses", passes).expect("passes");
    let mut handler = ProgramHandler::new(Session::new(module), &controller::Mach4, clock());
    let mut machine = vision_driver_sim::SimMachine::new(&rig.sim).expect("machine");
    let mut after = Vec::new();
    let mut sink = |e: &Event| {
        if e.line() > m281_line {
            after.push(e.clone());
        }
    };
    machine.run_program(program, Some(&mut handler), &mut sink).expect("the program runs");
    let p = machine.interpreter().program_position();
    Run { records: handler.take_records(), after, end: (p.x, p.y) }
}

/// The same motion, positions within 1e-6 units (the moves back are written with 7 decimals).
fn same(a: &[Event], b: &[Event]) -> bool {
    let close = |p: vision_gcode::Xyz, q: vision_gcode::Xyz| (p - q).norm() < 1e-6;
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| match (x, y) {
            (Event::Linear(m), Event::Linear(n)) => {
                m.line == n.line
                    && m.rate == n.rate
                    && m.path == n.path
                    && close(m.start, n.start)
                    && close(m.end, n.end)
            }
            _ => x == y,
        })
}

fn recentred(run: &Run) -> bool {
    run.records.iter().any(|r| matches!(&r.result, Ok(Outcome::Capture(c)) if c.report.recentred.is_some()))
}

#[test]
fn an_incremental_move_after_m281_stays_incremental() {
    // Dot 3 of the demo target is seen 18 px off centre: M281 moves to re-centre.
    let program = "G90 G20 G17\nG54\nT98 M6\nG0 X6.0 Y4.0\nG91\nM281\nG0 X1.0\nM30\n";
    let moved = run(program, 3, 6);
    let one_shot = run(program, 0, 6);
    assert!(recentred(&moved), "M281 re-centred");
    assert!(!recentred(&one_shot));
    assert!((moved.end.0 - 7.0).abs() < 1e-6 && (moved.end.1 - 4.0).abs() < 1e-6, "{:?}", moved.end);
    assert!(same(&moved.after, &one_shot.after), "{:?}\n{:?}", moved.after, one_shot.after);
}

#[test]
fn a_feed_move_after_m281_stays_a_feed_move() {
    let program = "G90 G20 G17\nG54\nT98 M6\nG0 X5.9 Y3.9\nG1 X6.0 Y4.0 F20\nM281\nX56.0\nM30\n";
    let moved = run(program, 3, 6);
    let one_shot = run(program, 0, 6);
    assert!(recentred(&moved));
    assert!(same(&moved.after, &one_shot.after), "{:?}\n{:?}", moved.after, one_shot.after);
    let feed = moved.after.iter().find_map(|e| match e {
        Event::Linear(m) => Some(m.rate),
        _ => None,
    });
    assert!(matches!(feed, Some(vision_gcode::Rate::Feed(_))), "X56.0 runs as {feed:?}");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Random modal states before M281 (distance mode, motion mode and feed, plane, arc
    /// distance mode, path mode, canned-cycle return mode): the program after it behaves as
    /// with one shot.
    #[test]
    fn the_program_after_m281_runs_as_after_a_one_shot_m281(
        incremental in any::<bool>(),
        feed in prop_oneof![Just(None), (1.0f64..200.0).prop_map(Some)],
        plane in prop::sample::select(vec!["G17", "G18", "G19"]),
        arc in prop::sample::select(vec!["G90.1", "G91.1"]),
        path in prop::sample::select(vec!["G61", "G64", "G64 P0.01"]),
        retract in prop::sample::select(vec!["G98", "G99"]),
    ) {
        let motion = match feed {
            Some(f) => format!("G1 F{f:.3}"),
            None => "G0".to_string(),
        };
        let distance = if incremental { "G91" } else { "G90" };
        // Arrive over dot 3 in G90, then set the modes under test without moving.
        let program = format!(
            "G90 G20 G17\nG54\nT98 M6\nG0 X6.0 Y4.0\n{plane} {arc} {path} {retract}\n{motion}\n{distance}\nM281\n\
             G17\nX0.5 Y0.25\nY-0.5\nM30\n"
        );
        let moved = run(&program, 3, 8);
        let one_shot = run(&program, 0, 8);
        prop_assert!(recentred(&moved));
        prop_assert!(same(&moved.after, &one_shot.after), "{:?}\n{:?}", moved.after, one_shot.after);
        prop_assert!((moved.end.0 - one_shot.end.0).abs() < 1e-6 && (moved.end.1 - one_shot.end.1).abs() < 1e-6);
    }
}

#[test]
fn m283s_walk_leaves_the_programs_modes_as_they_were() {
    // Example 1's start, then an incremental feed mode the walk's G90 G0 moves must not keep.
    let program = "G90 G20 G54\nT98 M6\nG0 X-2.5 Y-4.0\nG91 G1 F30\nM283 C1\nX0.5\nM30\n";
    let (rig, module) = Rig::new(None, Camera::Sim);
    let mut handler = ProgramHandler::new(Session::new(module), &controller::Mach4, clock());
    let mut machine = vision_driver_sim::SimMachine::new(&rig.sim).expect("machine");
    let mut after = Vec::new();
    let mut sink = |e: &Event| {
        if e.line() == 6 {
            after.push(e.clone());
        }
    };
    machine.run_program(program, Some(&mut handler), &mut sink).expect("the program runs");
    let records = handler.take_records();
    assert!(matches!(records.last().map(|r| &r.result), Some(Ok(Outcome::Calibrate(_)))), "{records:?}");
    let [Event::Linear(m)] = after.as_slice() else { panic!("{after:?}") };
    assert_eq!(m.rate, vision_gcode::Rate::Feed(30.0));
    assert!(((m.end.x - m.start.x) - 0.5).abs() < 1e-9 && (m.end.y - m.start.y).abs() < 1e-9, "{m:?}");
}
