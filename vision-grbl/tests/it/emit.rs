//! `emit` round trips: random moves and arcs (three planes, both senses, helices, full and
//! multi-turn circles, radii from 0.05 mm to 3 m, inch and mm machines, a work offset) become
//! lines that the emulated Grbl accepts and moves to the event's end with, and that a fresh
//! `vision_gcode` interpreter reads back as the same geometry.

use std::f64::consts::TAU;

use proptest::prelude::*;
use vision_gcode::{
    ArcDirection, ArcMove, Dialect, Event, Interpreter, InterpreterConfig, LinearMove, PathMode, Plane, Rate, Xyz,
};
use vision_grbl::emit::{Emitter, Frame, MAX_LINE};
use vision_grbl::emulator::{EmulatorConfig, Machine};
use vision_math::LengthUnit;

/// A controller with fine steps (0.1 µm), fast axes and `wco` as G54 (mm, 3 decimals).
pub(crate) fn grbl(wco: [f64; 3]) -> Machine {
    let mut settings = Vec::new();
    for axis in 0..3 {
        settings.extend([(100 + axis, 10_000.0), (110 + axis, 1_000_000.0), (120 + axis, 1_000_000.0)]);
    }
    settings.push((12, 0.01));
    let mut m = Machine::new(EmulatorConfig { settings, ..Default::default() });
    m.take_output();
    let line = format!("G10 L2 P1 X{:.3} Y{:.3} Z{:.3}", wco[0], wco[1], wco[2]);
    assert_eq!(send(&mut m, &line), "ok", "{line}");
    m
}

/// Sends one line, runs the controller until it answers; the answer's last line.
pub(crate) fn send(m: &mut Machine, line: &str) -> String {
    m.receive(format!("{line}\n").as_bytes());
    let mut got = String::new();
    for _ in 0..1_000_000 {
        m.advance(0.001);
        got.push_str(&String::from_utf8(m.take_output()).expect("utf8"));
        if got.ends_with("ok\r\n") || got.contains("error:") {
            break;
        }
    }
    got.trim_end().lines().last().unwrap_or_default().to_string()
}

/// Sends emitted lines (each checked by [`check_words`]), every one answered `ok`, and waits
/// until the motion is over.
pub(crate) fn run(m: &mut Machine, lines: &[String]) {
    for line in lines {
        check_words(line);
        assert_eq!(send(m, line), "ok", "{line}");
    }
    for _ in 0..10_000_000 {
        if !m.in_motion() {
            return;
        }
        m.advance(0.01);
    }
    panic!("the motion never ended");
}

/// The words of a line: letter and number text.
pub(crate) fn words(line: &str) -> Vec<(char, String)> {
    let mut out: Vec<(char, String)> = Vec::new();
    for c in line.chars().filter(|c| *c != ' ') {
        if c.is_ascii_uppercase() {
            out.push((c, String::new()));
        } else {
            out.last_mut().expect("a line starts with a letter").1.push(c);
        }
    }
    out
}

/// Only Grbl 1.1's words, numbers with at most 3 decimals, at most [`MAX_LINE`] characters.
pub(crate) fn check_words(line: &str) {
    assert!(line.len() <= MAX_LINE && line.len() <= 80, "too long: {line}");
    for (letter, number) in words(line) {
        match letter {
            'G' => assert!(
                [
                    "0", "1", "2", "3", "4", "17", "18", "19", "20", "21", "90", "91", "53", "54", "55", "56", "57",
                    "58", "59", "94"
                ]
                .contains(&number.as_str()),
                "G{number} in {line}"
            ),
            'M' => assert!(
                ["0", "1", "2", "30", "3", "4", "5", "7", "8", "9"].contains(&number.as_str()),
                "M{number} in {line}"
            ),
            'X' | 'Y' | 'Z' | 'I' | 'J' | 'K' | 'F' | 'S' | 'P' => {
                let value: f64 = number.parse().unwrap_or_else(|_| panic!("{letter}{number} in {line}"));
                let limit = if "XYZIJK".contains(letter) { 99_999.0 } else { 99_999_999.0 };
                assert!(value.is_finite() && value.abs() <= limit, "{line}");
                assert!(number.split('.').nth(1).is_none_or(|d| d.len() <= 3), "{line}");
                assert!(!number.contains(['e', 'E']), "{line}");
            }
            _ => panic!("{letter} in {line}"),
        }
    }
}

