//! The manual's vision programs (examples 1–7, fixtures in `tests/programs/`) parse and run with
//! a recording handler that plays a simple camera; and the G-code M282 emits, executed here,
//! carries every commanded mark onto its observed position (SPEC §3's definition of correct).
#![expect(clippy::cast_possible_truncation, clippy::cast_sign_loss, reason = "test values are small and whole")]
#![expect(clippy::float_cmp, reason = "tests compare exact values")]

use vision_core::controller::modal_commands;
use vision_gcode::{
    Context, Event, HandlerError, Interpreter, InterpreterConfig, MCodeHandler, RunOutcome, Tool, UserMCode, Xyz,
};
use vision_math::{AlignmentChain, Model, Point2, Vector2};

/// Mach4's text for `commands`, as its bridge writes it.
fn mach4_text(commands: &[vision_core::MachineCommand]) -> Vec<String> {
    vision_mcode::lines(&vision_core::controller::Mach4, commands).expect("text")
}

/// Where the part really lies: nominal mark `n` (work frame) is at `part.apply(n)`.
fn rectangle_part() -> AlignmentChain {
    AlignmentChain {
        scale: Vector2::new(1.0004, 0.9997),
        center: Point2::new(3.0, 2.0),
        rotation_deg: 0.35,
        shift: Vector2::new(0.08, -0.05),
    }
}

fn similarity_part() -> AlignmentChain {
    AlignmentChain { scale: Vector2::new(0.9995, 0.9995), ..rectangle_part() }
}

/// One handler call as recorded.
#[derive(Debug, Clone, PartialEq)]
struct Call {
    line: u32,
    code: u32,
    words: Vec<(char, f64)>,
    comment: Option<String>,
    program: Xyz,
    machine: Xyz,
}

/// A camera that always finds the mark nearest the optical axis, and a vision module that does
/// what M280–M284 do with the interpreter: cancel, capture into #500.., fit and emit, bump and
/// write the camera tool offset, switch jobs.
struct FakeVision {
    part: AlignmentChain,
    marks: Vec<Point2<f64>>,
    model: Model,
    dots: Vec<(Point2<f64>, Point2<f64>)>,
    calls: Vec<Call>,
    jobs: Vec<u32>,
    emitted: Option<AlignmentChain>,
}

impl FakeVision {
    fn new(part: AlignmentChain, marks: &[(f64, f64)]) -> FakeVision {
        FakeVision {
            part,
            marks: marks.iter().map(|&(x, y)| Point2::new(x, y)).collect(),
            model: Model::Rectangle,
            dots: Vec::new(),
            calls: Vec::new(),
            jobs: Vec::new(),
            emitted: None,
        }
    }

    /// M281: the observed mark in the program frame (SPEC §2, with an alignment active: mapped
    /// back through it).
    fn capture(&mut self, ctx: &mut Context<'_>) -> Result<Point2<f64>, HandlerError> {
        let work = ctx.work_position().xy();
        let seen = self
            .marks
            .iter()
            .map(|n| self.part.apply(*n))
            .min_by(|a, b| (a - work).norm().total_cmp(&(b - work).norm()))
            .ok_or_else(|| HandlerError::Failed("NG / no mark".into()))?;
        let observed = match ctx.active_alignment() {
            Some(chain) => chain.inverse(seen).ok_or_else(|| HandlerError::Failed("singular alignment".into()))?,
            None => seen,
        };
        let commanded = ctx.program_position().xy();
        self.dots.push((commanded, observed));
        let slot = u32::try_from(self.dots.len().min(4)).unwrap_or(4);
        for base in [500, 500 + 8 * slot] {
            ctx.set_pound(base, observed.x)?;
            ctx.set_pound(base + 1, observed.y)?;
        }
        Ok(observed)
    }
}

