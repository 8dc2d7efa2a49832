//! Random G-code (moves, arcs, modes, dwells, tools, G68 rotation and non-uniform G51 scale,
//! whose arcs arrive as polylines) through the interpreter and the planner: the sampled
//! bounds hold, the path ends exactly where the interpreter leaves the machine, and a program
//! the interpreter refuses comes out as the error of its line, after the motion before it
//! came to rest; and the path comes to rest only where an event, a dwell or a corner that is
//! not blended between two lines (G61, `G64 P0`, a reversal, an arc) makes it.

use crate::common;

use std::fmt::Write as _;

use common::{norm, sub};
use proptest::prelude::*;
use vision_gcode::{Interpreter, InterpreterConfig, Xyz};
use vision_math::LengthUnit;
use vision_path::{GcodeItems, Item, Limits, PathError, PlanConfig, Setpoint, Setpoints, Step};

#[derive(Debug, Clone)]
enum Line {
    Move {
        rapid: bool,
        x: f64,
        y: f64,
        z: f64,
    },
    /// A G2/G3 in G17 about a centre at (i, j) from the current point, turning `angle` rad,
    /// its end `grow` mm off the circle (a spiral, within the interpreter's centre tolerance).
    Arc {
        cw: bool,
        i: f64,
        j: f64,
        angle: f64,
        grow: f64,
    },
    Mode(Option<Option<f64>>),
    Scale(f64, f64),
    Rotate(f64),
    Cancel,
    Dwell(f64),
    Tool(bool),
    Garbage,
}

/// How far an arc's end lies off its circle, mm: none, or up to 0.025 (the interpreter accepts
/// 0.028).
fn grow() -> impl Strategy<Value = f64> {
    prop_oneof![Just(0.0), -0.025..0.025f64]
}

fn line() -> impl Strategy<Value = Line> {
    prop_oneof![
        6 => (any::<bool>(), -40.0..40.0f64, -40.0..40.0f64, -5.0..5.0f64)
            .prop_map(|(rapid, x, y, z)| Line::Move { rapid, x, y, z }),
        3 => (any::<bool>(), -20.0..20.0f64, -20.0..20.0f64, 0.2..6.0f64, grow())
            .prop_filter("a real radius", |(_, i, j, _, _)| i.hypot(*j) > 1.0)
            .prop_map(|(cw, i, j, angle, grow)| Line::Arc { cw, i, j, angle, grow }),
        // Small arcs, where the rounding's spiral is a large part of the radius.
        2 => (any::<bool>(), 0.0..std::f64::consts::TAU, 0.08..1.0f64, 0.2..6.0f64, grow())
            .prop_map(|(cw, dir, r, angle, grow)| Line::Arc { cw, i: r * dir.cos(), j: r * dir.sin(), angle, grow }),
        1 => prop::option::of(prop::option::of(0.0..2.0f64)).prop_map(Line::Mode),
        1 => (0.5..2.0f64, 0.5..2.0f64).prop_map(|(a, b)| Line::Scale(a, b)),
        1 => (-90.0..90.0f64).prop_map(Line::Rotate),
        1 => Just(Line::Cancel),
        1 => (0.0..0.02f64).prop_map(Line::Dwell),
        1 => any::<bool>().prop_map(Line::Tool),
        1 => Just(Line::Garbage),
    ]
}

