//! The seed's API: configure, start, poll, stop — against a recording sink.
#![expect(clippy::float_cmp, reason = "tests compare exact values")]

use crate::common;

use std::sync::{Arc, Mutex};
use std::time::Duration;

use common::{norm, Program};
use vision_path::{
    Axis, AxisLimits, AxisMap, DigitalOutput, DrivePosition, Event, FollowerConfig, Item, MotionSink, OutputCommand,
    OutputWrite, Pace, PathError, PathFollower, PathMode, Rate, RunState, Setpoint, SpindleCommand, Tool, ToolOutputs,
    ToolTable, Xyz,
};

#[derive(Default)]
struct Record {
    setpoints: Vec<(Setpoint, Vec<DrivePosition>)>,
    writes: Vec<OutputWrite>,
}

#[derive(Clone, Default)]
struct Recorder(Arc<Mutex<Record>>);

impl MotionSink for Recorder {
    fn setpoint(&mut self, setpoint: &Setpoint, drives: &[DrivePosition]) -> Result<(), String> {
        self.0.lock().unwrap().setpoints.push((*setpoint, drives.to_vec()));
        Ok(())
    }
    fn output(&mut self, write: OutputWrite) -> Result<(), String> {
        self.0.lock().unwrap().writes.push(write);
        Ok(())
    }
}

/// The seed's Python example: X on drive 1, Y on drive 3, tool 1 on device 1 ports 0/1,
/// drives at 500 mm/s and 1000 mm/s².
fn seed_follower() -> PathFollower {
    let out = |port| DigitalOutput { device: 1, port, active_high: true };
    let outputs = ToolOutputs { clockwise: out(0), counter_clockwise: out(1) };
    follower(ToolTable::new().with(1, Tool { outputs: Some(outputs), ..Tool::default() }))
}

/// The seed's drives (X on 1, Y on 3, 500 mm/s, 1000 mm/s²) with `tools`.
fn follower(tools: ToolTable) -> PathFollower {
    let axes = AxisMap::new(&[(Axis::X, 1), (Axis::Y, 3)]).unwrap();
    let limits = [AxisLimits { max_speed: 500.0, max_accel: 1000.0 }; 3];
    PathFollower::new(FollowerConfig::new(axes, tools, limits)).unwrap()
}

fn tool(command: SpindleCommand) -> impl FnOnce(usize) -> Item {
    move |line| Item::Event { line, event: Event::Output(OutputCommand::Tool { tool: Some(1), command }) }
}

/// The seed's example program (G90 G90.1 G21 G17 G64 P0.5), as segments.
fn seed_program() -> Vec<Result<Item, PathError>> {
    let feed = Rate::Feed(1000.0);
    let mut p = Program::new(Xyz::ZERO, PathMode::Blend { tolerance: Some(0.5) });
    p.line_to(Xyz::new(60.0, 110.0, 0.0), Rate::Rapid); // G0 X60 Y110 F1000
    p.item(tool(SpindleCommand::Clockwise)); // M3 $1
    p.line_to(Xyz::new(110.0, 110.0, 0.0), feed); // G1 X110 Y110
    p.g17_arc_to(Xyz::new(110.0, 10.0, 0.0), Xyz::new(100.0, 60.0, 0.0), true, feed); // G2 X110 Y10 I100 J60
    p.line_to(Xyz::new(60.0, 10.0, 0.0), feed); // G1 X60 Y10
    p.g17_arc_to(Xyz::new(60.0, 110.0, 0.0), Xyz::new(60.0, 60.0, 0.0), true, feed); // G2 X60 Y110 I60 J60
    p.item(|line| Item::Dwell { line, seconds: 1.0 }); // G4 P1.0
    p.item(tool(SpindleCommand::Stop)); // M5 $1
    p.line_to(Xyz::new(1.0, 1.0, 0.0), Rate::Rapid); // G0 X1 Y1
    p.item(|line| Item::End { line });
    p.items.into_iter().map(Ok).collect()
}

#[test]
fn the_seed_example_runs_to_completion_on_drives_1_and_3_with_its_tool() {
    let mut follower = seed_follower();
    assert_eq!(follower.status().state, RunState::Idle);
    let rec = Recorder::default();
    follower.start(seed_program(), 1000.0, rec.clone(), Pace::Unpaced).unwrap();
    let status = follower.wait();
    assert_eq!(status.state, RunState::Completed, "{:?}", status.error);
    assert!(!status.running());
    assert_eq!(status.position, Xyz::new(1.0, 1.0, 0.0));
    let record = rec.0.lock().unwrap();
    let (last, drives) = record.setpoints.last().unwrap();
    assert_eq!(status.elapsed, last.time);
    assert_eq!(drives, &vec![DrivePosition { drive: 1, position: 1.0 }, DrivePosition { drive: 3, position: 1.0 }]);
    // M3 $1: counter-clockwise off, clockwise on; M5 $1: both off; nothing left to switch off.
    let w = |port, high| OutputWrite { device: 1, port, high };
    assert_eq!(record.writes, vec![w(1, false), w(0, true), w(0, false), w(1, false)]);
    // The dwell holds 1 s at (60, 110).
    let held = record.setpoints.iter().filter(|(s, _)| s.position == Xyz::new(60.0, 110.0, 0.0)).count();
    assert!((1000..=1003).contains(&held), "{held}");
}