impl MCodeHandler for FakeVision {
    fn call(&mut self, call: &UserMCode<'_>, ctx: &mut Context<'_>) -> Result<Vec<String>, HandlerError> {
        self.calls.push(Call {
            line: call.line(),
            code: call.code(),
            words: call.words().to_vec(),
            comment: call.comment().map(str::to_string),
            program: ctx.program_position(),
            machine: ctx.machine_position(),
        });
        match call.code() {
            280 => {
                self.dots.clear();
                self.model = if call.word('P') == Some(3.0) { Model::Similarity } else { Model::Rectangle };
                Ok(mach4_text(&[vision_core::MachineCommand::CancelAlignment]))
            }
            281 => {
                self.capture(ctx)?;
                Ok(Vec::new())
            }
            282 => {
                let (commanded, observed): (Vec<_>, Vec<_>) = self.dots.iter().copied().unzip();
                let fit = self.model.fit(&commanded, &observed).map_err(|e| HandlerError::Failed(e.to_string()))?;
                let chain = fit.transform.chain().ok_or_else(|| HandlerError::Failed("no chain".into()))?;
                self.emitted = Some(chain);
                let commands = modal_commands(&chain).map_err(|e| HandlerError::Failed(e.to_string()))?;
                Ok(mach4_text(&commands))
            }
            283 => {
                // The axis-detect bump, synchronously: move, look, move back.
                let start = ctx.program_position();
                ctx.execute("G91 G0 X0.1 Y0")?;
                assert!((ctx.program_position().x - start.x - 0.1).abs() < 1e-12, "execute is synchronous");
                ctx.execute("G0 X0 Y0.1")?;
                ctx.execute("G0 X-0.1 Y-0.1\nG90")?;
                ctx.dwell(0.25)?;
                if call.word('C').is_some() {
                    ctx.set_tool_offset(98, 1.5, -0.25)?;
                }
                Ok(Vec::new())
            }
            284 => {
                self.jobs.push(call.word('P').map_or(0, |p| p as u32));
                Ok(Vec::new())
            }
            other => Err(HandlerError::Failed(format!("M{other} is not a vision M-code"))),
        }
    }
}

fn machine() -> Interpreter {
    let mut interp = Interpreter::new(InterpreterConfig::default());
    interp.set_tool(98, Tool { offset: Xyz::new(2.0, -1.0, 0.0), outputs: None });
    interp
}

