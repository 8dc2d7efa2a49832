//! Limits, feeds and run length at the edges of the physical range (issue 17, item 1): absurd
//! values are refused with a clear message, and no accepted input yields a cycle time that
//! breaks |Δp| ≤ v·T or a plan that never ends.

use crate::common;

use common::Program;
use vision_path::{Item, Limits, PathError, PathMode, PlanConfig, Rate, Setpoints, Xyz};

fn plan(limits: Limits, period: f64, items: Vec<Item>) -> Result<vision_path::Summary, PathError> {
    Setpoints::from_items(&PlanConfig::new(limits, period, Xyz::ZERO), items)?.run_to_end()
}

fn one_inch(rate: Rate) -> Vec<Item> {
    let mut p = Program::new(Xyz::ZERO, PathMode::ExactStop);
    p.line_to(Xyz::new(1.0, 0.0, 0.0), rate);
    p.item(|line| Item::End { line });
    p.items
}

#[test]
fn limits_outside_the_physical_range_are_refused_naming_the_limit() {
    for bad in [1e-300, 1e-12, 1e-5, 0.0, -1.0, f64::NAN, f64::INFINITY, 1e12] {
        for (limits, what) in [
            (Limits::uniform(bad, 10.0, 20.0), "max path acceleration"),
            (Limits::uniform(20.0, bad, 20.0), "axis max speed"),
            (Limits::uniform(20.0, 10.0, bad), "axis max acceleration"),
        ] {
            let e = limits.validate().expect_err("out of range");
            assert!(e.to_string().starts_with(what), "{bad}: {e}");
            assert!(matches!(e, PathError::InvalidConfig { .. }), "{e}");
            assert!(plan(limits, 0.001, one_inch(Rate::Rapid)).is_err());
        }
    }
    let slowest = Limits::uniform(*Limits::ACCEL_RANGE.start(), *Limits::SPEED_RANGE.start(), 1e-3);
    assert_eq!(slowest.validate(), Ok(()));
    let fastest = Limits::uniform(*Limits::ACCEL_RANGE.end(), *Limits::SPEED_RANGE.end(), 1e7);
    assert_eq!(fastest.validate(), Ok(()));
}

#[test]
fn a_feed_below_the_slowest_speed_is_refused_at_its_line() {
    let limits = Limits::uniform(20.0, 10.0, 20.0);
    for f in [1e-12, 1e-300, 0.005, 0.0, -1.0] {
        let e = plan(limits, 0.001, one_inch(Rate::Feed(f))).expect_err("too slow");
        assert_eq!(e.line(), Some(1), "F{f}: {e}");
        assert!(e.to_string().contains("feed"), "{e}");
    }
}

#[test]
fn the_slowest_accepted_motion_keeps_the_speed_bound() {
    // 1 unit at the slowest speed and acceleration: 10 000 s of motion at most 1e-4 units/s,
    // so the cycle time is at least length / speed (1e-200 once gave 0 s).
    let v = *Limits::SPEED_RANGE.start();
    let limits = Limits::uniform(*Limits::ACCEL_RANGE.start(), v, *Limits::ACCEL_RANGE.start());
    let s = plan(limits, 0.05, one_inch(Rate::Rapid)).expect("valid");
    assert!(s.cycle_time >= 1.0 / v, "cycle time {} s for 1 unit at {v} units/s", s.cycle_time);
    assert_eq!(s.end, Xyz::new(1.0, 0.0, 0.0));
    let s = plan(limits, 0.05, one_inch(Rate::Feed(v * 60.0))).expect("the slowest feed is accepted");
    assert!(s.cycle_time >= 1.0 / v, "{}", s.cycle_time);
}

#[test]
fn a_path_longer_than_the_setpoint_bound_ends_with_an_error_at_its_line_before_its_setpoints() {
    let limits = Limits::uniform(20.0, 10.0, 20.0);
    let mut config = PlanConfig::new(limits, 0.001, Xyz::ZERO);
    assert_eq!(config.max_setpoints, PlanConfig::DEFAULT_MAX_SETPOINTS);
    config.max_setpoints = 100;
    // One unit at F6 (0.1 units/s) takes 10 s: 10 000 setpoints.
    // Refused when the move is planned (issue 26: a circle of radius 1e9 was sampled for 45 s
    // before the bound stopped it).
    let steps: Vec<_> = Setpoints::from_items(&config, one_inch(Rate::Feed(6.0))).expect("valid").collect();
    assert_eq!(steps.len(), 1, "the error alone");
    let e = steps[0].as_ref().expect_err("an error");
    assert_eq!(e.line(), Some(1));
    assert!(e.to_string().contains("longer than 100 setpoints"), "{e}");
    // The same move within the bound runs to its end.
    config.max_setpoints = 20_000;
    let s = Setpoints::from_items(&config, one_inch(Rate::Feed(6.0))).expect("valid").run_to_end().expect("fits");
    assert!(s.setpoints > 10_000);
}
