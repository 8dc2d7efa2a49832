//! `emit` behind the host's alignment: a real program run by `vision_gcode` under
//! `Context::set_host_alignment`, emitted, and run on the emulated Grbl; and the events other
//! than moves.

use vision_gcode::{
    Context, Coolant, Event, Interpreter, LinearMove, OutputChange, PathMode, Rate, SpindleCommand, UserCall, Xyz,
};
use vision_grbl::emit::{EmitError, Emitter, Frame};
use vision_math::{AlignmentChain, Point2, Vector2};

use crate::emit::{grbl, reader, run, words};

/// The firmware's G54 in these tests (mm).
const WCO: [f64; 3] = [-100.0, -50.0, -20.0];

/// The events of `program` run under `chain` (mm machine, Grbl's dialect, G54 at zero).
fn events(chain: AlignmentChain, program: &str) -> (Interpreter, Vec<Event>) {
    let mut interp = reader([0.0; 3]);
    let mut host = Vec::new();
    let mut ctx: Context<'_> = interp.context(&mut host);
    ctx.set_host_alignment(Some(chain)).expect("chain");
    let mut events = Vec::new();
    interp.run(program, None, &mut events).expect("runs");
    (interp, events)
}

fn chain(scale: (f64, f64), rotation_deg: f64, center: (f64, f64), shift: (f64, f64)) -> AlignmentChain {
    AlignmentChain {
        scale: Vector2::new(scale.0, scale.1),
        center: Point2::new(center.0, center.1),
        rotation_deg,
        shift: Vector2::new(shift.0, shift.1),
    }
}

fn emitter(wco: [f64; 3], work_system: u8) -> Emitter {
    Emitter::new(Frame { mm_per_unit: 1.0, wco, work_system }, Xyz::ZERO).expect("frame")
}

fn assert_near(got: [f64; 3], want: Xyz, tolerance: f64, what: &str) {
    for axis in 0..3 {
        assert!((got[axis] - want.axis(axis)).abs() <= tolerance, "{what}: {got:?}, expected {want:?}");
    }
}

#[test]
fn g91_moves_turn_with_the_alignment_and_g53_moves_do_not() {
    let c = chain((1.0, 1.0), 30.0, (2.0, 3.0), (4.0, -1.0));
    let (sin, cos) = 30f64.to_radians().sin_cos();
    let turn = |x: f64, y: f64| Xyz::new(cos * x - sin * y, sin * x + cos * y, 0.0);
    let map = |x: f64, y: f64, z: f64| turn(x - 2.0, y - 3.0) + Xyz::new(2.0 + 4.0, 3.0 - 1.0, z);
    let program = "G21 G90 G17\nG0 X10 Y0 Z5\nG91 G1 X10 F1000\nG1 Y-4 Z-2\nG90 G53 G0 X5 Y5 Z1\n\
                   G91 G0 X0 Y10\nG90 G0 X0 Y0 Z0";
    let first = map(10.0, 0.0, 5.0);
    let second = first + turn(10.0, 0.0);
    let third = second + turn(0.0, -4.0) + Xyz::new(0.0, 0.0, -2.0);
    let machine = Xyz::new(5.0, 5.0, 1.0);
    let expected = [first, second, third, machine, machine + turn(0.0, 10.0), map(0.0, 0.0, 0.0)];
    let (_, events) = events(c, program);
    assert_eq!(events.len(), expected.len(), "{events:?}");
    let mut emitter = emitter(WCO, 1);
    let mut m = grbl(WCO);
    run(&mut m, &emitter.preamble());
    for (event, want) in events.iter().zip(expected) {
        assert!((event.end().expect("a move") - want).max_abs() < 1e-9, "{event:?}, expected {want:?}");
        let lines = emitter.event(event).expect("emitted");
        run(&mut m, &lines);
        assert_near(m.machine_position(), want, 0.001, &format!("{lines:?}"));
    }
}

