//! The LinuxCNC dialect of the session, on a LinuxCNC-like host: a fake that applies LinuxCNC's
//! canon (`machine = g5x + R(rot)·(p + g92) + tool`) for `G10 L2 P0 R`, `G52` and `G0`, and
//! moves the simulated head there, so the real module with the simulated camera runs as it
//! would under LinuxCNC.
#![expect(clippy::float_cmp, reason = "tests compare exact values")]

use std::collections::BTreeMap;

use vision_core::{DriverRegistry, MachineCommand, Timestamp, VisionModule};
use vision_driver_sim::{Fixture, Sim, SimMachine};
use vision_host::{linuxcnc, testkit, Controller, HostError, Machine, MachineError, MachineErrorKind, Session};
use vision_math::{LengthUnit, Matrix2, Point2, Vector2};

/// Rotation by `deg` degrees counter-clockwise.
fn rot(deg: f64) -> Matrix2<f64> {
    let (s, c) = deg.to_radians().sin_cos();
    Matrix2::new(c, -s, s, c)
}

/// LinuxCNC as the session sees it through remap.py, inches, G54 active.
struct FakeLinuxCnc {
    /// Moves the simulated head (tool 1 loaded, no offsets: `G53` puts the spindle there).
    machine: SimMachine,
    /// The G54 origin, machine coordinates.
    g5x: Vector2<f64>,
    /// The G54 rotation, degrees counter-clockwise.
    rotation_deg: f64,
    /// The G92/G52 offset.
    g92: Vector2<f64>,
    /// The tool table as LinuxCNC holds it (added to the programmed point).
    tools: BTreeMap<u32, Vector2<f64>>,
    tool: u32,
    /// The spindle, machine coordinates.
    spindle: Vector2<f64>,
    /// The spindle's Z, machine coordinates (program Z: no Z offsets here).
    z: f64,
    incremental: bool,
    /// Distance modes saved by M70, newest last.
    saved: Vec<bool>,
    /// Numbered parameters (0 when never written, as in LinuxCNC).
    params: BTreeMap<u32, f64>,
    /// Every line run, in order.
    lines: Vec<String>,
    messages: Vec<String>,
    /// The true vector from the spindle to the point the camera images at its calibrated centre.
    camera_truth: Vector2<f64>,
}

impl FakeLinuxCnc {
    /// The machine of `sim`, G54 at the world's work offset rotated by `rotation_deg`, the
    /// camera tool loaded with its true offset in LinuxCNC's sign.
    fn new(sim: &Sim, rotation_deg: f64, camera_offset: Vector2<f64>) -> FakeLinuxCnc {
        let world = sim.world();
        let machine = SimMachine::new(sim).expect("the built-in machine");
        let camera = world.machine.camera_tool;
        let g5x = Vector2::new(world.machine.work_offset[0], world.machine.work_offset[1]);
        let spindle = Vector2::new(world.machine.start[0], world.machine.start[1]);
        let mut host = FakeLinuxCnc {
            machine,
            g5x,
            rotation_deg,
            g92: Vector2::zeros(),
            tools: BTreeMap::from([(camera, -camera_offset), (1, Vector2::zeros())]),
            tool: camera,
            spindle,
            z: world.machine.start[2],
            incremental: false,
            saved: Vec::new(),
            params: BTreeMap::new(),
            lines: Vec::new(),
            messages: Vec::new(),
            camera_truth: camera_offset,
        };
        host.go(spindle);
        host
    }

    fn tool_vector(&self) -> Vector2<f64> {
        self.tools.get(&self.tool).copied().unwrap_or_else(Vector2::zeros)
    }

    /// LinuxCNC's canon: where commanding `p` puts the spindle.
    fn spindle_for(&self, p: Point2<f64>) -> Vector2<f64> {
        self.g5x + rot(self.rotation_deg) * (p.coords + self.g92) + self.tool_vector()
    }