/// A mm interpreter in Grbl's dialect, G54 at `wco` (mm).
pub(crate) fn reader(wco: [f64; 3]) -> Interpreter {
    let mut config = InterpreterConfig::new(LengthUnit::Millimetre);
    config.dialect = Dialect::Grbl;
    let mut interp = Interpreter::new(config);
    for (i, v) in (0u32..).zip(wco) {
        interp.set_param(5221 + i, v).expect("G54");
    }
    interp
}

/// One random step, in mm.
#[derive(Debug, Clone)]
enum Step {
    Line {
        to: [f64; 3],
        rapid: bool,
    },
    /// `grow`: the end radius minus the start radius (a spiral within the interpreter's
    /// tolerance, beyond Grbl's).
    Arc {
        plane: u8,
        cw: bool,
        radius: f64,
        phase: f64,
        sweep: Sweep,
        dz: f64,
        grow: f64,
    },
}

#[derive(Debug, Clone, Copy)]
enum Sweep {
    /// Less than a turn (radians).
    Part(f64),
    /// Whole turns.
    Full(u32),
    /// More than one turn, not whole (radians).
    Multi(f64),
}

fn step() -> impl Strategy<Value = Step> {
    let line =
        (prop::array::uniform3(-300.0..300.0f64), any::<bool>()).prop_map(|(to, rapid)| Step::Line { to, rapid });
    let radius = prop_oneof![0.05..1.0f64, 1.0..100.0f64, 100.0..3000.0f64];
    let sweep = prop_oneof![
        (0.1..TAU - 0.01).prop_map(Sweep::Part),
        // Just short of a turn, and tiny: where rounding could flip Grbl's sweep.
        (TAU - 1e-3..TAU - 1e-9).prop_map(Sweep::Part),
        (1e-7..1e-3f64).prop_map(Sweep::Part),
        (1..3u32).prop_map(Sweep::Full),
        (TAU + 0.1..3.0 * TAU).prop_map(Sweep::Multi),
    ];
    let dz = prop_oneof![Just(0.0), -20.0..20.0f64];
    let grow = prop_oneof![3 => Just(0.0), 1 => -0.025..0.025f64];
    let arc = (0..3u8, any::<bool>(), radius, 0.0..TAU, sweep, dz, grow).prop_map(
        |(plane, cw, radius, phase, sweep, dz, grow)| Step::Arc { plane, cw, radius, phase, sweep, dz, grow },
    );
    prop_oneof![line, arc]
}

const PLANES: [Plane; 3] = [Plane::Xy, Plane::Zx, Plane::Yz];
/// Feed, mm/min: fast, so that the emulator's simulated time stays short.
const FEED_MM: f64 = 900_000.0;

/// The event of `step` from `p` (mm), in machine units of `k` mm.
fn event(step: &Step, p: Xyz, k: f64, line: u32) -> Event {
    match *step {
        Step::Line { to, rapid } => Event::Linear(LinearMove {
            line,
            start: p * (1.0 / k),
            end: Xyz::from(to) * (1.0 / k),
            rate: if rapid { Rate::Rapid } else { Rate::Feed(FEED_MM / k) },
            path: PathMode::ExactStop,
        }),
        Step::Arc { plane, cw, radius, phase, sweep, dz, grow } => {
            let plane = PLANES[usize::from(plane)];
            let (a, b, n) = plane.axes();
            let angle = match sweep {
                Sweep::Part(x) | Sweep::Multi(x) => x,
                Sweep::Full(turns) => f64::from(turns) * TAU,
            };
            let sign = if cw { -1.0 } else { 1.0 };
            let mut center = p;
            center.set_axis(a, p.axis(a) - radius * phase.cos());
            center.set_axis(b, p.axis(b) - radius * phase.sin());
            let mut end = p;
            if grow != 0.0 || !matches!(sweep, Sweep::Full(_)) {
                let r = radius + grow;
                end.set_axis(a, center.axis(a) + r * (phase + sign * angle).cos());
                end.set_axis(b, center.axis(b) + r * (phase + sign * angle).sin());
            }
            end.set_axis(n, p.axis(n) + dz);
            Event::Arc(ArcMove {
                line,
                start: p * (1.0 / k),
                end: end * (1.0 / k),
                center: center * (1.0 / k),
                plane,
                direction: if cw { ArcDirection::Clockwise } else { ArcDirection::CounterClockwise },
                angle,
                feed: FEED_MM / k,
                path: PathMode::ExactStop,
            })
        }
    }
}