#[test]
fn a_tool_left_on_is_switched_off_at_the_end_and_the_next_path_starts_where_this_one_ended() {
    let mut follower = seed_follower();
    let mut p = Program::new(Xyz::ZERO, PathMode::ExactStop);
    p.item(tool(SpindleCommand::CounterClockwise));
    p.line_to(Xyz::new(10.0, 0.0, 0.0), Rate::Feed(3000.0));
    let rec = Recorder::default();
    follower.start(p.items.into_iter().map(Ok), 1000.0, rec.clone(), Pace::Unpaced).unwrap();
    assert_eq!(follower.wait().state, RunState::Completed);
    let w = |port, high| OutputWrite { device: 1, port, high };
    assert_eq!(rec.0.lock().unwrap().writes, vec![w(0, false), w(1, true), w(1, false)]);

    let mut q = Program::new(Xyz::new(10.0, 0.0, 0.0), PathMode::ExactStop);
    q.line_to(Xyz::new(10.0, 5.0, 0.0), Rate::Feed(3000.0));
    let rec2 = Recorder::default();
    follower.start(q.items.into_iter().map(Ok), 1000.0, rec2.clone(), Pace::Unpaced).unwrap();
    assert_eq!(follower.wait().state, RunState::Completed);
    assert_eq!(rec2.0.lock().unwrap().setpoints[0].0.position, Xyz::new(10.0, 0.0, 0.0));
}

#[test]
fn an_active_low_tool_is_driven_low_to_switch_on_and_high_when_the_path_leaves_it_on() {
    let out = |port| DigitalOutput { device: 3, port, active_high: false };
    let outputs = ToolOutputs { clockwise: out(0), counter_clockwise: out(1) };
    let mut follower = follower(ToolTable::new().with(2, Tool { outputs: Some(outputs), ..Tool::default() }));
    let mut p = Program::new(Xyz::ZERO, PathMode::ExactStop);
    p.item(|line| Item::Event {
        line,
        event: Event::Output(OutputCommand::Tool { tool: Some(2), command: SpindleCommand::Clockwise }),
    });
    p.line_to(Xyz::new(10.0, 0.0, 0.0), Rate::Feed(3000.0));
    let rec = Recorder::default();
    follower.start(p.items.into_iter().map(Ok), 1000.0, rec.clone(), Pace::Unpaced).unwrap();
    assert_eq!(follower.wait().state, RunState::Completed);
    // M3: counter-clockwise released (high), clockwise driven active (low); at the end the
    // tool still on is switched off by driving its port to the inactive level (high).
    let w = |port, high| OutputWrite { device: 3, port, high };
    assert_eq!(rec.0.lock().unwrap().writes, vec![w(1, true), w(0, false), w(0, true)]);
}

#[test]
fn stop_brakes_to_rest_on_the_path_and_switches_the_tool_off() {
    let mut follower = seed_follower();
    let mut p = Program::new(Xyz::ZERO, PathMode::ExactStop);
    p.item(tool(SpindleCommand::Clockwise));
    p.line_to(Xyz::new(20000.0, 0.0, 0.0), Rate::Feed(24000.0));
    let rec = Recorder::default();
    // 20× real time: the 50-second move would take 2.5 s of wall clock; it is stopped early.
    follower.start(p.items.into_iter().map(Ok), 1000.0, rec.clone(), Pace::Scaled(20.0)).unwrap();
    let mut moving = false;
    for _ in 0..200 {
        std::thread::sleep(Duration::from_millis(5));
        let s = follower.status();
        if s.running() && s.elapsed > 0.5 {
            moving = true;
            break;
        }
    }
    assert!(moving, "the path should be moving: {:?}", follower.status());
    assert_eq!(follower.start(Vec::new(), 1000.0, Recorder::default(), Pace::Unpaced), Err(PathError::AlreadyRunning));
    let status = follower.stop();
    assert_eq!(status.state, RunState::Stopped);
    assert!(status.position.x > 0.0 && status.position.x < 20000.0, "{:?}", status.position);
    let record = rec.0.lock().unwrap();
    let last = record.setpoints.last().unwrap().0;
    assert_eq!(last.velocity, Xyz::ZERO);
    let bound = 1000.0 * 1e-6 * (1.0 + 1e-6) + 1e-9;
    for w in record.setpoints.windows(3) {
        let dd =
            common::sub(common::sub(w[2].0.position, w[1].0.position), common::sub(w[1].0.position, w[0].0.position));
        assert!(norm(dd) <= bound);
    }
    assert_eq!(record.writes.last(), Some(&OutputWrite { device: 1, port: 0, high: false }));
}