/// The program text; `pos` tracks the program-frame point to place arc ends on the circle.
fn program(lines: &[Line]) -> String {
    let mut text = String::from("G21 G90 G17 G91.1 F3000 T1 M6\n");
    let (mut px, mut py) = (0.0f64, 0.0f64);
    for l in lines {
        match *l {
            Line::Move { rapid, x, y, z } => {
                let _ = writeln!(text, "{} X{x:.4} Y{y:.4} Z{z:.4}", if rapid { "G0" } else { "G1" });
                (px, py) = ((x * 1e4).round() / 1e4, (y * 1e4).round() / 1e4);
            }
            Line::Arc { cw, i, j, angle, grow } => {
                let (i, j) = ((i * 1e4).round() / 1e4, (j * 1e4).round() / 1e4);
                let (cx, cy) = (px + i, py + j);
                let a0 = (-j).atan2(-i);
                let a1 = if cw { a0 - angle } else { a0 + angle };
                let r = i.hypot(j) + grow;
                let (ex, ey) = (cx + r * a1.cos(), cy + r * a1.sin());
                let _ = writeln!(text, "{} X{ex:.4} Y{ey:.4} I{i:.4} J{j:.4}", if cw { "G2" } else { "G3" });
                (px, py) = ((ex * 1e4).round() / 1e4, (ey * 1e4).round() / 1e4);
            }
            Line::Mode(None) => text.push_str("G61\n"),
            Line::Mode(Some(None)) => text.push_str("G64\n"),
            Line::Mode(Some(Some(p))) => {
                let _ = writeln!(text, "G64 P{p:.3}");
            }
            // A frame change re-derives the program point from the machine; going back to the
            // tracked point (in the new frame) keeps the arcs' ends on their circles.
            Line::Scale(a, b) => {
                let _ = writeln!(text, "G51 X{a:.3} Y{b:.3}\nG0 X{px:.4} Y{py:.4}");
            }
            Line::Rotate(r) => {
                let _ = writeln!(text, "G68 X0 Y0 R{r:.3}\nG0 X{px:.4} Y{py:.4}");
            }
            Line::Cancel => {
                let _ = writeln!(text, "G69 G50\nG0 X{px:.4} Y{py:.4}");
            }
            Line::Dwell(s) => {
                let _ = writeln!(text, "G4 P{s:.3}");
            }
            Line::Tool(on) => text.push_str(if on { "M3\n" } else { "M5\n" }),
            Line::Garbage => text.push_str("G1 X1 Q7\n"),
        }
    }
    text.push_str("M30\n");
    text
}

const A: f64 = 800.0;
const T: f64 = 0.002;

proptest! {
    #![proptest_config(ProptestConfig { cases: common::cases(1024), ..ProptestConfig::default() })]

    #[test]
    fn gcode_programs_plan_within_the_limits_and_end_where_the_interpreter_does(
        lines in prop::collection::vec(line(), 1..14)
    ) {
        let text = program(&lines);
        let mut config = InterpreterConfig::new(LengthUnit::Millimetre);
        config.default_feed = Some(3000.0);
        let items = GcodeItems::new(Interpreter::new(config.clone()), text.as_str());
        let plan = PlanConfig::new(Limits::uniform(A, 300.0, 1500.0), T, items.start_position());
        let items: Vec<_> = items.collect();
        let mut setpoints: Vec<Setpoint> = Vec::new();
        let mut failure = None;
        for step in Setpoints::new(&plan, items.clone().into_iter()).unwrap() {
            match step {
                Ok(Step::Setpoint(s)) => setpoints.push(s),
                Ok(Step::Event(_)) => {}
                Err(e) => failure = Some(e),
            }
        }
        for w in setpoints.windows(3) {
            let dd = sub(sub(w[2].position, w[1].position), sub(w[1].position, w[0].position));
            prop_assert!(norm(dd) <= A * T * T * (1.0 + 1e-6) + 1e-9, "acceleration at {} (line {})\n{text}", w[1].time, w[1].line);
            for c in dd.to_array() {
                prop_assert!(c.abs() <= 1500.0 * T * T * (1.0 + 1e-6) + 1e-9);
            }
        }
        for w in setpoints.windows(2) {
            for c in sub(w[1].position, w[0].position).to_array() {
                prop_assert!(c.abs() <= 300.0 * T * (1.0 + 1e-6) + 1e-9);
            }
        }
        let last = setpoints.last().unwrap();
        prop_assert_eq!(last.velocity, Xyz::ZERO);
        let ran: Vec<Item> = items.into_iter().map_while(Result::ok).collect();
        let (rests, allowed) = (common::interior_rests(&setpoints), common::allowed_rests(&ran));
        prop_assert!(rests <= allowed, "{} stops inside the path, at most {} allowed\n{}", rests, allowed, text);
        // The interpreter alone, up to where it stops.
        let mut interp = Interpreter::new(config);
        let outcome = interp.run(&text, None, &mut |_: &vision_gcode::Event| {});
        let m = interp.machine_position();
        prop_assert_eq!(last.position, m, "\n{}", text);
        match (outcome, failure) {
            (Ok(_), None) => {}
            (Err(e), Some(failure @ PathError::Program { line, column, .. })) => {
                prop_assert_eq!(line, e.line() as usize);
                prop_assert_eq!(column, e.column());
                // One position format: the planner says it as the interpreter does.
                prop_assert_eq!(failure.to_string(), e.to_string());
            }
            (o, f) => prop_assert!(false, "interpreter {:?} but planner {:?}\n{}", o, f, text),
        }
    }
}
