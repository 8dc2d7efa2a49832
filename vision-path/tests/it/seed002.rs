//! Every example snippet of seed 002, through the interpreter and the planner, on the seed's
//! machine: millimetres, 1000 mm/s² path acceleration, drives at 500 mm/s and 1000 mm/s²,
//! 1 ms setpoints, tool 1 on device 1 ports 0/1, and a default feed (several snippets feed
//! without ever programming `F`).
#![expect(clippy::float_cmp, reason = "tests compare exact values")]

use crate::common;

use common::{interior_rests, norm, sub, Run};
use vision_gcode::{Interpreter, InterpreterConfig};
use vision_math::LengthUnit;
use vision_path::{
    Axis, AxisLimits, AxisMap, DigitalOutput, Event, FollowerConfig, GcodeItems, Limits, MotionSink, OutputCommand,
    OutputWrite, Pace, PathError, PathFollower, PlanConfig, RunState, Setpoint, Setpoints, SpindleCommand, Tool,
    ToolOutputs, ToolTable, Xyz,
};

const A: f64 = 1000.0;
const T: f64 = 0.001;

/// The seed's `tool1 = TOOL(1, clockwise, counterClockwise)`: device 1, ports 0 and 1, high.
fn seed_tool() -> ToolOutputs {
    let out = |port| DigitalOutput { device: 1, port, active_high: true };
    ToolOutputs { clockwise: out(0), counter_clockwise: out(1) }
}

/// The seed's tool table: tool 1 only. The interpreter and the follower share it.
fn seed_tools() -> ToolTable {
    ToolTable::new().with(1, Tool { offset: Xyz::ZERO, outputs: Some(seed_tool()) })
}

fn machine_motion() -> InterpreterConfig {
    let mut config = InterpreterConfig::new(LengthUnit::Millimetre);
    config.default_feed = Some(1000.0);
    config.tools = seed_tools();
    config
}

/// Interpreter + planner on `program`; checks the sampled bounds and that the path ends exactly
/// where the interpreter leaves the machine.
fn plan(program: &str) -> Run {
    let items = GcodeItems::new(Interpreter::new(machine_motion()), program);
    let config = PlanConfig::new(Limits::uniform(A, 500.0, 1000.0), T, items.start_position());
    let planned = common::collect(Setpoints::new(&config, items).unwrap(), program);
    let sp = &planned.setpoints;
    for w in sp.windows(2) {
        let d = sub(w[1].position, w[0].position);
        assert!(d.to_array().iter().all(|c| c.abs() <= 500.0 * T * (1.0 + 1e-6) + 1e-9), "axis speed at {}", w[1].time);
    }
    for w in sp.windows(3) {
        let dd = sub(sub(w[2].position, w[1].position), sub(w[1].position, w[0].position));
        assert!(norm(dd) <= A * T * T * (1.0 + 1e-6) + 1e-9, "acceleration at {} (line {})", w[1].time, w[1].line);
    }
    let mut interp = Interpreter::new(machine_motion());
    interp.run(program, None, &mut |_: &vision_gcode::Event| {}).unwrap();
    let m = interp.machine_position();
    assert_eq!(sp.last().unwrap().position, m, "ends exactly where the interpreter does");
    assert_eq!(sp.last().unwrap().velocity, Xyz::ZERO);
    planned
}

fn rests_at(p: &Run, at: [f64; 3]) -> bool {
    p.setpoints.iter().any(|s| s.position == Xyz::from(at) && s.velocity == Xyz::ZERO)
}

/// Setpoints strictly between the first and the last (the path's interior).
fn interior(p: &Run) -> &[Setpoint] {
    &p.setpoints[1..p.setpoints.len() - 1]
}

#[test]
fn g61_square_stops_at_every_corner_and_g64_p10_blends_them() {
    let exact = plan("G91 G21 G61\nG0 X500\nY500\nX-500\nY-500");
    for c in [[500.0, 0.0, 0.0], [500.0, 500.0, 0.0], [0.0, 500.0, 0.0]] {
        assert!(rests_at(&exact, c), "G61 stops at {c:?}");
    }
    let blended = plan("G91 G21 G64 P10.0\nG0 X500\nY500\nX-500\nY-500");
    let moving_from = blended.setpoints.iter().position(|s| s.position.x > 1.0).unwrap();
    let moving_to = blended.setpoints.iter().rposition(|s| s.position.y > 1.0).unwrap();
    assert!(blended.setpoints[moving_from..moving_to].iter().all(|s| norm(s.velocity) > 0.0));
    let corners = [[500.0, 0.0, 0.0], [500.0, 500.0, 0.0], [0.0, 500.0, 0.0]];
    for c in corners {
        let nearest =
            blended.setpoints.iter().map(|s| norm(sub(s.position, Xyz::from(c)))).fold(f64::INFINITY, f64::min);
        assert!(nearest > 9.9 && nearest < 10.01, "passes P10 from {c:?}: {nearest}");
    }
    let te = exact.setpoints.last().unwrap().time;
    let tb = blended.setpoints.last().unwrap().time;
    assert!(tb < te, "blending is faster: {tb} vs {te}");
}

