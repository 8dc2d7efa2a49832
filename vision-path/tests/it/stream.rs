//! The setpoint stream on hand-made programs: corners, arcs, stops, errors, bad input.
#![expect(clippy::float_cmp, reason = "tests compare exact values")]

use crate::common;

use common::{norm, sub, Program};
use vision_path::Xyz;
use vision_path::{
    Event, Item, Limits, OutputCommand, PathError, PathMode, PlanConfig, Rate, Segment, Setpoint, Setpoints, Shape,
    SpindleCommand, Step,
};

fn config() -> PlanConfig {
    PlanConfig::new(Limits::uniform(1000.0, 500.0, 1000.0), 0.001, Xyz::ZERO)
}

fn moves_of(run: &common::Run) -> Vec<Setpoint> {
    run.setpoints.clone()
}

/// The seed's square, `G91 G21 G61 / G0 X500 / Y500 / X-500 / Y-500`, as segments.
fn seed_square(mode: PathMode) -> Vec<Item> {
    let mut p = Program::new(Xyz::ZERO, mode);
    p.line_to(Xyz::new(500.0, 0.0, 0.0), Rate::Rapid)
        .line_to(Xyz::new(500.0, 500.0, 0.0), Rate::Rapid)
        .line_to(Xyz::new(0.0, 500.0, 0.0), Rate::Rapid)
        .line_to(Xyz::new(0.0, 0.0, 0.0), Rate::Rapid);
    p.item(|line| Item::End { line });
    p.items
}

#[test]
fn the_seed_square_under_g61_stops_at_each_corner_and_under_g64_keeps_moving() {
    // The seed's limits: 1000 units/s² path acceleration, 500 units/s per axis (and axes
    // strong enough that the path limit is the one that binds in the corners).
    let config = || PlanConfig::new(Limits::uniform(1000.0, 500.0, 2000.0), 0.001, Xyz::ZERO);
    let exact = common::run(&config(), &seed_square(PathMode::ExactStop));
    for corner in [[500.0, 0.0, 0.0], [500.0, 500.0, 0.0], [0.0, 500.0, 0.0]] {
        assert!(
            exact.setpoints.iter().any(|s| s.position == Xyz::from(corner) && s.velocity == Xyz::ZERO),
            "{corner:?}"
        );
    }
    // Each side: 500 units at 500 units/s with a = 1000 takes 1.5 s; four of them.
    let t = exact.setpoints.last().unwrap().time;
    assert!((6.0..6.01).contains(&t), "G61 cycle time {t}");

    let blended = common::run(&config(), &seed_square(PathMode::Blend { tolerance: Some(10.0) }));
    let tb = blended.setpoints.last().unwrap().time;
    assert!(tb < t - 0.05, "blending saves time: {tb} vs {t}");
    let mid: Vec<_> = blended.setpoints.iter().filter(|s| s.time > 1.0 && s.time < tb - 1.0).collect();
    // The blend arc: ℓ = P / tan(π/8), radius ℓ, speed √(A·r·√3/2) ≈ 144.6 units/s.
    let corner_speed = (1000.0 * (10.0 / (std::f64::consts::PI / 8.0).tan()) * 3f64.sqrt() / 2.0).sqrt();
    let slowest = mid.iter().map(|s| norm(s.velocity)).fold(f64::INFINITY, f64::min);
    assert!((slowest - corner_speed).abs() < 1e-6, "a blended square never stops between its ends: {slowest}");
    let corner = [500.0, 0.0, 0.0];
    let closest =
        blended.setpoints.iter().map(|s| norm(sub(s.position, Xyz::from(corner)))).fold(f64::INFINITY, f64::min);
    // The nearest sample lies up to v·T/2 = 0.065 along the arc from the nearest point.
    assert!(closest <= 10.0 + 1e-3 && closest > 9.99, "passes P from the corner: {closest}");
}

#[test]
fn collinear_moves_do_not_stop_even_under_g61() {
    let mut p = Program::new(Xyz::ZERO, PathMode::ExactStop);
    for k in 1..=10 {
        p.line_to(Xyz::new(10.0 * f64::from(k), 5.0 * f64::from(k), 0.0), Rate::Feed(3000.0));
    }
    let run = common::run(&config(), &p.items);
    let moving = &run.setpoints[1..run.setpoints.len() - 1];
    assert!(moving.iter().all(|s| norm(s.velocity) > 0.0));
}