#[test]
fn a_move_of_an_unmapped_axis_halts_the_path_at_rest_before_it_and_switches_the_tool_off() {
    let mut follower = seed_follower();
    let mut p = Program::new(Xyz::ZERO, PathMode::ExactStop);
    p.item(tool(SpindleCommand::CounterClockwise));
    p.line_to(Xyz::new(5.0, 5.0, 0.0), Rate::Feed(3000.0)).line_to(Xyz::new(5.0, 5.0, 1.0), Rate::Feed(3000.0));
    let rec = Recorder::default();
    follower.start(p.items.into_iter().map(Ok), 1000.0, rec.clone(), Pace::Unpaced).unwrap();
    let status = follower.wait();
    assert_eq!(status.state, RunState::Failed);
    assert_eq!(status.error, Some(PathError::UnmappedAxis { line: 3, axis: 'Z' }));
    assert_eq!(status.position, Xyz::new(5.0, 5.0, 0.0));
    assert!(status.error.unwrap().to_string().contains("no drive is mapped to Z"));
    // M4 $1 (clockwise off, counter-clockwise on); the failed path drives it off again.
    let w = |port, high| OutputWrite { device: 1, port, high };
    assert_eq!(rec.0.lock().unwrap().writes, vec![w(0, false), w(1, true), w(1, false)]);
}

#[test]
fn an_unknown_tool_halts_the_path_with_the_reason_and_the_tool_off() {
    let w = |port, high| OutputWrite { device: 1, port, high };
    let mut follower = seed_follower();
    let items = vec![
        Ok(tool(SpindleCommand::Clockwise)(2)),
        Ok(Item::Event {
            line: 3,
            event: Event::Output(OutputCommand::Tool { tool: Some(7), command: SpindleCommand::Clockwise }),
        }),
    ];
    let rec = Recorder::default();
    follower.start(items, 1000.0, rec.clone(), Pace::Unpaced).unwrap();
    assert_eq!(follower.wait().error, Some(PathError::UnknownTool { line: 3, tool: 7 }));
    assert_eq!(rec.0.lock().unwrap().writes, vec![w(1, false), w(0, true), w(0, false)]);
}

#[test]
fn a_failing_sink_halts_the_path_with_the_reason_and_the_tool_off() {
    /// Drive 1 faults once the path has left X 0.5; outputs still work.
    #[derive(Clone, Default)]
    struct Broken(Arc<Mutex<Vec<OutputWrite>>>);
    impl MotionSink for Broken {
        fn setpoint(&mut self, setpoint: &Setpoint, _: &[DrivePosition]) -> Result<(), String> {
            if setpoint.position.x > 0.5 {
                return Err("drive 1 not enabled".into());
            }
            Ok(())
        }
        fn output(&mut self, write: OutputWrite) -> Result<(), String> {
            self.0.lock().unwrap().push(write);
            Ok(())
        }
    }
    let w = |port, high| OutputWrite { device: 1, port, high };
    let mut follower = seed_follower();
    let mut p = Program::new(Xyz::ZERO, PathMode::ExactStop);
    p.item(tool(SpindleCommand::Clockwise));
    p.line_to(Xyz::new(1.0, 0.0, 0.0), Rate::Rapid);
    let broken = Broken::default();
    follower.start(p.items.into_iter().map(Ok), 1000.0, broken.clone(), Pace::Unpaced).unwrap();
    let status = follower.wait();
    assert_eq!(status.state, RunState::Failed);
    assert!(status.error.unwrap().to_string().contains("drive 1 not enabled"));
    assert_eq!(*broken.0.lock().unwrap(), vec![w(1, false), w(0, true), w(0, false)]);
}

#[test]
fn bad_configuration_is_refused() {
    assert!(AxisMap::new(&[(Axis::X, 1), (Axis::Y, 1)]).unwrap_err().to_string().contains("drive 1"));
    assert!(AxisMap::new(&[(Axis::X, 1), (Axis::X, 2)]).is_err());
    let axes = AxisMap::new(&[(Axis::X, 1)]).unwrap();
    let bad = [AxisLimits { max_speed: 0.0, max_accel: 1000.0 }; 3];
    assert!(PathFollower::new(FollowerConfig::new(axes, ToolTable::new(), bad)).is_err());
    let mut follower = seed_follower();
    assert!(follower.start(Vec::new(), -1.0, Recorder::default(), Pace::Unpaced).is_err());
    assert!(follower.start(Vec::new(), 1.0, Recorder::default(), Pace::Scaled(0.0)).is_err());
    assert_eq!(follower.status().state, RunState::Idle);
}
