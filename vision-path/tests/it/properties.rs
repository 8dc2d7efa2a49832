//! The planner's promises, checked on random programs against an independent model of the
//! programmed path:
//!
//! * no step between setpoints exceeds speed × period (path speed per line, and per axis);
//! * no second difference exceeds acceleration × period² (path and per axis), within the
//!   stated tolerance `(1 + 1e-6)·a·T² + 1e-9` units — also on spirals (arcs whose end radius
//!   differs from their start radius, as rounded G-code makes them) joined tangentially;
//! * G61 reaches every corner exactly (bitwise) with zero velocity;
//! * G64 P never strays more than P from the programmed path, and the path never comes to rest
//!   at a corner the planner's rules blend (two lines, not a reversal);
//! * the path ends exactly (bitwise) at the programmed end, at rest;
//! * events happen at rest at their programmed point, dwells last their time;
//! * a single straight move takes the analytic trapezoid (or triangle) time, rounded up to
//!   the next period.
#![expect(clippy::float_cmp, reason = "tests compare exact values")]

use crate::common;

use common::{distance, norm, segments, sub, tangent, Program, Run, PLANES};
use proptest::prelude::*;
use vision_path::Xyz;
use vision_path::{AxisLimits, Event, Item, Limits, OutputCommand, PathMode, PlanConfig, Rate, SpindleCommand};

const REL: f64 = 1e-6;
const ABS: f64 = 1e-9;

#[derive(Debug, Clone)]
enum Op {
    Line {
        to: [f64; 3],
        rapid: bool,
    },
    /// A short move relative to the current point (stresses blends and the look-ahead).
    Nudge([f64; 3]),
    /// An arc (a spiral when `grow` ≠ 1: the end radius is `grow` × the start radius).
    Arc {
        plane: usize,
        dir: f64,
        radius: f64,
        angle: f64,
        rise: f64,
        grow: f64,
    },
    /// In XY: a line along `heading`, a spiral leaving it exactly tangentially (radius `r0` →
    /// `r0·grow`), and a line leaving the spiral exactly tangentially.
    TangentSpiral {
        heading: f64,
        lead: f64,
        r0: f64,
        grow: f64,
        angle: f64,
    },
    Dwell(f64),
    Tool(bool),
}

fn op(helix: bool) -> impl Strategy<Value = Op> {
    let coord = -50.0..50.0f64;
    prop_oneof![
        6 => ([coord.clone(), coord.clone(), coord], prop::bool::weighted(0.2))
            .prop_map(|(to, rapid)| Op::Line { to, rapid }),
        3 => prop::array::uniform3(-1.0..1.0f64).prop_map(Op::Nudge),
        3 => (0..3usize, 0.0..std::f64::consts::TAU, 1.0..30.0f64, -6.0..6.0f64, -5.0..5.0f64, grow())
            .prop_filter("arcs sweep at least 0.1 rad", |(_, _, _, a, _, _)| a.abs() > 0.1)
            .prop_map(move |(plane, dir, radius, angle, rise, grow)| Op::Arc {
                plane, dir, radius, angle, rise: if helix { rise } else { 0.0 }, grow,
            }),
        1 => (0.0..std::f64::consts::TAU, 0.5..20.0f64, 0.2..20.0f64, 0.7..1.5f64, -6.0..6.0f64)
            .prop_filter("spirals sweep at least 0.1 rad", |(_, _, _, _, a)| a.abs() > 0.1)
            .prop_map(|(heading, lead, r0, grow, angle)| Op::TangentSpiral { heading, lead, r0, grow, angle }),
        1 => (0.0..0.05f64).prop_map(Op::Dwell),
        1 => any::<bool>().prop_map(Op::Tool),
    ]
}

/// The end radius over the start radius of an arc: mostly a circle, often a spiral.
fn grow() -> impl Strategy<Value = f64> {
    prop_oneof![2 => Just(1.0), 1 => 0.8..1.25f64]
}

fn limits() -> impl Strategy<Value = (Limits, f64)> {
    (
        200.0..5000.0f64,
        prop::array::uniform3((50.0..800.0f64, 200.0..8000.0f64)),
        prop::sample::select(vec![0.001, 0.002, 0.004]),
    )
        .prop_map(|(a, axes, period)| {
            let axes = axes.map(|(max_speed, max_accel)| AxisLimits { max_speed, max_accel });
            (Limits { max_path_accel: a, axes }, period)
        })
}