#[test]
fn g90_and_g91_squares_with_a_z_lift() {
    let abs = plan("G21 G90 G64 P1\nG0 Z500\nX500\nY500\nX-500\nY-500");
    let inc = plan("G21 G91 G64 P1\nG0 Z500\nX500\nY500\nX-500\nY-500");
    assert_eq!(abs.setpoints.last().unwrap().position, Xyz::new(-500.0, -500.0, 500.0));
    assert_eq!(inc.setpoints.last().unwrap().position, Xyz::new(0.0, 0.0, 500.0));
    // G64 P1 blends every corner (all are 90° or 45°): neither square stops before its end.
    assert_eq!(interior_rests(&abs.setpoints), 0);
    assert_eq!(interior_rests(&inc.setpoints), 0);
}

/// Every setpoint of `line` lies on the circle about `centre` of `radius` in the plane whose
/// normal axis is `normal`.
fn on_circle(p: &Run, line: usize, centre: [f64; 3], normal: usize, radius: f64) {
    let mut n = 0;
    for s in p.setpoints.iter().filter(|s| s.line == line) {
        let mut d = sub(s.position, Xyz::from(centre));
        d.set_axis(normal, 0.0);
        assert!((norm(d) - radius).abs() < 1e-9, "line {line} at {:?} is {} from the centre", s.position, norm(d));
        n += 1;
    }
    assert!(n > 100, "line {line} has {n} setpoints");
}

#[test]
fn arcs_in_all_three_planes_stay_on_their_circles() {
    let xy = plan("G90 G21 G61 G17 G90.1\nG0 X500 Y250 Z500\nG3 X0 Y250 I250 J250\nG3 X500 Y250 I250 J250");
    on_circle(&xy, 3, [250.0, 250.0, 0.0], 2, 250.0);
    on_circle(&xy, 4, [250.0, 250.0, 0.0], 2, 250.0);
    // G3 from (500, 250) about (250, 250) to (0, 250) goes through +Y first.
    assert!(xy.setpoints.iter().filter(|s| s.line == 3).any(|s| s.position.y > 499.0));
    let inc = plan("G90 G21 G61 G17 G91.1\nG0 X500 Y250 Z500\nG3 X0 Y250 I-250 J0\nG3 X500 Y250 I250 J0");
    on_circle(&inc, 3, [250.0, 250.0, 0.0], 2, 250.0);
    let zx = plan("G90 G21 G61 G18 G90.1\nG0 X500 Y500 Z250\nG3 X0 Z250 I250 K250\nG3 X500 Z250 I250 K250");
    on_circle(&zx, 3, [250.0, 0.0, 250.0], 1, 250.0);
    // G18 counter-clockwise runs Z → X: from (X500, Z250) it goes through Z < 250 first.
    assert!(zx.setpoints.iter().filter(|s| s.line == 3).any(|s| s.position.z < 1.0));
    let yz = plan("G90 G21 G61 G19 G90.1\nG0 X250 Y500 Z250\nG3 Y0 Z250 J250 K250\nG3 Y500 Z250 J250 K250");
    on_circle(&yz, 3, [0.0, 250.0, 250.0], 0, 250.0);
    let g2 = plan("G61 G21 G17\nG90\nG90.1\nG0 X500\nG0 Y250 Z500\nG2 X0 Y250 I250 J250");
    on_circle(&g2, 6, [250.0, 250.0, 0.0], 2, 250.0);
    assert!(g2.setpoints.iter().filter(|s| s.line == 6).any(|s| s.position.y < 1.0), "G2 goes through −Y");
}

#[test]
fn g28_g92_rapid_and_linear_snippets() {
    let g28 = plan("G90 G21 G61\nG0 X500\nY500\nZ500\nG28.1\nG0 Y0\nX0\nG28");
    assert_eq!(g28.setpoints.last().unwrap().position, Xyz::new(500.0, 500.0, 500.0));
    let g92 = plan("G90 G21 G64 P10.0\nG0 X500\nY500 Z500\nG92 X0 Y0 Z0\nG0 X-250 Y-250 Z-250");
    assert_eq!(g92.setpoints.last().unwrap().position, Xyz::new(250.0, 250.0, 250.0));
    let rapid = plan("G90 G21 G64 P10.0\nG0 X500 Y500 F1000\nZ500\nX0 Y0\nZ0 F500");
    let g1 = plan("G90 G21 G64 P10.0\nG1 Y500 Z500 F1000\nX500\nY0 Z0\nX0 F500");
    // G64 P10 blends every corner of these three (G92 moves no axis, so it is no stop either).
    for p in [&g92, &rapid, &g1] {
        assert_eq!(interior_rests(&p.setpoints), 0);
    }
    // G1 at F1000 = 16.7 mm/s; the last side at F500 = 8.3 mm/s.
    let top = interior(&g1).iter().filter(|s| s.line == 5).map(|s| norm(s.velocity)).fold(0.0, f64::max);
    assert!((top - 500.0 / 60.0).abs() < 1e-9, "{top}");
}