/// The re-read events `got` (mm) against the emitted `event` (machine units of `k` mm).
fn same_geometry(event: &Event, got: &[Event], k: f64) {
    let near = |p: Xyz, q: Xyz| (p - q).max_abs() <= 0.002;
    match event {
        Event::Linear(m) => {
            if let [Event::Linear(g)] = got {
                assert!(near(g.end, m.end * k), "{g:?} for {m:?}");
                assert_eq!(matches!(g.rate, Rate::Rapid), matches!(m.rate, Rate::Rapid));
            } else {
                assert!(got.is_empty() && near(m.start * k, m.end * k), "{got:?} for {m:?}");
            }
        }
        Event::Arc(arc) => {
            let (a, b, _) = arc.plane.axes();
            let centre = arc.center * k;
            let in_plane = |v: Xyz| v.axis(a).hypot(v.axis(b));
            let radius = in_plane(arc.start * k - centre);
            // Along the arc: rounding the start, the end and the centre to 1 µm turns the
            // angle seen from the centre by up to 0.0007 + 0.0007 + 2 · 0.0007 mm.
            let (mut angle, mut tolerance) = (0.0, 0.003);
            for e in got {
                match e {
                    Event::Arc(g) => {
                        assert_eq!((g.plane, g.direction), (arc.plane, arc.direction), "{g:?} for {arc:?}");
                        let off = g.center - centre;
                        assert!(off.axis(a).abs() <= 0.002 && off.axis(b).abs() <= 0.002, "{g:?} for {arc:?}");
                        angle += g.angle;
                    }
                    // A piece shorter than 2 µm goes straight: the angle it turns about the centre.
                    Event::Linear(g) => {
                        let (u, v) = (g.start - centre, g.end - centre);
                        let cross = u.axis(a) * v.axis(b) - u.axis(b) * v.axis(a);
                        angle += cross.atan2(u.axis(a) * v.axis(a) + u.axis(b) * v.axis(b)).abs();
                        tolerance += 0.002;
                    }
                    other => panic!("{other:?}"),
                }
            }
            assert!((angle - arc.angle).abs() * radius <= tolerance, "swept {angle} for {arc:?}: {got:?}");
            let end = got.last().and_then(Event::end).unwrap_or(arc.start * k);
            assert!(near(end, arc.end * k), "{got:?} for {arc:?}");
        }
        _ => unreachable!("only moves are generated"),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn moves_and_arcs_reach_grbl_and_read_back_the_same(
        steps in prop::collection::vec(step(), 1..5),
        inch in any::<bool>(),
        wco in prop::array::uniform3(-500_000i32..500_000),
    ) {
        let k = if inch { 25.4 } else { 1.0 };
        let wco = wco.map(|v| f64::from(v) / 1000.0);
        let mut emitter = Emitter::new(Frame { mm_per_unit: k, wco, work_system: 1 }, Xyz::ZERO).expect("frame");
        let mut m = grbl(wco);
        let mut interp = reader(wco);
        let preamble = emitter.preamble();
        run(&mut m, &preamble);
        interp.run(&preamble.join("\n"), None, &mut Vec::new()).expect("preamble");
        let mut p = Xyz::ZERO;
        for (i, s) in steps.iter().enumerate() {
            let line = u32::try_from(i + 1).expect("few");
            let e = event(s, p, k, line);
            let lines = emitter.event(&e).expect("emitted");
            run(&mut m, &lines);
            let end = e.end().expect("a move") * k;
            let mpos = m.machine_position();
            for axis in 0..3 {
                prop_assert!((mpos[axis] - end.axis(axis)).abs() <= 0.001, "{mpos:?} for {e:?}: {lines:?}");
            }
            let mut got = Vec::new();
            interp.run(&lines.join("\n"), None, &mut got).expect("re-read");
            same_geometry(&e, &got, k);
            p = end;
        }
    }
}