    /// The program point the spindle is at (frame changes re-derive it; they do not move).
    fn program(&self) -> Point2<f64> {
        Point2::from(rot(-self.rotation_deg) * (self.spindle - self.g5x - self.tool_vector()) - self.g92)
    }

    /// Moves the spindle to machine point `m`.
    fn go(&mut self, m: Vector2<f64>) {
        let mut ignore = |_: &vision_gcode::Event| {};
        self.machine.context(&mut ignore).execute(&format!("G53 G0 X{} Y{}", m.x, m.y)).expect("a G53 move");
        self.spindle = m;
    }

    /// Where the point the camera images at its calibrated centre is, machine coordinates.
    fn optical_axis(&self) -> Point2<f64> {
        Point2::from(self.spindle + self.camera_truth)
    }
}

fn unsupported(line: &str) -> MachineError {
    MachineError::new(MachineErrorKind::RefusedGcode, format!("the fake LinuxCNC does not run {line:?}"))
}

impl Machine for FakeLinuxCnc {
    fn gcode(&self, command: &MachineCommand) -> Result<Vec<String>, MachineError> {
        Ok(vision_mcode::gcode(self.controller(), command)?)
    }
    fn execute(&mut self, line: &str) -> Result<(), MachineError> {
        let mut g = Vec::new();
        let mut words = BTreeMap::new();
        for token in line.split_whitespace() {
            let mut chars = token.chars();
            let letter = chars.next().ok_or_else(|| unsupported(line))?.to_ascii_uppercase();
            let value: f64 = chars.as_str().parse().map_err(|_| unsupported(line))?;
            if letter == 'G' {
                g.push(value);
            } else {
                words.insert(letter, value);
            }
        }
        let word = |c: char| words.get(&c).copied();
        if g.contains(&90.0) {
            self.incremental = false;
        }
        if g.contains(&91.0) {
            self.incremental = true;
        }
        let has = |c: f64| g.contains(&c);
        if has(10.0) {
            if word('L') != Some(2.0) || word('P') != Some(0.0) || word('X').is_some() || word('Y').is_some() {
                return Err(unsupported(line));
            }
            if let Some(r) = word('R') {
                self.rotation_deg = r;
            }
        } else if has(52.0) {
            self.g92 = Vector2::new(word('X').unwrap_or(self.g92.x), word('Y').unwrap_or(self.g92.y));
        } else if has(0.0) {
            if let Some(z) = word('Z') {
                self.z = if self.incremental { self.z + z } else { z };
                let mut ignore = |_: &vision_gcode::Event| {};
                let line = format!("G53 G0 Z{}", self.z);
                self.machine.context(&mut ignore).execute(&line).expect("a G53 Z move");
            }
            let now = self.program();
            let target = if self.incremental {
                Point2::new(now.x + word('X').unwrap_or(0.0), now.y + word('Y').unwrap_or(0.0))
            } else {
                Point2::new(word('X').unwrap_or(now.x), word('Y').unwrap_or(now.y))
            };
            let m = self.spindle_for(target);
            self.go(m);
        } else if !(has(4.0) || g.iter().all(|c| *c == 90.0 || *c == 91.0)) || g.is_empty() {
            return Err(unsupported(line));
        }
        self.lines.push(line.to_string());
        Ok(())
    }
    fn save_modal_state(&mut self) -> Result<(), MachineError> {
        self.saved.push(self.incremental);
        Ok(())
    }
    fn restore_modal_state(&mut self) -> Result<(), MachineError> {
        self.incremental = self.saved.pop().ok_or_else(|| unsupported("M72 without M70"))?;
        Ok(())
    }
    fn pound(&self, index: u32) -> Result<f64, MachineError> {
        Ok(self.params.get(&index).copied().unwrap_or(0.0))
    }
    fn set_pound(&mut self, index: u32, value: f64) -> Result<(), MachineError> {
        self.params.insert(index, value);
        Ok(())
    }
    fn active_tool(&self) -> Result<u32, MachineError> {
        Ok(self.tool)
    }
    fn tool_offset(&self, tool: u32) -> Result<Vector2<f64>, MachineError> {
        self.tools
            .get(&tool)
            .copied()
            .ok_or_else(|| MachineError::new(MachineErrorKind::UnknownTool, format!("no tool {tool}")))
    }
    fn set_tool_offset(&mut self, tool: u32, offset: Vector2<f64>) -> Result<(), MachineError> {
        self.tools.insert(tool, offset);
        Ok(())
    }
    fn program_position(&self) -> Result<Point2<f64>, MachineError> {
        Ok(self.program())
    }
    fn units(&self) -> Result<LengthUnit, MachineError> {
        Ok(LengthUnit::Inch)
    }
    fn dwell(&mut self, _seconds: f64) -> Result<(), MachineError> {
        Ok(())
    }
    fn message(&mut self, text: &str) {
        self.messages.push(text.to_string());
    }
    fn now(&self) -> Timestamp {
        Timestamp::from_unix(1_800_000_000, 0)
    }
    fn controller(&self) -> &'static dyn Controller {
        &vision_host::controller::LinuxCnc
    }
    fn xy_rotation_deg(&self) -> Result<f64, MachineError> {
        Ok(self.rotation_deg)
    }
    fn g92_offset(&self) -> Result<Vector2<f64>, MachineError> {
        Ok(self.g92)
    }
}