#[test]
fn tool_snippets_switch_at_rest_at_their_programmed_points() {
    let implicit = plan("G90 G21\nT1 M6\nG0 X100 Y100\nM3\nG1 X200 Y200\nM5");
    let kinds: Vec<_> = implicit.events.iter().map(|e| (e.line, e.event)).collect();
    assert_eq!(
        kinds,
        vec![
            (2, Event::ToolChange(1)),
            (4, Event::Output(OutputCommand::Tool { tool: Some(1), command: SpindleCommand::Clockwise })),
            (6, Event::Output(OutputCommand::Tool { tool: Some(1), command: SpindleCommand::Stop })),
        ]
    );
    let m3 = implicit.events[1];
    let at = implicit.setpoints.iter().find(|s| s.time == m3.time).unwrap();
    assert_eq!(at.position, Xyz::new(100.0, 100.0, 0.0));
    let explicit = plan("G90 G21\nG0 X100 Y100\nM3 A1 P0\nG1 X200 Y200\nM5 A1 P0");
    let port = |port, command| Event::Output(OutputCommand::Port { device: 1, port, command });
    assert_eq!(explicit.events[0].event, port(0, SpindleCommand::Clockwise));
    assert_eq!(explicit.events[1].event, port(0, SpindleCommand::Stop));
    let m4 = plan("G90 G21\nG0 X100 Y100\nM4 A1 P1\nG1 X200 Y200\nM5 A1 P1");
    let events: Vec<_> = m4.events.iter().map(|e| e.event).collect();
    assert_eq!(events, vec![port(1, SpindleCommand::CounterClockwise), port(1, SpindleCommand::Stop)]);
}

/// The Python example's program (`GCODE_STRING`), two header comment lines first.
fn seed_example() -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/path/seed002-example.nc");
    std::fs::read_to_string(path).expect("examples/path/seed002-example.nc")
}