#[test]
fn a_full_circle_under_rotation_and_uniform_scale_is_one_exact_circle() {
    let c = chain((1.25, 1.25), 30.0, (1.0, 2.0), (3.0, 4.0));
    let (_, events) = events(c, "G21 G90 G17\nG0 X10 Y0\nG2 X10 Y0 I-5 J0 F500");
    let centre = c.apply(Point2::new(5.0, 0.0));
    let start = c.apply(Point2::new(10.0, 0.0));
    let mut emitter = emitter(WCO, 1);
    let mut m = grbl(WCO);
    run(&mut m, &emitter.preamble());
    let lines = emitter.event(&events[0]).expect("rapid");
    run(&mut m, &lines);
    let lines = emitter.event(&events[1]).expect("circle");
    assert_eq!(lines.len(), 1, "{lines:?}");
    let w: Vec<(char, f64)> = words(&lines[0]).into_iter().map(|(l, n)| (l, n.parse().expect("number"))).collect();
    let word = |letter: char| w.iter().find(|(l, _)| *l == letter).map(|(_, v)| *v).expect("word");
    assert_eq!(w[0], ('G', 2.0), "{lines:?}");
    let (x, y) = (word('X') + WCO[0], word('Y') + WCO[1]);
    assert!((x - start.x).abs() <= 0.001 && (y - start.y).abs() <= 0.001, "end == start: {lines:?}");
    let (i, j) = (word('I'), word('J'));
    assert!((x + i - centre.x).abs() <= 0.001 && (y + j - centre.y).abs() <= 0.001, "centre: {lines:?}");
    assert!((i.hypot(j) - 6.25).abs() <= 0.001, "radius: {lines:?}");
    run(&mut m, &lines);
    assert_near(m.machine_position(), Xyz::new(start.x, start.y, 0.0), 0.001, "back at the start");
}

#[test]
fn a_non_uniform_scale_gives_segments_on_the_mapped_ellipse() {
    let c = chain((1.0, 1.02), 30.0, (1.0, 2.0), (3.0, 4.0));
    let (interp, events) = events(c, "G21 G90 G17\nG0 X10 Y0\nG3 X-10 Y0 I-10 J0 F500");
    let tolerance = interp.config().chord_tolerance;
    let mut emitter = emitter(WCO, 1);
    let mut m = grbl(WCO);
    run(&mut m, &emitter.preamble());
    let mut lines = Vec::new();
    for e in &events {
        lines.extend(emitter.event(e).expect("emitted"));
    }
    run(&mut m, &lines);
    // The vertices, machine coordinates: each line's X/Y after the modal ones.
    let (mut x, mut y) = (0.0, 0.0);
    let mut vertices = Vec::new();
    for line in &lines[1..] {
        for (letter, number) in words(line) {
            match letter {
                'G' => assert_eq!(number, "1", "segments, not arcs: {line}"),
                'X' => x = number.parse::<f64>().expect("X") + WCO[0],
                'Y' => y = number.parse::<f64>().expect("Y") + WCO[1],
                _ => {}
            }
        }
        vertices.push(Point2::new(x, y));
    }
    assert!(vertices.len() > 20, "{lines:?}");
    // Off the circle of radius 10 in the program frame; the map stretches by at most 1.02.
    let off = |p: Point2<f64>| 1.02 * (10.0 - c.inverse(p).expect("invertible").coords.norm());
    let mut previous = c.apply(Point2::new(10.0, 0.0));
    for v in vertices {
        assert!(off(v).abs() <= 0.001, "vertex {v:?} off by {}", off(v));
        let mid = Point2::from((previous.coords + v.coords) / 2.0);
        assert!(off(mid) <= tolerance + 0.001, "midpoint {mid:?} off by {}", off(mid));
        previous = v;
    }
    let end = c.apply(Point2::new(-10.0, 0.0));
    assert_near(m.machine_position(), Xyz::new(end.x, end.y, 0.0), 0.001, "the arc's end");
}