/// Example 4's marks: the corners of a 6 × 4 in part.
const MARKS: [[f64; 2]; 4] = [[0.0, 0.0], [6.0, 0.0], [6.0, 4.0], [0.0, 4.0]];

/// A rig: the simulated world with only a 6 × 4 part on it, placed in the G54 frame rotated by
/// `base_deg`, then turned `part_deg` about its centre, shifted by `shift` and scaled by
/// `scale` in that frame; a session with a perfect calibration and VisionFitMaxScaleDev
/// `gate_pct`; the fake LinuxCNC with G54 rotated by `base_deg`.
fn rig(base_deg: f64, part_deg: f64, shift: Vector2<f64>, scale: f64, gate_pct: f64) -> (Session, FakeLinuxCnc) {
    let sim = testkit::sim();
    let c = Vector2::new(3.0, 2.0);
    // Work = R(θ₀)·(R(α)·S·(n − c) + c + s) = R(θ₀ + α)·S·(n − c) + c + (R(θ₀)·(c + s) − c).
    let work_shift = rot(base_deg) * (c + shift) - c;
    let part = Fixture {
        name: "part".into(),
        sheet: None,
        marks: MARKS.to_vec(),
        diameter: Some(0.25),
        shift: [work_shift.x, work_shift.y],
        rotation_deg: base_deg + part_deg,
        scale: [scale, scale],
        center: Some([c.x, c.y]),
        present: true,
    };
    sim.set_fixtures(vec![part]).expect("a valid part");
    let mut params = testkit::sim_params(&sim);
    params.set("VisionFitMaxScaleDev", gate_pct).expect("a percentage");
    let centre = Vector2::new(params.px_center_offset_x(), params.px_center_offset_y());
    let camera = sim.true_camera_offset(centre, LengthUnit::Inch);
    let mut registry = DriverRegistry::new();
    sim.register(&mut registry);
    let module = VisionModule::from_registry(params, &registry).expect("the simulated camera");
    (Session::new(module), FakeLinuxCnc::new(&sim, base_deg, camera))
}

/// Example 4 for LinuxCNC: M280, a capture over each nominal corner, M282.
fn align(session: &mut Session, host: &mut FakeLinuxCnc) -> Result<(), HostError> {
    session.mcode(host, 280, &[])?;
    for [x, y] in MARKS {
        host.execute(&format!("G0 X{x} Y{y}"))?;
        session.mcode(host, 281, &[])?;
    }
    session.mcode(host, 282, &[]).map(|_| ())
}