#[test]
fn the_python_example_stays_within_half_a_millimetre_and_dwells_a_second() {
    let p = plan(&seed_example());
    // The corners it blends are line → arc and arc → line; every setpoint on the cut (lines
    // 13–16) stays within P0.5 of the programmed contour.
    let contour = |x: Xyz| -> f64 {
        let (px, py) = (x.x, x.y);
        let seg = |a: (f64, f64), b: (f64, f64)| {
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            let t = (((px - a.0) * dx + (py - a.1) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
            (px - a.0 - t * dx).hypot(py - a.1 - t * dy)
        };
        // Right arc: centre (100, 60), x ≥ 100 side; left arc: centre (60, 60), x ≤ 60 side.
        let right = if px >= 100.0 {
            ((px - 100.0).hypot(py - 60.0) - (50f64 * 50.0 + 10.0 * 10.0).sqrt()).abs()
        } else {
            f64::INFINITY
        };
        let left = if px <= 60.0 { ((px - 60.0).hypot(py - 60.0) - 50.0).abs() } else { f64::INFINITY };
        seg((60.0, 110.0), (110.0, 110.0)).min(seg((110.0, 10.0), (60.0, 10.0))).min(right).min(left)
    };
    let cut: Vec<_> = p.setpoints.iter().filter(|s| (13..=16).contains(&s.line)).collect();
    assert!(cut.len() > 1000);
    for s in &cut {
        assert!(contour(s.position) <= 0.5 + 1e-9, "{:?} (line {}) is {} off", s.position, s.line, contour(s.position));
    }
    let dwell = p.setpoints.iter().filter(|s| s.line == 17).count();
    assert_eq!(dwell, 1000);
    assert_eq!(p.events.len(), 2);
    // It comes to rest twice on the way: for M3 (line 12) and for G4 + M5 (lines 17–18). The
    // cut's corners are blended, so the cut itself never stops.
    assert_eq!(interior_rests(&p.setpoints), 2);
    assert!(cut[1..cut.len() - 1].iter().all(|s| s.velocity != Xyz::ZERO), "the cut stops at a corner");
}

#[derive(Clone, Default)]
struct Writes(std::sync::Arc<std::sync::Mutex<Vec<OutputWrite>>>);

impl MotionSink for Writes {
    fn setpoint(&mut self, _: &Setpoint, _: &[vision_path::DrivePosition]) -> Result<(), String> {
        Ok(())
    }
    fn output(&mut self, write: OutputWrite) -> Result<(), String> {
        self.0.lock().unwrap().push(write);
        Ok(())
    }
}

fn seed_follower() -> PathFollower {
    let axes = AxisMap::new(&[(Axis::X, 1), (Axis::Y, 3)]).unwrap();
    let limits = [AxisLimits { max_speed: 500.0, max_accel: 1000.0 }; 3];
    PathFollower::new(FollowerConfig::new(axes, seed_tools(), limits)).unwrap()
}

#[test]
fn start_gcode_follows_the_python_example_like_start_path() {
    let mut follower = seed_follower();
    let writes = Writes::default();
    follower.start_gcode(&machine_motion(), seed_example(), 1000.0, writes.clone(), Pace::Unpaced).unwrap();
    let status = follower.wait();
    assert_eq!(status.state, RunState::Completed, "{:?}", status.error);
    assert_eq!(status.position, Xyz::new(1.0, 1.0, 0.0));
    assert_eq!(status.line, 19, "the last line of the text");
    let w = |port, high| OutputWrite { device: 1, port, high };
    assert_eq!(*writes.0.lock().unwrap(), vec![w(1, false), w(0, true), w(0, false), w(1, false)]);
}

#[test]
fn start_gcode_checks_the_whole_program_before_anything_moves() {
    let mut follower = seed_follower();
    // Z has no drive on the seed's machine. The tool is not switched on either.
    let writes = Writes::default();
    let err = follower.start_gcode(&machine_motion(), "G21 G90\nM3 $1\nG0 Z5", 1000.0, writes.clone(), Pace::Unpaced);
    assert_eq!(err, Err(PathError::UnmappedAxis { line: 3, axis: 'Z' }));
    assert!(writes.0.lock().unwrap().is_empty());
    let err =
        follower.start_gcode(&machine_motion(), "G21 G90\nG0 X10\nG1 X20 Q3", 1000.0, Writes::default(), Pace::Unpaced);
    match err {
        Err(PathError::Program { line: 3, message, .. }) => assert!(!message.starts_with("line"), "{message}"),
        other => panic!("{other:?}"),
    }
    // The interpreter knows tools 1–254; the follower's table has only tool 1 wired.
    let mut config = machine_motion();
    config.tools = ToolTable::numbered(1, 254).with(1, config.tools.get(1).unwrap());
    let err = follower.start_gcode(&config, "G21\nT2 M6\nM3", 1000.0, Writes::default(), Pace::Unpaced);
    assert_eq!(err, Err(PathError::UnknownTool { line: 3, tool: 2 }));
    assert_eq!(follower.status().state, RunState::Idle);
    assert_eq!(follower.status().position, Xyz::ZERO);
}

#[test]
fn a_gcode_path_that_fails_mid_program_halts_at_rest_and_switches_its_tool_off() {
    // `start` (not `start_gcode`) reads the program as it runs: the bad line 4 is met after
    // the tool went on and the machine moved.
    let mut follower = seed_follower();
    let writes = Writes::default();
    let items =
        GcodeItems::new(Interpreter::new(machine_motion()), "G21 G90\nM3 $1\nG1 X10 F600\nG1 X20 Q3".to_string());
    follower.start(items, 1000.0, writes.clone(), Pace::Unpaced).unwrap();
    let status = follower.wait();
    assert_eq!(status.state, RunState::Failed);
    assert!(matches!(status.error, Some(PathError::Program { line: 4, .. })), "{:?}", status.error);
    assert_eq!(status.position, Xyz::new(10.0, 0.0, 0.0));
    let w = |port, high| OutputWrite { device: 1, port, high };
    assert_eq!(*writes.0.lock().unwrap(), vec![w(1, false), w(0, true), w(0, false)]);
}

#[test]
fn start_gcode_refuses_at_once_while_a_path_runs() {
    let mut follower = seed_follower();
    // A 20 m move in real time: still running when start_gcode is called.
    follower
        .start_gcode(&machine_motion(), "G21 G90\nG1 X20000 F24000", 1000.0, Writes::default(), Pace::RealTime)
        .unwrap();
    // Refused before the program is even read: its bad word would otherwise be the error.
    let err = follower.start_gcode(&machine_motion(), "G21\nG1 X1 Q3", 1000.0, Writes::default(), Pace::Unpaced);
    assert_eq!(err, Err(PathError::AlreadyRunning));
    assert_eq!(follower.stop().state, RunState::Stopped);
}