#[test]
fn an_arc_keeps_its_centripetal_acceleration_within_the_path_limit() {
    // A full circle of radius 5 at a feed far above what the curvature allows.
    let mut p = Program::new(Xyz::new(5.0, 0.0, 0.0), PathMode::ExactStop);
    p.arc(0, Xyz::ZERO, std::f64::consts::TAU - 1e-9, 0.0, Rate::Feed(60000.0));
    let cfg = PlanConfig::new(Limits::uniform(1000.0, 500.0, 10000.0), 0.001, Xyz::new(5.0, 0.0, 0.0));
    let run = common::run(&cfg, &p.items);
    let top = moves_of(&run).iter().map(|s| norm(s.velocity)).fold(0.0, f64::max);
    // v² / r ≤ A·√3/2 at the cap.
    let share = 3f64.sqrt() / 2.0;
    assert!(top * top / 5.0 <= 1000.0 * share * (1.0 + 1e-9), "{top}");
    assert!(top * top / 5.0 >= 0.99 * 1000.0 * share, "the cap is used: {top}");
    // With weaker axes: a circle's acceleration vector lies in its plane, so an axis in the
    // plane sees at most |a|, and the axis limit takes the path limit's place.
    let cfg = PlanConfig::new(Limits::uniform(1000.0, 500.0, 400.0), 0.001, Xyz::new(5.0, 0.0, 0.0));
    let top = common::run(&cfg, &p.items).setpoints.iter().map(|s| norm(s.velocity)).fold(0.0, f64::max);
    assert!((top - (share * 400.0 * 5.0).sqrt()).abs() < 1e-9, "{top}");
}

#[test]
fn a_spiral_joined_tangentially_or_blended_keeps_the_acceleration_bound() {
    // A line into a spiral whose radius grows from 1 to 1.5 over half a turn, and a line out.
    // Joined exactly tangentially (no stop even under G61) and at a blended corner (G64): the
    // spiral's parameter runs at the real speed at its ends, so the speed never jumps there.
    let bound = 1000.0 * 1e-6 * (1.0 + 1e-6) + 1e-9;
    let feed = Rate::Feed(30000.0);
    for mode in [PathMode::ExactStop, PathMode::Blend { tolerance: None }, PathMode::Blend { tolerance: Some(0.05) }] {
        let mut p = Program::new(Xyz::ZERO, mode);
        p.line_to(Xyz::new(10.0, 0.0, 0.0), feed).tangent_spiral(
            Xyz::new(1.0, 0.0, 0.0),
            1.0,
            1.5,
            std::f64::consts::PI,
            feed,
        );
        let out = common::tangent(common::segments(&p.items)[1], true);
        p.line_to(common::add(p.pos, common::scale(out, 10.0)), feed);
        let run = common::run(&config(), &p.items);
        let (worst, _) = common::worst_second_difference(&run.setpoints);
        assert!(worst <= bound, "{mode:?}: |Δ²p| = {} a·T²", worst / 1e-3);
        let interior = &run.setpoints[1..run.setpoints.len() - 1];
        assert!(interior.iter().all(|s| norm(s.velocity) > 0.0), "{mode:?}: tangent joins do not stop");
    }
    // The same spiral entered at a corner (the line runs along +X, the spiral starts along
    // +Y): G64 blends it, cutting into the spiral where its radius is about 1.
    for tolerance in [None, Some(0.2)] {
        let mut p = Program::new(Xyz::ZERO, PathMode::Blend { tolerance });
        p.line_to(Xyz::new(10.0, 0.0, 0.0), feed).spiral(
            0,
            Xyz::new(9.0, 0.0, 0.0),
            std::f64::consts::PI,
            0.0,
            1.5,
            feed,
        );
        p.line_to(common::add(p.pos, Xyz::new(0.0, -10.0, 0.0)), feed);
        let run = common::run(&config(), &p.items);
        let (worst, _) = common::worst_second_difference(&run.setpoints);
        assert!(worst <= bound, "P {tolerance:?}: |Δ²p| = {} a·T²", worst / 1e-3);
        assert_eq!(common::interior_rests(&run.setpoints), 0, "P {tolerance:?}: both corners are blended");
    }
}