/// The largest distance between the camera's optical axis commanded onto each nominal corner
/// and the corner's true position, inches.
fn worst_landing(host: &mut FakeLinuxCnc) -> f64 {
    let truth = host.machine.sim().marks();
    MARKS
        .iter()
        .zip(&truth)
        .map(|([x, y], mark)| {
            host.execute(&format!("G0 X{x} Y{y}")).expect("a move");
            (host.optical_axis() - mark.position).norm()
        })
        .fold(0.0, f64::max)
}

#[test]
fn a_shifted_and_rotated_part_lands_after_m282_also_on_an_operators_rotation() {
    for base in [0.0, 10.0] {
        let (mut session, mut host) = rig(base, 0.4, Vector2::new(0.06, -0.04), 1.0, 2.0);
        let before = worst_landing(&mut host);
        assert!(before > 0.03, "the part must be off before M282 (θ₀ {base}°): {before}");
        align(&mut session, &mut host).expect("aligned");
        // G10 L2 P0 R{θ₀ + θ}, G52: no G68, no G51.
        let emitted: Vec<&String> =
            host.lines.iter().filter(|l| l.starts_with("G10") || l.starts_with("G52")).collect();
        assert!(host.lines.iter().all(|l| !l.contains("G68") && !l.contains("G51")), "{:?}", host.lines);
        // These marks are read ~30 px off the image centre: each capture re-centres over its
        // mark (G91 G0, G90) and puts the camera back on the program's point.
        let m280 = host.lines.iter().position(|l| l == "G52 X0 Y0").expect("M280's cancel");
        for [x, y] in MARKS {
            let at = m280
                + host.lines[m280..].iter().position(|l| *l == format!("G0 X{x} Y{y}")).expect("the program's move");
            assert!(host.lines[at + 1].starts_with("G91 G0 X"), "{:?}", &host.lines[at..]);
            let back = format!("G90 G0 X{x:.7} Y{y:.7}");
            assert!(host.lines[at + 2..].iter().take(4).any(|l| *l == back), "{back}: {:?}", &host.lines[at..]);
        }
        assert!(emitted.len() >= 4, "{emitted:?}");
        assert!((host.rotation_deg - (base + 0.4)).abs() < 0.01, "rotation {}", host.rotation_deg);
        assert_eq!(host.params.get(&linuxcnc::ALIGNMENT_ACTIVE_PARAM), Some(&1.0));
        assert_eq!(host.params.get(&linuxcnc::BASE_ROTATION_PARAM), Some(&base));
        let worst = worst_landing(&mut host);
        assert!(worst < 0.0005, "θ₀ {base}°: a corner lands {worst} in off");
        // A second M282 from the same captures replaces the alignment, never compounds it.
        let (rotation, g92) = (host.rotation_deg, host.g92);
        session.mcode(&mut host, 282, &[]).expect("aligned again");
        assert!((host.rotation_deg - rotation).abs() < 1e-9 && (host.g92 - g92).norm() < 1e-9);
        let said = host.messages.last().cloned().unwrap_or_default();
        assert!(said.starts_with("M282: alignment applied without scale"), "{said}");

        // M280 puts θ₀ and G52 back, also from a fresh session (LinuxCNC restarted).
        let (mut fresh, _) = rig(base, 0.4, Vector2::new(0.06, -0.04), 1.0, 2.0);
        fresh.mcode(&mut host, 280, &[]).expect("cancelled");
        assert_eq!(host.rotation_deg, base);
        assert_eq!(host.g92, Vector2::zeros());
        assert_eq!(host.params.get(&linuxcnc::ALIGNMENT_ACTIVE_PARAM), Some(&0.0));
    }
}

#[test]
fn a_capture_under_an_active_alignment_reads_in_the_program_frame() {
    // After M282 the program frame is the part's: a capture over a corner reads that corner
    // (within the camera's noise, 0.1 px ≈ 0.0002 in per coordinate, and the fit's), on an
    // operator's rotation as without one.
    for base in [0.0, 10.0] {
        let (mut session, mut host) = rig(base, 0.4, Vector2::new(0.06, -0.04), 1.0, 2.0);
        align(&mut session, &mut host).expect("aligned");
        for [x, y] in MARKS {
            host.execute(&format!("G0 X{x} Y{y}")).expect("a move");
            let observed = match session.mcode(&mut host, 281, &[]).expect("a capture") {
                vision_mcode::Outcome::Capture(reply) => reply.report.observed,
                other => panic!("M281 captures: {other:?}"),
            };
            let miss = (observed - Point2::new(x, y)).norm();
            assert!(miss < 0.001, "θ₀ {base}°: corner ({x}, {y}) reads {miss} in off");
        }
    }
}