#[test]
fn after_m2_the_preamble_goes_again_and_the_other_events_are_grbl_words() {
    let g55 = [12.5, -7.25, 3.0];
    let mut m = grbl([0.0; 3]);
    assert_eq!(crate::emit::send(&mut m, "G10 L2 P2 X12.5 Y-7.25 Z3"), "ok");
    let mut emitter = emitter(g55, 2);
    assert_eq!(emitter.preamble(), ["G21 G90 G94 G17 G55"]);
    run(&mut m, &emitter.preamble());
    let to = |x: f64, rate: Rate| {
        Event::Linear(LinearMove {
            line: 1,
            start: Xyz::ZERO,
            end: Xyz::new(x, 1.0, 2.0),
            rate,
            path: PathMode::ExactStop,
        })
    };
    let cases: Vec<(Event, Vec<&str>)> = vec![
        (to(20.0, Rate::Feed(300.0)), vec!["G1 X7.5 Y8.25 Z-1 F300"]),
        (Event::Spindle { line: 2, command: SpindleCommand::Clockwise, speed: Some(12_000.0) }, vec!["M3 S12000"]),
        (Event::Coolant { line: 3, coolant: Coolant::Flood }, vec!["M8"]),
        (Event::Dwell { line: 4, seconds: 0.25 }, vec!["G4 P0.25"]),
        (Event::Stop { line: 5, optional: true }, vec!["M1"]),
        (Event::ToolChange { line: 6, tool: 2, offset: Xyz::ZERO }, vec![]),
        (
            Event::Output(OutputChange { line: 7, command: SpindleCommand::Stop, tool: Some(1), writes: Vec::new() }),
            vec!["M5"],
        ),
        (Event::ProgramEnd { line: 8, code: 2 }, vec!["M2"]),
        // Grbl's M2 went back to G54: the preamble selects G55 again.
        (to(30.0, Rate::Rapid), vec!["G21 G90 G94 G17 G55", "G0 X17.5"]),
        (to(30.0, Rate::Feed(300.0)), vec![]),
    ];
    for (event, want) in cases {
        let lines = emitter.event(&event).expect("emitted");
        assert_eq!(lines, want, "{event:?}");
        run(&mut m, &lines);
    }
    assert_near(m.machine_position(), Xyz::new(30.0, 1.0, 2.0), 0.001, "in G55 after M2");
    let call = UserCall { line: 9, code: 282, words: Vec::new(), comments: Vec::new() };
    assert_eq!(emitter.event(&Event::UserMCode(call)), Err(EmitError::UnhandledMCode { line: 9, code: 282 }));
    let bad = Event::Dwell { line: 10, seconds: f64::NAN };
    assert!(matches!(emitter.event(&bad), Err(EmitError::NonFinite { .. })));
    let far = to(200_000.0, Rate::Rapid);
    assert!(matches!(emitter.event(&far), Err(EmitError::BeyondRange { word: 'X', .. })));
    // A refused event changed nothing: the next move still knows where the firmware is.
    assert_eq!(emitter.event(&to(31.0, Rate::Rapid)).expect("move"), ["X18.5"]);
}

#[test]
fn g18_g3_takes_the_short_way_from_z_towards_x_as_linuxcnc_and_grbl_do() {
    // G18's axes are Z then X (normal +Y): G3 from X1 Z0 about the origin turns through
    // X > 0, Z < 0 to X0 Z-1, a quarter; G2 the other three quarters.
    for (program, quarter) in [("G3 X0 Z-1 I-1 K0", true), ("G2 X0 Z-1 I-1 K0", false)] {
        let text = format!("G21 G90 G18\nG0 X1 Z0\n{program} F500");
        let (_, events) = events(AlignmentChain::IDENTITY, &text);
        let Some(Event::Arc(arc)) = events.last() else { panic!("{events:?}") };
        assert!((arc.angle - if quarter { 0.25 } else { 0.75 } * std::f64::consts::TAU).abs() < 1e-12);
        let mut emitter = emitter([0.0; 3], 1);
        let mut m = grbl([0.0; 3]);
        run(&mut m, &emitter.preamble());
        run(&mut m, &emitter.event(&events[0]).expect("rapid"));
        let lines = emitter.event(&events[1]).expect("arc");
        assert_eq!(lines[1].split(' ').next(), program.split(' ').next(), "{lines:?}");
        let mut left_the_quarter = false;
        for line in &lines {
            crate::emit::check_words(line);
            m.receive(format!("{line}\n").as_bytes());
        }
        for _ in 0..5_000 {
            m.advance(0.001);
            let [x, _, z] = m.machine_position();
            left_the_quarter |= x < -0.01 || z > 0.01;
        }
        assert_eq!(String::from_utf8(m.take_output()).expect("utf8").matches("ok").count(), 2);
        assert_eq!(left_the_quarter, !quarter, "{program}");
        assert_near(m.machine_position(), Xyz::new(0.0, 0.0, -1.0), 0.001, program);
    }
}