#[test]
fn an_output_happens_at_rest_at_its_programmed_point_and_a_dwell_holds() {
    let mut p = Program::new(Xyz::ZERO, PathMode::Blend { tolerance: None });
    p.line_to(Xyz::new(100.0, 100.0, 0.0), Rate::Rapid);
    p.item(|line| Item::Event {
        line,
        event: Event::Output(OutputCommand::Tool { tool: Some(1), command: SpindleCommand::Clockwise }),
    });
    p.line_to(Xyz::new(200.0, 200.0, 0.0), Rate::Feed(6000.0));
    p.item(|line| Item::Dwell { line, seconds: 0.25 });
    p.item(|line| Item::Event {
        line,
        event: Event::Output(OutputCommand::Tool { tool: Some(1), command: SpindleCommand::Stop }),
    });
    p.line_to(Xyz::new(1.0, 1.0, 0.0), Rate::Rapid);
    let run = common::run(&config(), &p.items);
    assert_eq!(run.events.len(), 2);
    let on = run.events[0];
    assert_eq!(on.line, 2);
    let at = run.setpoints.iter().find(|s| s.time == on.time).unwrap();
    assert_eq!(at.position, Xyz::new(100.0, 100.0, 0.0));
    let dwell: Vec<_> = run.setpoints.iter().filter(|s| s.line == 4).collect();
    assert_eq!(dwell.len(), 250);
    assert!(dwell.iter().all(|s| s.position == Xyz::new(200.0, 200.0, 0.0)));
    assert!(run.events[1].time >= dwell.last().unwrap().time + 0.001 - 1e-12);
}

#[test]
fn events_follow_the_setpoint_of_their_time_in_the_stream() {
    let mut p = Program::new(Xyz::ZERO, PathMode::ExactStop);
    p.line_to(Xyz::new(1.0, 0.0, 0.0), Rate::Feed(600.0));
    p.item(|line| Item::Event { line, event: Event::ToolChange(3) });
    p.item(|line| Item::Event {
        line,
        event: Event::Output(OutputCommand::Port { device: 1, port: 2, command: SpindleCommand::Clockwise }),
    });
    let steps: Vec<Step> = Setpoints::from_items(&config(), p.items).unwrap().map(Result::unwrap).collect();
    let mut last_time = 0.0;
    let mut seen = 0;
    for s in &steps {
        match s {
            Step::Setpoint(sp) => last_time = sp.time,
            Step::Event(e) => {
                assert_eq!(e.time, last_time, "an event comes right after the setpoint of its time");
                seen += 1;
            }
        }
    }
    assert_eq!(seen, 2);
}

#[test]
fn stop_brakes_along_the_path_within_the_limit_and_ends_at_rest() {
    let mut p = Program::new(Xyz::ZERO, PathMode::Blend { tolerance: Some(1.0) });
    p.line_to(Xyz::new(300.0, 0.0, 0.0), Rate::Feed(24000.0)).line_to(Xyz::new(300.0, 300.0, 0.0), Rate::Feed(24000.0));
    p.item(|line| Item::Event { line, event: Event::ToolChange(1) });
    let cfg = config();
    let mut stream = Setpoints::from_items(&cfg, p.items).unwrap();
    let mut sp = Vec::new();
    for step in stream.by_ref().take(700) {
        if let Step::Setpoint(s) = step.unwrap() {
            sp.push(s);
        }
    }
    assert!(norm(sp.last().unwrap().velocity) > 300.0, "at speed when stopped");
    stream.stop();
    let mut events = 0;
    for step in stream {
        match step.unwrap() {
            Step::Setpoint(s) => sp.push(s),
            Step::Event(_) => events += 1,
        }
    }
    assert_eq!(events, 0, "events not reached do not happen");
    let last = sp.last().unwrap();
    assert_eq!(last.velocity, Xyz::ZERO);
    assert!(last.position.x < 300.0 && last.position.y == 0.0, "stops on the path before the corner: {last:?}");
    // Braking from 400 units/s at 1000 units/s² takes 0.4 s.
    assert!((last.time - 0.7).abs() < 0.41, "{}", last.time);
    let bound = 1000.0 * 1e-6 * (1.0 + 1e-6) + 1e-9;
    for w in sp.windows(3) {
        let dd = sub(sub(w[2].position, w[1].position), sub(w[1].position, w[0].position));
        assert!(norm(dd) <= bound, "{} at {}", norm(dd), w[1].time);
    }
}

#[test]
fn stop_before_the_first_setpoint_or_at_rest_ends_at_once() {
    let mut p = Program::new(Xyz::ZERO, PathMode::ExactStop);
    p.item(|line| Item::Dwell { line, seconds: 10.0 });
    p.line_to(Xyz::new(5.0, 0.0, 0.0), Rate::Rapid);
    let mut s = Setpoints::from_items(&config(), p.items.clone()).unwrap();
    s.stop();
    let all: Vec<_> = s.collect();
    assert_eq!(all.len(), 1);
    let mut s = Setpoints::from_items(&config(), p.items).unwrap();
    assert_eq!(s.by_ref().take(100).count(), 100);
    s.stop();
    assert_eq!(s.count(), 1, "one more setpoint, at rest, then the end");
}