/// M281 run stepwise (as the LinuxCNC remap runs it, waiting for the machine between the steps)
/// is M281: the same moves, the same capture, the same report.
#[test]
fn m281_stepwise_is_m281() {
    let (mut one_shot, mut host_a) = rig(0.0, 0.4, Vector2::new(0.06, -0.04), 1.0, 2.0);
    let (mut stepwise, mut host_b) = rig(0.0, 0.4, Vector2::new(0.06, -0.04), 1.0, 2.0);
    one_shot.mcode(&mut host_a, 280, &[]).expect("begun");
    stepwise.mcode(&mut host_b, 280, &[]).expect("begun");
    for [x, y] in MARKS {
        let line = format!("G0 X{x} Y{y}");
        host_a.execute(&line).expect("a move");
        host_b.execute(&line).expect("a move");
        let (from_a, from_b) = (host_a.lines.len(), host_b.lines.len());
        one_shot.mcode(&mut host_a, 281, &[]).expect("a capture");
        let mut steps = 1;
        let mut moving = stepwise.capture_begin(&mut host_b, &[]).expect("a first step");
        while moving {
            moving = stepwise.capture_next(&mut host_b).expect("a next step");
            steps += 1;
        }
        assert!(steps >= 2, "({x}, {y}) is read off centre: M281 must re-centre");
        assert_eq!(host_a.lines[from_a..], host_b.lines[from_b..]);
        assert_eq!(host_a.messages.last(), host_b.messages.last());
    }
    let (a, b) = (one_shot.mcode(&mut host_a, 282, &[]), stepwise.mcode(&mut host_b, 282, &[]));
    assert_eq!(a.expect("aligned").gcode(), b.expect("aligned").gcode());
    // A step out of order is refused in M281's words.
    let e = stepwise.capture_next(&mut host_b).expect_err("no capture in progress");
    assert_eq!(e.to_string(), "M281: no re-centring is in progress; M281 starts one");
}

#[test]
fn a_part_printed_large_is_refused_under_a_small_gate_and_applied_rigidly_under_a_wide_one() {
    let (mut session, mut host) = rig(10.0, 0.4, Vector2::new(0.06, -0.04), 1.001, 0.05);
    let e = align(&mut session, &mut host).expect_err("0.1 % is beyond a 0.05 % gate");
    assert!(e.to_string().starts_with("LinuxCNC cannot scale"), "{e}");
    // Nothing changed: M280's cancel is all that ran.
    assert_eq!(host.rotation_deg, 10.0);
    assert_eq!(host.g92, Vector2::zeros());
    assert_eq!(host.params.get(&linuxcnc::ALIGNMENT_ACTIVE_PARAM), Some(&0.0));
    assert_eq!(host.lines.iter().filter(|l| l.starts_with("G10")).count(), 1, "{:?}", host.lines);

    let (mut session, mut host) = rig(10.0, 0.4, Vector2::new(0.06, -0.04), 1.001, 2.0);
    align(&mut session, &mut host).expect("within a 2 % gate");
    let said = host.messages.last().cloned().unwrap_or_default();
    assert!(said.contains("LinuxCNC cannot scale") && said.contains("ignored"), "{said}");
    // The rigid part: the corners miss by the ignored 0.1 % of their distance from the centre
    // (3.6 in), not more; the centre lands.
    let worst = worst_landing(&mut host);
    assert!((0.002..0.0045).contains(&worst), "a corner lands {worst} in off");
    host.execute("G0 X3 Y2").expect("a move");
    let truth = {
        let c = Vector2::new(3.0, 2.0);
        let work_shift = rot(10.0) * (c + Vector2::new(0.06, -0.04)) - c;
        Point2::from(c + work_shift + host.g5x)
    };
    assert!((host.optical_axis() - truth).norm() < 0.0005, "the centre lands {}", (host.optical_axis() - truth).norm());
}

