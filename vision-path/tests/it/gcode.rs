//! G-code through the interpreter and the adapter: what the interpreter reports is what the
//! planner drives, and the bounds hold on what G-code really contains (rounded arcs).

use crate::common;

use common::{worst_second_difference, Run};
use vision_gcode::{Interpreter, InterpreterConfig, Xyz};
use vision_math::LengthUnit;
use vision_path::{GcodeItems, Limits, PlanConfig, Setpoints};

const A: f64 = 1000.0;
const T: f64 = 0.001;

/// `program` (millimetres) on a machine with `A` path acceleration, axes at 500 mm/s and
/// `A`, 1 ms setpoints.
fn plan(program: &str) -> Run {
    let mut config = InterpreterConfig::new(LengthUnit::Millimetre);
    config.default_feed = Some(1000.0);
    let items = GcodeItems::new(Interpreter::new(config), program);
    let plan = PlanConfig::new(Limits::uniform(A, 500.0, A), T, items.start_position());
    common::collect(Setpoints::new(&plan, items).unwrap(), program)
}

#[test]
fn an_arc_of_a_nanoradian_is_not_driven_as_a_full_circle() {
    // The interpreter reports a 1e-9 rad arc (its end is 1e-8 mm past its start); the planner
    // must not take it for a full circle of 62.8 mm.
    let p = plan("G21 G90 G17\nG0 X10 Y0\nG3 X10 Y0.00000001 I-10 J0 F600");
    let arc: Vec<_> = p.setpoints.iter().filter(|s| s.line == 3).collect();
    assert!(arc.len() <= 2, "a 1e-8 mm arc takes at most a period or two: {}", arc.len());
    for s in &p.setpoints {
        assert!(s.position.x <= 10.0 + 1e-12 && s.position.y.abs() <= 1e-8, "{s:?}");
    }
    assert_eq!(p.setpoints.last().unwrap().position, Xyz::new(10.0, 1e-8, 0.0));
    // The whole program is the rapid's trapezoid: 10 mm at a = 1000 is a triangle of 0.2 s.
    let t = p.setpoints.last().unwrap().time;
    assert!(t < 0.21, "{t}");
    // With one full turn more (P2), the circle is driven.
    let p = plan("G21 G90 G17\nG0 X10 Y0\nG3 X10 Y0.00000001 I-10 J0 P2 F600");
    assert!(p.setpoints.iter().any(|s| s.position.x < -9.99), "the P2 arc goes round");
    assert!(worst_second_difference(&p.setpoints).0 <= A * T * T * (1.0 + 1e-6) + 1e-9);
}

#[test]
fn a_rounded_arc_that_is_slightly_a_spiral_keeps_the_acceleration_bound_where_it_is_blended() {
    // The start radius is 0.1 mm, the end radius 0.128 mm (within the interpreter's centre
    // tolerance): a spiral, blended (G64) into the lines on either side. A parameter whose
    // speed factor is below 1 at the spiral's smaller end made the real speed jump at the
    // blends (|Δ²p| up to 1.53·a·T²).
    let program = "G21 G90 G64\nG1 X0.1 Y-10 F3000\nG1 X0.1 Y0\nG3 X-0.128 Y0 I-0.1 J0\nG1 X-0.128 Y-10";
    let p = plan(program);
    let (path, axes) = worst_second_difference(&p.setpoints);
    assert!(path <= A * T * T * (1.0 + 1e-6) + 1e-9, "|Δ²p| = {} a·T²", path / (A * T * T));
    assert!(axes.iter().all(|&d| d <= A * T * T * (1.0 + 1e-6) + 1e-9), "{axes:?}");
    assert!(p.setpoints.iter().any(|s| s.line == 4), "the spiral is driven");
    assert_eq!(common::interior_rests(&p.setpoints), 0, "the corner is blended, the spiral's joins pass");
    assert_eq!(p.setpoints.last().unwrap().position, Xyz::new(-0.128, -10.0, 0.0));
}