fn program(name: &str) -> String {
    let path = format!("{}/tests/programs/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn run(name: &str, vision: &mut FakeVision) -> (Interpreter, Vec<Event>) {
    let mut interp = machine();
    let mut events = Vec::new();
    let outcome = interp.run(&program(name), Some(vision), &mut events).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(matches!(outcome, RunOutcome::Ended { code: 30, .. }), "{name}: {outcome:?}");
    assert!(events.iter().all(|e| e.end().is_none_or(Xyz::is_finite)));
    (interp, events)
}

fn codes(vision: &FakeVision) -> Vec<u32> {
    vision.calls.iter().map(|c| c.code).collect()
}

#[test]
fn example1_calibration_walk_moves_synchronously_and_writes_the_camera_offset() {
    let mut vision = FakeVision::new(rectangle_part(), &[(0.0, 0.0)]);
    let (interp, events) = run("example1_calibration.nc", &mut vision);
    assert_eq!(codes(&vision), vec![283]);
    let call = &vision.calls[0];
    assert_eq!((call.line, call.words.clone()), (8, vec![('C', 1.0)]));
    assert_eq!(call.comment.as_deref(), Some(" walk sheet 1, solve K, write camera tool offset "));
    // The bump moves are events of the M283 line, in order, and end where they started.
    let bumps: Vec<&Event> = events.iter().filter(|e| e.line() == 8).collect();
    assert_eq!(bumps.len(), 4, "{bumps:?}");
    // The camera tool's offset (2, −1) was in effect from M6: the spindle started at 0.
    assert!((bumps[0].end().expect("a move") - Xyz::new(0.1, 0.0, 0.0)).norm() < 1e-12);
    assert_eq!(bumps[3], &Event::Dwell { line: 8, seconds: 0.25 });
    assert_eq!(interp.tool_offset(98), Some(Xyz::new(1.5, -0.25, 0.0)));
}

#[test]
fn example2_verify_walk_centre_reads_zero_after_the_fit() {
    let corners = [(-2.5, -4.0), (-2.5, 4.0), (2.5, 4.0), (2.5, -4.0), (0.0, 0.0)];
    let mut vision = FakeVision::new(rectangle_part(), &corners);
    let (interp, _) = run("example2_verify.nc", &mut vision);
    assert_eq!(codes(&vision), vec![280, 281, 281, 281, 281, 282, 281]);
    let commanded: Vec<Xyz> = vision.calls.iter().filter(|c| c.code == 281).map(|c| c.program).collect();
    assert_eq!(commanded[..4], [(-2.5, -4.0), (-2.5, 4.0), (2.5, 4.0), (2.5, -4.0)].map(|(x, y)| Xyz::new(x, y, 0.0)));
    // Dot 5 after M282: the camera is on the real centre mark, which reads ~0 in the program frame.
    // Exact data: only the emitted decimals' rounding (≤ 1e-7) remains.
    let (x, y) = (interp.param(500), interp.param(501));
    assert!(x.abs() < 1e-7 && y.abs() < 1e-7, "residual ({x}, {y})");
    let last = vision.calls.last().expect("calls");
    let real = rectangle_part().apply(Point2::origin());
    // Camera tool: the spindle is the optical axis minus the tool offset.
    assert!((last.machine - Xyz::new(real.x - 2.0, real.y + 1.0, 0.0)).norm() < 1e-7);
}

#[test]
fn example3_quick_calibration() {
    let mut vision = FakeVision::new(rectangle_part(), &[(0.0, 0.0)]);
    let (interp, _) = run("example3_quick_cal.nc", &mut vision);
    assert_eq!(vision.calls[0].words, vec![('Q', 0.5)]);
    assert_eq!(interp.tool_offset(98), Some(Xyz::new(2.0, -1.0, 0.0)), "Q does not write the offset");
}

#[test]
fn example4_and_5_fits_apply_and_are_cancelled() {
    for (name, part, marks, calls) in [
        (
            "example4_rectangle_fit.nc",
            rectangle_part(),
            vec![(0.0, 0.0), (6.0, 0.0), (6.0, 4.0), (0.0, 4.0)],
            vec![280, 281, 281, 281, 281, 282],
        ),
        (
            "example5_similarity_fit.nc",
            similarity_part(),
            vec![(0.0, 0.0), (8.0, 0.0), (4.0, 6.0)],
            vec![280, 281, 281, 281, 282],
        ),
    ] {
        let mut vision = FakeVision::new(part, &marks);
        let (interp, events) = run(name, &mut vision);
        assert_eq!(codes(&vision), calls, "{name}");
        assert!(vision.emitted.is_some());
        assert_eq!(interp.active_alignment(), None, "{name}: cancelled before M30");
        assert_eq!(interp.active_tool(), 1);
        assert!(events.iter().any(|e| matches!(e, Event::ToolChange { tool: 1, .. })));

        // The same program cut before its cancel line: M282's lines are in force, and every
        // nominal mark, commanded with the cutter (tool 1, no offset), lands on the part.
        let text = program(name);
        let cancel = mach4_text(&[vision_core::MachineCommand::CancelAlignment]);
        let cut = text.rfind(&format!("\n{}", cancel[0])).expect("a cancel line");
        let mut vision = FakeVision::new(part, &marks);
        let mut interp = machine();
        let outcome = interp.run(&text[..cut], Some(&mut vision), &mut Vec::new()).expect("runs");
        assert!(matches!(outcome, RunOutcome::Completed { .. }), "{name}: {outcome:?}");
        assert_eq!(interp.active_tool(), 1);
        let emitted = vision.emitted.expect("M282 emitted a chain");
        let active = interp.active_alignment().expect("M282's alignment is active");
        // The emitted lines carry fixed decimals (lengths 1e-7, degrees 1e-9, factors 1e-10).
        assert!((active.shift - emitted.shift).norm() <= 5e-8, "{name}: {active:?} vs {emitted:?}");
        assert!((active.center - emitted.center).norm() <= 5e-8, "{name}: {active:?} vs {emitted:?}");
        assert!((active.rotation_deg - emitted.rotation_deg).abs() <= 5e-10, "{name}: {active:?}");
        assert!((active.scale - emitted.scale).norm() <= 5e-11, "{name}: {active:?} vs {emitted:?}");
        for &(x, y) in &marks {
            interp.run(&format!("G0 X{x} Y{y}"), None, &mut Vec::new()).expect("moves");
            let real = part.apply(Point2::new(x, y));
            let m = interp.machine_position();
            assert!((m.xy() - real).norm() < 1e-6, "{name}: ({x}, {y}) went to {m:?}, the mark is at {real}");
        }
    }
}

#[test]
fn example6_pound_variables_feed_a_fixture_offset() {
    let mut vision = FakeVision::new(rectangle_part(), &[(10.0, 8.0)]);
    let (interp, _) = run("example6_pound_vars.nc", &mut vision);
    let seen = rectangle_part().apply(Point2::new(10.0, 8.0));
    assert_eq!((interp.param(500), interp.param(501)), (seen.x, seen.y));
    assert_eq!(interp.work_offset(2), Xyz::new(seen.x, seen.y, 0.0));
}

#[test]
fn example7_job_switch_and_an_aligned_capture() {
    let marks = [(0.0, 0.0), (10.0, 0.0), (10.0, 6.0), (0.0, 6.0), (5.0, 3.0)];
    let mut vision = FakeVision::new(rectangle_part(), &marks);
    let (interp, _) = run("example7_job_switch.nc", &mut vision);
    assert_eq!(codes(&vision), vec![284, 280, 281, 281, 281, 281, 282, 284, 281]);
    assert_eq!(vision.jobs, vec![1, 2]);
    // The final capture runs in the aligned frame: the part centre reads at its nominal place.
    assert!((interp.param(500) - 5.0).abs() < 1e-7 && (interp.param(501) - 3.0).abs() < 1e-7);
}

/// SPEC §3: "The emitted G-code, executed by the interpreter, must carry every commanded mark
/// onto its observed position to within the fit residual."
#[test]
fn m282_gcode_carries_every_commanded_mark_onto_its_observation() {
    let commanded = [Point2::new(0.0, 0.0), Point2::new(6.0, 0.0), Point2::new(6.0, 4.0), Point2::new(0.0, 4.0)];
    // Noisy observations: the fit is not exact, so the residual bound matters.
    let observed =
        [Point2::new(0.1, 0.05), Point2::new(6.0999, 0.1024), Point2::new(6.065, 4.1023), Point2::new(0.0651, 4.0499)];
    for model in [Model::Rectangle, Model::Similarity] {
        let fit = model.fit(&commanded, &observed).expect("fits");
        let lines = mach4_text(&modal_commands(&fit.transform.chain().expect("chain")).expect("finite"));
        for (unit_line, k) in [("G20", 1.0), ("G21", 25.4)] {
            let mut interp = machine();
            let mut text = format!("{unit_line} G90 T98 M6\n");
            for line in &lines {
                // The chain is in inches; in a G21 program the same lines in millimetres.
                text.push_str(&if k == 1.0 { line.clone() } else { scale_line(line, k) });
                text.push('\n');
            }
            interp.run(&text, None, &mut Vec::new()).expect("M282's lines run");
            for (n, o) in commanded.iter().zip(&observed) {
                interp.run(&format!("G0 X{} Y{}", n.x * k, n.y * k), None, &mut Vec::new()).expect("move");
                // The camera (tool 98) is where the program said, in the work frame.
                let w = interp.work_position();
                let err = ((w.x / k - o.x).powi(2) + (w.y / k - o.y).powi(2)).sqrt();
                // Within the residual, plus what the emitted decimals round away (≤ 1e-7 here).
                assert!(err <= fit.max_residual + 1e-7, "{model:?} {unit_line}: {err} > {}", fit.max_residual);
                let m = interp.machine_position();
                assert!((m.x - (w.x / k - 2.0)).abs() < 1e-9 && (m.y - (w.y / k + 1.0)).abs() < 1e-9);
            }
        }
    }
}

/// Multiplies the X/Y words of an M282 line by `k` (G52 and G68 lengths; not G51 factors or R).
fn scale_line(line: &str, k: f64) -> String {
    if line.starts_with("G51") || line.starts_with("G69") {
        return line.to_string();
    }
    line.split(' ')
        .map(|w| match w.split_at(1) {
            ("X" | "Y", v) => format!("{}{}", &w[..1], v.parse::<f64>().expect("number") * k),
            _ => w.to_string(),
        })
        .collect::<Vec<_>>()
        .join(" ")
}