/// A rig for M283: the built-in world (calibration sheet 1 on it) with the sheet turned by the
/// operator's `base_deg` with the G54 rotation, an uncalibrated session, and the camera tool's
/// table offset off the truth by `table_error`; the camera is over the sheet's first dot.
fn calibration_rig(base_deg: f64, table_error: Vector2<f64>) -> (Session, FakeLinuxCnc) {
    let sim = testkit::sim();
    let mut fixtures = sim.world().fixtures;
    for f in &mut fixtures {
        f.rotation_deg += base_deg;
    }
    sim.set_fixtures(fixtures).expect("the same fixtures, turned");
    let params = testkit::uncalibrated_params(&sim);
    let truth = sim.true_camera_offset(Vector2::zeros(), LengthUnit::Inch);
    let mut registry = DriverRegistry::new();
    sim.register(&mut registry);
    let module = VisionModule::from_registry(params, &registry).expect("the simulated camera");
    let mut host = FakeLinuxCnc::new(&sim, base_deg, truth);
    host.tools.insert(sim.world().machine.camera_tool, -(truth + table_error));
    let dot = vision_core::cal_sheet(1).expect("sheet 1").dots(LengthUnit::Inch)[0];
    host.execute(&format!("G0 X{} Y{}", dot.x, dot.y)).expect("over the first dot");
    (Session::new(module), host)
}

/// The stepwise walk as m283.ngc drives it: next target, `G0` to its height (the walk starts
/// at Z 0 here) and then its X/Y, capture; then finish.
fn walk_stepwise(
    session: &mut Session,
    host: &mut FakeLinuxCnc,
    words: &[(char, f64)],
) -> Result<vision_mcode::Outcome, HostError> {
    session.walk_begin(host, words)?;
    let mut captures = 0;
    while let Some(t) = session.walk_next(host)? {
        host.execute(&format!("G0 Z{}", t.lift))?;
        host.execute(&format!("G0 X{} Y{}", t.at.x, t.at.y))?;
        session.walk_capture(host)?;
        captures += 1;
        assert!(captures < 200, "the walk does not end");
    }
    session.walk_finish(host)
}

fn calibration(outcome: &vision_mcode::Outcome) -> &vision_core::CalReport {
    match outcome {
        vision_mcode::Outcome::Calibrate(reply) => &reply.report,
        other => panic!("M283 calibrates: {other:?}"),
    }
}

/// The camera tool's offset as the module sees it (LinuxCNC's table value, negated).
fn camera_offset(session: &Session, host: &FakeLinuxCnc) -> Vector2<f64> {
    let tool = session.module().params().camera_tool().unwrap_or(0);
    -host.tools[&tool]
}

