//! The same physical machine plans the same cycle time whether its coordinates are in inches or
//! millimetres: a program's G20/G21 and the machine unit are bookkeeping, not physics.

use proptest::prelude::*;
use vision_gcode::{Interpreter, InterpreterConfig};
use vision_math::{LengthUnit, MM_PER_INCH};
use vision_path::{GcodeItems, Limits, PlanConfig, Setpoints, Step};

/// The last setpoint's time (s) of `program` on a machine in `unit` whose limits are the
/// physical ones given in millimetres.
fn cycle_time(program: &str, unit: LengthUnit, accel_mm: f64, speed_mm: f64) -> f64 {
    let k = match unit {
        LengthUnit::Millimetre => 1.0,
        LengthUnit::Inch => 1.0 / MM_PER_INCH,
    };
    let limits = Limits::uniform(accel_mm * k, speed_mm * k, accel_mm * k);
    let items = GcodeItems::new(Interpreter::new(InterpreterConfig::new(unit)), program);
    let plan = PlanConfig::new(limits, 0.001, items.start_position());
    let mut last = 0.0;
    for step in Setpoints::new(&plan, items).expect("plans") {
        if let Step::Setpoint(s) = step.expect("runs") {
            last = s.time;
        }
    }
    last
}

/// A short G64 program of lines and tangent-ish arcs in millimetres, from `moves`.
fn program(tolerance: Option<f64>, feed: f64, moves: &[(bool, f64, f64)]) -> String {
    let mut text = match tolerance {
        Some(p) => format!("G21 G90 G17 G64 P{p:.3} F{feed:.1}\n"),
        None => format!("G21 G90 G17 G64 F{feed:.1}\n"),
    };
    let (mut x, mut y) = (0.0, 0.0);
    for &(arc, dx, dy) in moves {
        if arc {
            // A half circle to (x + dx, y): centre halfway.
            text.push_str(&format!("G3 X{:.3} Y{y:.3} I{:.3} J0\n", x + dx, dx / 2.0));
            x += dx;
        } else {
            x += dx;
            y += dy;
            text.push_str(&format!("G1 X{x:.3} Y{y:.3}\n"));
        }
    }
    text
}

/// The smallest case the property below found: a line, then a small arc away from the origin,
/// whose radii to start and end differ in the last bit in millimetres and not in inches. It
/// planned 1.016 s against 0.985 s (G61) when that rounding made the arc a spiral.
#[test]
fn a_line_then_a_small_arc_plans_alike_in_both_units() {
    let text = "G21 G90 G17 G61 F3321.0\nG1 X33.979 Y0.000\nG3 X36.505 Y0.000 I1.263 J0\n";
    let mm = cycle_time(text, LengthUnit::Millimetre, 508.0, 500.0);
    let inch = cycle_time(text, LengthUnit::Inch, 508.0, 500.0);
    assert!((mm - inch).abs() <= 0.0011 + 1e-3 * mm, "mm {mm} s, in {inch} s");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn inch_and_millimetre_machines_plan_the_same_cycle_time(
        tolerance in prop::option::of(0.001f64..0.5),
        feed in 300.0f64..6000.0,
        moves in prop::collection::vec((any::<bool>(), 0.5f64..40.0, -20.0f64..20.0), 1..6),
        accel in 200.0f64..3000.0,
    ) {
        let text = program(tolerance, feed, &moves);
        let mm = cycle_time(&text, LengthUnit::Millimetre, accel, 500.0);
        let inch = cycle_time(&text, LengthUnit::Inch, accel, 500.0);
        // One setpoint (1 ms) of rounding, and 0.1 % for the different float paths.
        prop_assert!((mm - inch).abs() <= 0.0011 + 1e-3 * mm, "{text}\nmm {mm} s, in {inch} s");
    }
}