fn build(ops: &[Op], mode: PathMode, feed: f64) -> Vec<Item> {
    let mut p = Program::new(Xyz::new(1.0, 2.0, 3.0), mode);
    for op in ops {
        match *op {
            Op::Line { to, rapid } => {
                p.line_to(Xyz::from(to), if rapid { Rate::Rapid } else { Rate::Feed(feed) });
            }
            Op::Nudge(d) => {
                p.line_to(common::add(p.pos, Xyz::from(d)), Rate::Feed(feed));
            }
            Op::Arc { plane, dir, radius, angle, rise, grow } => {
                // The centre lies `radius` away from the current point, in the arc's plane.
                let (b1, b2) = match plane {
                    0 => ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
                    1 => ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0]),
                    _ => ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
                };
                let off = common::add(
                    common::scale(Xyz::from(b1), radius * dir.cos()),
                    common::scale(Xyz::from(b2), radius * dir.sin()),
                );
                let centre = common::add(p.pos, off);
                debug_assert!(common::dot(off, PLANES[plane]).abs() < 1e-12);
                p.spiral(plane, centre, angle, rise, grow, Rate::Feed(feed));
            }
            Op::TangentSpiral { heading, lead, r0, grow, angle } => {
                let u = [heading.cos(), heading.sin(), 0.0];
                p.line_to(common::add(p.pos, common::scale(Xyz::from(u), lead)), Rate::Feed(feed));
                p.tangent_spiral(Xyz::from(u), r0, r0 * grow, angle, Rate::Feed(feed));
                let out = segments(&p.items).last().map(|s| tangent(s, true)).expect("the spiral");
                p.line_to(common::add(p.pos, common::scale(out, lead)), Rate::Feed(feed));
            }
            Op::Dwell(seconds) => {
                p.item(|line| Item::Dwell { line, seconds });
            }
            Op::Tool(on) => {
                let command = if on { SpindleCommand::Clockwise } else { SpindleCommand::Stop };
                p.item(|line| Item::Event {
                    line,
                    event: Event::Output(OutputCommand::Tool { tool: Some(1), command }),
                });
            }
        }
    }
    p.item(|line| Item::End { line });
    p.items
}

/// The speed each line asks for, units/s (rapid and non-motion lines: unbounded here; the
/// axis limits bound them).
fn requested(items: &[Item], line: usize) -> f64 {
    items.iter().find(|i| i.line() == line).map_or(f64::INFINITY, |i| match i {
        Item::Move(s) => match s.rate {
            Rate::Feed(f) => f / 60.0,
            Rate::Rapid => f64::INFINITY,
        },
        _ => 0.0,
    })
}

fn check_kinematics(run: &Run, items: &[Item], limits: &Limits, period: f64) -> Result<(), TestCaseError> {
    let sp = &run.setpoints;
    for w in sp.windows(2) {
        prop_assert!((w[1].time - w[0].time - period).abs() < 1e-9, "fixed period");
        let d = sub(w[1].position, w[0].position);
        let v = requested(items, w[0].line).max(requested(items, w[1].line));
        prop_assert!(
            norm(d) <= v * period * (1.0 + REL) + ABS,
            "step {} > {} at t = {}",
            norm(d),
            v * period,
            w[1].time
        );
        for (i, axis) in limits.axes.iter().enumerate() {
            prop_assert!(
                d.axis(i).abs() <= axis.max_speed * period * (1.0 + REL) + ABS,
                "axis {i} step {} at t = {}",
                d.axis(i),
                w[1].time
            );
        }
    }
    let t2 = period * period;
    for w in sp.windows(3) {
        let dd = sub(sub(w[2].position, w[1].position), sub(w[1].position, w[0].position));
        let bound = limits.max_path_accel * t2;
        prop_assert!(
            norm(dd) <= bound * (1.0 + REL) + ABS,
            "second difference {} > {} at t = {} (line {})",
            norm(dd),
            bound,
            w[1].time,
            w[1].line
        );
        for (i, axis) in limits.axes.iter().enumerate() {
            prop_assert!(
                dd.axis(i).abs() <= axis.max_accel * t2 * (1.0 + REL) + ABS,
                "axis {i} second difference {} at t = {}",
                dd.axis(i),
                w[1].time
            );
        }
    }
    Ok(())
}

fn check_end_events_dwells(run: &Run, items: &[Item], period: f64) -> Result<(), TestCaseError> {
    let last = run.setpoints.last().expect("at least one setpoint");
    let end = segments(items).last().map_or(Xyz::new(1.0, 2.0, 3.0), |s| s.end);
    prop_assert_eq!(last.position, end, "the path ends exactly at the programmed end");
    prop_assert_eq!(last.velocity, Xyz::ZERO);
    let mut pos = Xyz::new(1.0, 2.0, 3.0);
    let mut events = run.events.iter();
    for item in items {
        match item {
            Item::Move(s) => pos = s.end,
            Item::Event { line, event } => {
                let ev = events.next().expect("every event is emitted");
                prop_assert_eq!(ev.line, *line);
                prop_assert_eq!(ev.event, *event);
                let at = run.setpoints.iter().find(|s| s.time == ev.time).expect("a setpoint at the event's time");
                prop_assert_eq!(at.position, pos, "events happen at the programmed point");
                prop_assert_eq!(at.velocity, Xyz::ZERO);
            }
            Item::Dwell { line, seconds } if *seconds > 0.0 => {
                let held: Vec<_> = run.setpoints.iter().filter(|s| s.line == *line).collect();
                let span = held.last().unwrap().time + period - held[0].time;
                prop_assert!(span >= seconds - 1e-9 && span <= seconds + period + 1e-9, "dwell {seconds} held {span}");
                prop_assert!(held.iter().all(|s| s.position == pos));
            }
            _ => {}
        }
    }
    prop_assert!(events.next().is_none());
    Ok(())
}