#[test]
fn the_stepwise_walk_solves_and_commits_as_the_one_shot_m283() {
    let error = Vector2::new(0.04, -0.03);
    for (words, base) in [(vec![('P', 1.0)], 0.0), (vec![('P', 1.0)], 10.0), (vec![('Q', 0.5)], 10.0)] {
        let (mut one, mut one_host) = calibration_rig(base, error);
        let want = one.mcode(&mut one_host, 283, &words).expect("the one-shot M283");
        let (mut step, mut step_host) = calibration_rig(base, error);
        let got = walk_stepwise(&mut step, &mut step_host, &words).expect("the stepwise M283");
        let (want, got) = (calibration(&want), calibration(&got));
        // The same readings, taken where the moves put the camera: the one-shot walk's relative
        // moves round to 7 decimals, a stepwise walk moves to the exact point: K agrees to ~1e-12.
        let (k1, k2) = match (want, got) {
            (vision_core::CalReport::Sheet(a), vision_core::CalReport::Sheet(b)) => {
                assert_eq!(a.triggers, b.triggers);
                // The calibration lift ran stepwise too (Z first, then X/Y): the same centre.
                assert!(a.centre.measured && b.centre.measured, "{:?}\n{:?}", a.centre, b.centre);
                assert!((a.centre.offset_px - b.centre.offset_px).norm() < 1e-6, "{:?}\n{:?}", a.centre, b.centre);
                assert_eq!(a.verify.len(), b.verify.len());
                assert!((a.offset_written - b.offset_written).norm() < 1e-9, "{a:?}\n{b:?}");
                assert!((a.verify_rms - b.verify_rms).abs() < 1e-9, "{a:?}\n{b:?}");
                assert!((a.sheet_rotation_deg - b.sheet_rotation_deg).abs() < 1e-9);
                (a.k, b.k)
            }
            (vision_core::CalReport::Quick(a), vision_core::CalReport::Quick(b)) => {
                assert_eq!(a.axis.remap, b.axis.remap);
                assert!((a.size_error - b.size_error).abs() < 1e-9);
                (a.k, b.k)
            }
            _ => panic!("different modes: {want:?}\n{got:?}"),
        };
        assert!((k1 - k2).norm() / k1.norm() < 1e-9, "K {k1} vs {k2}");
        assert_eq!(want.date(), got.date());
        // Both committed: K in the module, the offset in the table (the sheet walk only).
        assert_eq!(one.module().params().cal_k(), k1);
        assert_eq!(step.module().params().cal_k(), k2);
        assert!((camera_offset(&one, &one_host) - camera_offset(&step, &step_host)).norm() < 1e-9);
        let said = step_host.messages.last().cloned().unwrap_or_default();
        assert_eq!(said, "M283: calibration done and saved");
    }
}

#[test]
fn a_sheet_walk_on_an_operators_rotation_writes_k_and_the_offset_along_the_machine_axes() {
    for base in [0.0, 10.0] {
        let (mut session, mut host) = calibration_rig(base, Vector2::new(0.04, -0.03));
        walk_stepwise(&mut session, &mut host, &[('P', 1.0)]).expect("calibrated");
        let sim = host.machine.sim().clone();
        let offset = camera_offset(&session, &host);
        let e = sim.calibration_error(session.module().params(), offset, LengthUnit::Inch);
        assert!(e.remap_matches, "θ₀ {base}°: {e:?}");
        assert!(e.k_relative < 0.002, "θ₀ {base}°: {e:?}");
        assert!(e.offset < 0.0005, "θ₀ {base}°: {e:?}");
    }
}

#[test]
fn an_ng_capture_stops_the_walk_and_writes_nothing() {
    let (mut session, mut host) = calibration_rig(0.0, Vector2::new(0.04, -0.03));
    host.execute("G0 X30 Y30").expect("off the sheet");
    let before = (session.module().params().cal_k(), host.tools.clone());
    session.walk_begin(&mut host, &[('P', 1.0)]).expect("begun");
    let p = session.walk_next(&mut host).expect("a point").expect("the first capture").at;
    host.execute(&format!("G0 X{} Y{}", p.x, p.y)).expect("a move");
    let e = session.walk_capture(&mut host).expect_err("no mark out there");
    assert!(e.to_string().contains("lost the mark"), "{e}");
    assert_eq!(session.module().param("VisionLastStatus"), Ok(vision_core::ParamValue::Text(e.to_string())));
    assert_eq!((session.module().params().cal_k(), host.tools.clone()), before);
    // The walk is over: the next step says so.
    let e = session.walk_next(&mut host).expect_err("no walk");
    assert!(e.to_string().contains("no M283 walk is in progress"), "{e}");
}

