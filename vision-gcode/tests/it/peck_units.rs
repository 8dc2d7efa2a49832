//! G73/G83 count their pecks in the program's units, as LinuxCNC's rs274 does: a millimetre
//! program makes the same pecks on an inch machine as on a millimetre one, also where the hole
//! depth is an exact multiple of Q (there the conversion to inches used to round one peck away).

use vision_gcode::{Event, GcodeError, Interpreter, InterpreterConfig, RunProblem, Xyz};
use vision_math::LengthUnit;

/// The end points of `text`'s straight moves on a `unit` machine, in millimetres.
fn moves_mm(unit: LengthUnit, text: &str) -> Vec<Xyz> {
    let mut interp = Interpreter::new(InterpreterConfig::new(unit));
    let mut events: Vec<Event> = Vec::new();
    interp.run(text, None, &mut events).expect("runs");
    let to_mm = unit.factor_to(LengthUnit::Millimetre);
    events
        .iter()
        .filter_map(|e| match e {
            Event::Linear(m) => Some(m.end * to_mm),
            _ => None,
        })
        .collect()
}

#[test]
fn inch_and_millimetre_machines_make_the_same_pecks() {
    // Depths that are exact multiples of Q (R − k·Q), absolute and incremental, and ordinary ones.
    for cycle in [
        "G90 G83 X0 Y0 Z-0.9 R0.3 Q0.3",
        "G90 G73 X1 Y0 Z-0.9 R0.3 Q0.3",
        "G90 G83 X0 Y0 Z-1.04 R0.67 Q1.71",
        "G90 G83 X0 Y0 Z-10.16 R2.54 Q2.54 L2",
        "G91 G83 X7.62 Y5.08 Z-10.16 R2.54 Q2.54 L3",
        "G91 G83 X1 Z-0.6 R0.3 Q0.3",
        "G90 G83 X0 Y0 Z-3.7 R0.2 Q0.9",
    ] {
        let text = format!("G21 G17 G90 F500\nG0 X0 Y0 Z5\n{cycle}\nG80");
        let mm = moves_mm(LengthUnit::Millimetre, &text);
        let inch = moves_mm(LengthUnit::Inch, &text);
        assert_eq!(mm.len(), inch.len(), "{cycle}: {mm:?}\n{inch:?}");
        for (a, b) in mm.iter().zip(&inch) {
            assert!((*a - *b).norm() < 1e-9, "{cycle}: {a:?} vs {b:?}");
        }
    }
}

#[test]
fn a_peck_far_below_the_hole_depth_is_refused() {
    let mut interp = Interpreter::new(InterpreterConfig::new(LengthUnit::Millimetre));
    let mut events: Vec<Event> = Vec::new();
    let result = interp.run("G21 G90 F500\nG0 Z5\nG83 X0 Y0 Z-100 R1 Q[10**-300]", None, &mut events);
    match result {
        Err(GcodeError::Run { problem: RunProblem::OutOfRange { letter: 'Q', .. }, line: 3, .. }) => {}
        other => panic!("expected Q out of range, got {other:?}"),
    }
}