fn config(limits: Limits, period: f64) -> PlanConfig {
    PlanConfig::new(limits, period, Xyz::new(1.0, 2.0, 3.0))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: common::cases(160), ..ProptestConfig::default() })]

    #[test]
    fn exact_stop_programs_obey_the_limits_and_stop_at_every_corner(
        ops in prop::collection::vec(op(true), 1..16),
        (limits, period) in limits(),
        feed in 1200.0..30000.0f64,
    ) {
        let items = build(&ops, PathMode::ExactStop, feed);
        let run = common::run(&config(limits, period), &items);
        check_kinematics(&run, &items, &limits, period)?;
        check_end_events_dwells(&run, &items, period)?;
        for w in items.windows(2) {
            if let (Item::Move(a), Item::Move(b)) = (&w[0], &w[1]) {
                let turn = common::dot(tangent(a, true), tangent(b, false)).clamp(-1.0, 1.0).acos();
                if turn > 1e-6 {
                    let hit = run.setpoints.iter().any(|s| s.position == a.end && s.velocity == Xyz::ZERO);
                    prop_assert!(hit, "no rest setpoint at the G61 corner {:?} (line {})", a.end, a.line);
                }
            }
        }
    }

    #[test]
    fn blended_programs_obey_the_limits_and_stay_within_p(
        ops in prop::collection::vec(op(false), 1..16),
        (limits, period) in limits(),
        feed in 1200.0..30000.0f64,
        p in prop::option::weighted(0.8, 0.01..5.0f64),
    ) {
        let items = build(&ops, PathMode::Blend { tolerance: p }, feed);
        let run = common::run(&config(limits, period), &items);
        check_kinematics(&run, &items, &limits, period)?;
        check_end_events_dwells(&run, &items, period)?;
        let (rests, allowed) = (common::interior_rests(&run.setpoints), common::allowed_rests(&items));
        prop_assert!(rests <= allowed, "{rests} stops inside the path, at most {allowed} allowed (blendable corners must not stop)");
        if let Some(p) = p {
            let segs = segments(&items);
            for s in &run.setpoints {
                let d = segs.iter().map(|g| distance(s.position, g)).fold(f64::INFINITY, f64::min);
                prop_assert!(segs.is_empty() || d <= p + 1e-9, "{:?} (line {}) is {d} from the path, P = {p}", s.position, s.line);
            }
        }
    }

    #[test]
    fn a_single_move_takes_the_analytic_trapezoid_time(
        to in prop::array::uniform3(-300.0..300.0f64),
        (limits, period) in limits(),
        feed in prop::option::of(600.0..60000.0f64),
    ) {
        let start = [1.0, 2.0, 3.0];
        let d = sub(Xyz::from(to), Xyz::from(start));
        let len = norm(d);
        prop_assume!(len > 1.0);
        let mut v = feed.map_or(f64::INFINITY, |f| f / 60.0);
        let mut a = limits.max_path_accel;
        for (di, axis) in d.to_array().iter().zip(&limits.axes) {
            let c = di.abs() / len;
            if c > 0.0 {
                v = v.min(axis.max_speed / c);
                a = a.min(axis.max_accel / c);
            }
        }
        let analytic = if len >= v * v / a { len / v + v / a } else { 2.0 * (len / a).sqrt() };
        let mut p = Program::new(Xyz::from(start), PathMode::ExactStop);
        p.line_to(Xyz::from(to), feed.map_or(Rate::Rapid, Rate::Feed));
        let summary = vision_path::Setpoints::from_items(&config(limits, period), p.items.clone())
            .unwrap()
            .run_to_end()
            .unwrap();
        prop_assert!(summary.cycle_time >= analytic - 1e-9 && summary.cycle_time < analytic + period + 1e-9,
            "planned {} vs analytic {analytic}", summary.cycle_time);
        if analytic >= 100.0 * period {
            prop_assert!((summary.cycle_time - analytic).abs() <= 0.01 * analytic);
        }
        prop_assert_eq!(summary.end, Xyz::from(to));
    }
}