#[test]
fn steps_out_of_order_are_refused_and_keep_the_walk() {
    let (mut session, mut host) = calibration_rig(0.0, Vector2::zeros());
    let e = session.walk_capture(&mut host).expect_err("no walk yet");
    assert!(e.to_string().contains("no M283 walk is in progress"), "{e}");
    session.walk_begin(&mut host, &[('Q', 0.5)]).expect("begun");
    let e = session.walk_capture(&mut host).expect_err("no point asked for");
    assert!(e.to_string().contains("no capture is pending"), "{e}");
    let e = session.walk_finish(&mut host).expect_err("nothing captured");
    assert!(e.to_string().contains("the walk is not done"), "{e}");
    // Still the same walk: it runs to the end from here.
    while let Some(t) = session.walk_next(&mut host).expect("a point") {
        host.execute(&format!("G0 Z{}", t.lift)).expect("a move");
        host.execute(&format!("G0 X{} Y{}", t.at.x, t.at.y)).expect("a move");
        session.walk_capture(&mut host).expect("a capture");
    }
    session.walk_finish(&mut host).expect("calibrated");
    // M283's own refusals come at the start, before anything moves.
    let e = session.walk_begin(&mut host, &[('P', 9.0)]).expect_err("no sheet 9");
    assert!(e.to_string().contains('9'), "{e}");
    // LinuxCNC writes the manual's M283 C1 as P1 (C is an axis word there): C names P, and P
    // is a sheet number, alone.
    let e = session.walk_begin(&mut host, &[('C', 1.0)]).expect_err("C on LinuxCNC");
    assert_eq!(e.to_string(), "M283 C1: on LinuxCNC the sheet number is P: write M283 P1 (C is an axis word)");
    let e = session.walk_begin(&mut host, &[('P', 1.5)]).expect_err("no sheet number");
    assert_eq!(e.to_string(), "M283 P1.5 is invalid: P is a calibration sheet number (P1)");
    let e = session.walk_begin(&mut host, &[('P', 1.0), ('Q', 0.5)]).expect_err("both");
    assert!(e.to_string().starts_with("M283 takes one of Qd"), "{e}");
}

#[test]
fn m283_is_refused_while_an_alignment_is_active_and_the_refusal_names_m280() {
    let (mut session, mut host) = rig(10.0, 0.4, Vector2::new(0.06, -0.04), 1.0, 2.0);
    align(&mut session, &mut host).expect("aligned");
    // A fresh session (LinuxCNC restarted) still sees the alignment, from the host.
    let (mut fresh, _) = rig(10.0, 0.4, Vector2::new(0.06, -0.04), 1.0, 2.0);
    let e = fresh.walk_begin(&mut host, &[('Q', 0.5)]).expect_err("aligned");
    assert!(e.to_string().contains("M280"), "{e}");
    fresh.mcode(&mut host, 280, &[]).expect("cancelled");
    fresh.walk_begin(&mut host, &[('Q', 0.5)]).expect("no alignment now");
}

/// A base rotation of 1e308 (#3991 while aligned, or the G5x rotation) is refused as out of
/// range, never written back as a 309-digit `G10 L2 P0 R…`.
#[test]
fn a_base_rotation_past_the_bound_is_refused_and_writes_no_line() {
    let (mut session, mut host) = rig(0.0, 0.4, Vector2::new(0.06, -0.04), 1.0, 2.0);
    align(&mut session, &mut host).expect("aligned");
    host.params.insert(linuxcnc::BASE_ROTATION_PARAM, 1e308);
    let ran = host.lines.len();
    let e = session.mcode(&mut host, 280, &[]).expect_err("θ₀ of 1e308");
    assert!(e.to_string().contains("#3991") && e.to_string().contains("1e308"), "{e}");
    assert!(e.to_string().len() < 400, "{e}");
    assert_eq!(host.lines.len(), ran, "no line ran: {:?}", &host.lines[ran..]);
    // Not aligned: the G5x rotation itself.
    let (mut session, mut host) = rig(0.0, 0.4, Vector2::new(0.06, -0.04), 1.0, 2.0);
    host.rotation_deg = -1e308;
    let e = session.mcode(&mut host, 280, &[]).expect_err("G5x rotation of -1e308");
    assert!(e.to_string().contains("the G5x rotation is -1e308"), "{e}");
}