#[test]
fn an_error_arrives_at_its_place_after_the_motion_before_it_comes_to_rest() {
    let seg = Segment {
        line: 1,
        start: Xyz::ZERO,
        end: Xyz::new(10.0, 0.0, 0.0),
        shape: Shape::Line,
        rate: Rate::Feed(6000.0),
        mode: PathMode::Blend { tolerance: None },
    };
    let failure = PathError::Program { line: 2, column: None, message: "unknown word Q".into() };
    let items = vec![Ok(Item::Move(seg)), Err(failure.clone()), Ok(Item::End { line: 3 })];
    let steps: Vec<_> = Setpoints::new(&config(), items.into_iter()).unwrap().collect();
    let (last_ok, err) = (&steps[steps.len() - 2], &steps[steps.len() - 1]);
    match last_ok {
        Ok(Step::Setpoint(s)) => {
            assert_eq!(s.position, Xyz::new(10.0, 0.0, 0.0));
            assert_eq!(s.velocity, Xyz::ZERO);
        }
        other => panic!("expected the rest setpoint, got {other:?}"),
    }
    assert_eq!(err, &Err(failure));
}

fn first_error(items: Vec<Item>) -> PathError {
    Setpoints::from_items(&config(), items).unwrap().find_map(Result::err).expect("the program must be refused")
}

#[test]
fn bad_items_are_refused_with_their_line_and_what_to_do() {
    let line = |end: [f64; 3], rate| {
        Item::Move(Segment {
            line: 7,
            start: Xyz::ZERO,
            end: Xyz::from(end),
            shape: Shape::Line,
            rate,
            mode: PathMode::ExactStop,
        })
    };
    let e = first_error(vec![line([1.0, 0.0, 0.0], Rate::Feed(0.0))]);
    assert_eq!(e.line(), Some(7));
    assert!(e.to_string().contains("feed"), "{e}");
    let e = first_error(vec![line([f64::NAN, 0.0, 0.0], Rate::Rapid)]);
    assert!(e.to_string().contains("finite"), "{e}");
    let e = first_error(vec![Item::Move(Segment {
        line: 4,
        start: Xyz::new(1.0, 0.0, 0.0),
        end: Xyz::new(2.0, 0.0, 0.0),
        shape: Shape::Line,
        rate: Rate::Rapid,
        mode: PathMode::ExactStop,
    })]);
    assert!(e.to_string().contains("continuous"), "{e}");
    let e = first_error(vec![Item::Move(Segment {
        line: 5,
        start: Xyz::ZERO,
        end: Xyz::ZERO,
        shape: Shape::Arc(vision_path::ArcShape {
            centre: Xyz::ZERO,
            normal: Xyz::new(0.0, 0.0, 1.0),
            sweep: std::f64::consts::TAU,
        }),
        rate: Rate::Feed(100.0),
        mode: PathMode::ExactStop,
    })]);
    assert!(e.to_string().contains("zero radius"), "{e}");
    // A quarter turn that is said to be a half turn does not reach its end.
    let e = first_error(vec![Item::Move(Segment {
        line: 6,
        start: Xyz::ZERO,
        end: Xyz::new(-1.0, 1.0, 0.0),
        shape: Shape::Arc(vision_path::ArcShape {
            centre: Xyz::new(-1.0, 0.0, 0.0),
            normal: Xyz::new(0.0, 0.0, 1.0),
            sweep: std::f64::consts::PI,
        }),
        rate: Rate::Feed(100.0),
        mode: PathMode::ExactStop,
    })]);
    assert!(e.to_string().contains("sweep does not turn it"), "{e}");
    assert!(e.to_string().contains("line 6: "), "{e}");
    let e = first_error(vec![Item::Dwell { line: 9, seconds: -1.0 }]);
    assert_eq!(e.line(), Some(9));
    let e = first_error(vec![Item::Move(Segment {
        line: 2,
        start: Xyz::ZERO,
        end: Xyz::new(1.0, 0.0, 0.0),
        shape: Shape::Line,
        rate: Rate::Rapid,
        mode: PathMode::Blend { tolerance: Some(-1.0) },
    })]);
    assert!(e.to_string().contains("G64"), "{e}");
}

#[test]
fn an_empty_program_is_one_setpoint_at_the_start() {
    let cfg = PlanConfig::new(Limits::uniform(1000.0, 500.0, 1000.0), 0.004, Xyz::new(1.0, 2.0, 3.0));
    let s = Setpoints::from_items(&cfg, vec![Item::End { line: 1 }]).unwrap().run_to_end().unwrap();
    assert_eq!((s.setpoints, s.cycle_time, s.end), (1, 0.0, Xyz::new(1.0, 2.0, 3.0)));
    assert!(Setpoints::from_items(&PlanConfig { period: 0.0, ..cfg }, vec![]).is_err());
}
