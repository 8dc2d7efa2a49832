//! Tiny in-test fakes: a machine that writes Mach4's text for the module's commands and tracks
//! position under `G0/G1 G90/G91 G20/G21 X Y` and M282's modal lines, and a camera that makes native pixels from its own optics model (mount
//! rotation, mirror, pixel pitch, image centre), written from the physics and independently of
//! `vision_math::PixelChain`. The world (marks, spindle, camera) is kept in inches.

use std::collections::{BTreeMap, VecDeque};
use std::sync::{Arc, Mutex, MutexGuard};

use vision_math::chain::{fixed, ANGLE_DECIMALS, POSITION_DECIMALS, SCALE_DECIMALS};
use vision_math::{AlignmentChain, LengthUnit, Matrix2, Point2, Remap, Vector2};

use crate::command::MachineCommand;
use crate::controller::{Controller, Mach4};
use crate::driver::{CameraDriver, Capabilities, DriverError, DriverErrorKind, ImageRequest, Judgment, Reading};
use crate::machine::{Machine, MachineError, MachineErrorKind, Timestamp};
use crate::module::VisionModule;
use crate::params::Params;

/// The fake camera's optics. Sensor pixel `(u, v)` counted from the pixel the optical axis falls
/// on sees the table at `u·pitch.x·ex + v·pitch.y·ey` from the optical axis, where `ex` is the
/// sensor's x axis on the table (`rotation_deg` counter-clockwise from +X) and `ey` is `ex` turned
/// 90° counter-clockwise, or clockwise for a mirrored image (rows counted downwards).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Optics {
    /// Mount rotation: the sensor x axis on the table, degrees counter-clockwise from +X.
    pub rotation_deg: f64,
    /// The image is mirrored (sensor y is `ex` turned clockwise).
    pub mirrored: bool,
    /// Table length one pixel spans along sensor x and y, inches.
    pub pitch_in: Vector2<f64>,
    /// The pixel the optical axis falls on.
    pub centre_px: Vector2<f64>,
}

impl Optics {
    /// 0.00203 in square pixels, the optical axis at the centre of a 1776 px image.
    pub(crate) fn square(rotation_deg: f64, mirrored: bool) -> Optics {
        Optics {
            rotation_deg,
            mirrored,
            pitch_in: Vector2::new(0.00203, 0.00203),
            centre_px: Vector2::new(888.0, 888.0),
        }
    }

    /// The sensor's x and y axes on the table (unit vectors).
    fn axes(&self) -> (Vector2<f64>, Vector2<f64>) {
        let (s, c) = self.rotation_deg.to_radians().sin_cos();
        let ex = Vector2::new(c, s);
        let ey = if self.mirrored { Vector2::new(s, -c) } else { Vector2::new(-s, c) };
        (ex, ey)
    }

    /// The pixel that sees table offset `d` (inches) from the optical axis.
    pub(crate) fn pixel(&self, d: Vector2<f64>) -> Point2<f64> {
        let (ex, ey) = self.axes();
        Point2::new(self.centre_px.x + d.dot(&ex) / self.pitch_in.x, self.centre_px.y + d.dot(&ey) / self.pitch_in.y)
    }

    /// Table inches per pixel from the optical axis: the matrix `K·R` of a correct calibration.
    pub(crate) fn table_per_pixel(&self) -> Matrix2<f64> {
        let (ex, ey) = self.axes();
        Matrix2::from_columns(&[ex * self.pitch_in.x, ey * self.pitch_in.y])
    }

    /// The calibration a perfect M283 finds, inches per pixel: of the eight `K = (K·R)·Rᵀ`, the
    /// one whose diagonal is positive and largest (the camera turned by less than 45° after the
    /// remap), with its remap.
    pub(crate) fn calibration(&self) -> (Matrix2<f64>, Remap) {
        let m = self.table_per_pixel();
        let k_of = |r: &Remap| m * r.matrix().transpose();
        let score = |r: &Remap| k_of(r)[(0, 0)].min(k_of(r)[(1, 1)]);
        let best = Remap::all().into_iter().max_by(|a, b| score(a).total_cmp(&score(b))).unwrap_or_default();
        (k_of(&best), best)
    }
}

/// Everything the fakes share. Lengths in inches.
#[derive(Debug, Clone)]
pub(crate) struct World {
    pub units: LengthUnit,
    pub absolute: bool,
    pub program: Point2<f64>,
    /// Alignment modals, inches.
    pub alignment: Option<AlignmentChain>,
    pub tool: u32,
    pub offsets: BTreeMap<u32, Vector2<f64>>,
    pub pounds: BTreeMap<u32, f64>,
    /// Physical spindle position, updated on every move.
    pub spindle: Point2<f64>,
    /// Head Z, inches: the camera's working distance is `working_distance_in + z`.
    pub z: f64,
    /// The working distance at Z 0, inches (the optics' pitch holds there).
    pub working_distance_in: f64,
    /// Z moves fail after this many more accepted ones (the controller refuses the line).
    pub refuse_z_after: Option<usize>,
    /// The camera finds nothing while the head is above Z 0 (out of focus).
    pub blind_above: bool,
    pub now_s: u64,
    pub log: Vec<String>,
    pub dwell_s: f64,
    /// `set_pound` fails for this address.
    pub fail_pound: Option<u32>,
    /// The highest pound variable the machine has.
    pub last_pound: u32,
    /// A call of the machine (`FakeMachine::run_lines`) fails after this many more.
    pub fail_gcode_after: Option<usize>,
    /// Modal states saved by the module (distance mode, units), newest last.
    pub saved_modal: Vec<(bool, LengthUnit)>,
    /// `set_tool_offset` fails after this many more calls.
    pub fail_offset_after: Option<usize>,

    pub marks: Vec<Point2<f64>>,
    pub mark_size: f64,
    /// The true camera.
    pub optics: Optics,
    /// Image size, pixels (marks outside are not seen).
    pub res: Vector2<f64>,
    /// The frame size the camera reports (`CameraDriver::frame_size`); `None`: it reports none.
    pub frame: Option<(u32, u32)>,
    /// The camera driver's name.
    pub camera_name: &'static str,
    /// The mark the camera says it searches for (`CameraDriver::mark_spec`).
    pub mark_spec: Option<&'static str>,
    /// Optical axis minus spindle, inches.
    pub cam_offset: Vector2<f64>,
    pub script: VecDeque<Result<Reading, DriverError>>,
    pub select_job: bool,
    pub jobs: Vec<u32>,
    /// The image the camera keeps for a trigger (M281 D1); `None`: it has none.
    pub image: Option<Vec<u8>>,
    /// Every image request: the trigger's time, seconds since the epoch, and its stamp.
    pub grabs: Vec<(u64, String)>,
    pub triggers: usize,
    /// Uniform pixel noise amplitude (±px) added to every reading.
    pub noise_px: f64,
    pub rng: u64,
    /// A search window about the image centre, pixels: only a mark wholly inside it is found
    /// (as the `Camera` driver's `VisionCameraSearchRadius`); `None`: the whole image.
    pub window_px: Option<f64>,
}

impl Default for World {
    fn default() -> Self {
        World {
            units: LengthUnit::Inch,
            absolute: true,
            program: Point2::origin(),
            alignment: None,
            tool: 98,
            offsets: BTreeMap::from([(1, Vector2::zeros()), (98, Vector2::zeros())]),
            pounds: BTreeMap::new(),
            spindle: Point2::origin(),
            z: 0.0,
            working_distance_in: 6.0,
            refuse_z_after: None,
            blind_above: false,
            now_s: 1_700_000_000,
            log: Vec::new(),
            dwell_s: 0.0,
            fail_pound: None,
            last_pound: 9999,
            fail_gcode_after: None,
            saved_modal: Vec::new(),
            fail_offset_after: None,
            marks: Vec::new(),
            mark_size: 0.5,
            optics: Optics::square(0.0, true),
            res: Vector2::new(1776.0, 1776.0),
            frame: None,
            camera_name: "Fake",
            mark_spec: None,
            cam_offset: Vector2::zeros(),
            script: VecDeque::new(),
            select_job: true,
            jobs: Vec::new(),
            image: None,
            grabs: Vec::new(),
            triggers: 0,
            noise_px: 0.0,
            rng: 0x9E37_79B9_7F4A_7C15,
            window_px: None,
        }
    }
}

impl World {
    fn to_inch(&self, v: f64) -> f64 {
        self.units.convert(v, LengthUnit::Inch)
    }
    fn inch_to_cur(&self, v: f64) -> f64 {
        LengthUnit::Inch.convert(v, self.units)
    }
    /// Recomputes the spindle from the commanded position (a move happened).
    pub(crate) fn settle(&mut self) {
        let work = self.alignment.map_or(self.program, |a| a.apply(self.program));
        let off = self.offsets.get(&self.tool).copied().unwrap_or_default();
        self.spindle = work - off;
    }
    /// The optical axis, inches.
    pub(crate) fn camera_axis(&self) -> Point2<f64> {
        self.spindle + self.cam_offset
    }
    /// Uniform in [−1, 1), deterministic (xorshift).
    fn jitter(&mut self) -> f64 {
        self.rng ^= self.rng << 13;
        self.rng ^= self.rng >> 7;
        self.rng ^= self.rng << 17;
        let u = (self.rng >> 11) as f64 / (1u64 << 53) as f64;
        2.0 * u - 1.0
    }
    fn see(&mut self) -> Reading {
        let r = self.see_exact();
        if self.noise_px > 0.0 && r.found() {
            let (nx, ny) = (self.jitter() * self.noise_px, self.jitter() * self.noise_px);
            return Reading { x_px: r.x_px + nx, y_px: r.y_px + ny, ..r };
        }
        r
    }
    fn see_exact(&self) -> Reading {
        if self.blind_above && self.z > 1e-9 {
            return Reading { judgment: Judgment::Ng, count: Some(0), ..Reading::position(0.0, 0.0) };
        }
        let axis = self.camera_axis();
        // The image scales with the working distance, about the optical axis's pixel.
        let grow = (self.working_distance_in + self.z) / self.working_distance_in;
        let radius_px = 0.5 * self.mark_size / self.optics.pitch_in.x.max(self.optics.pitch_in.y) / grow;
        let in_window =
            |p: &Point2<f64>| self.window_px.is_none_or(|r| (p - Point2::from(self.res * 0.5)).norm() + radius_px <= r);
        let best = self
            .marks
            .iter()
            .map(|m| self.optics.pixel((m - axis) / grow))
            .filter(|p| p.x >= 0.0 && p.y >= 0.0 && p.x < self.res.x && p.y < self.res.y)
            .filter(in_window)
            .min_by(|a, b| {
                let c = Point2::from(self.res * 0.5);
                (a - c).norm().total_cmp(&(b - c).norm())
            });
        match best {
            None => Reading { judgment: Judgment::Ng, count: Some(0), ..Reading::position(0.0, 0.0) },
            Some(p) => Reading {
                judgment: Judgment::Ok,
                count: Some(1),
                x_px: p.x,
                y_px: p.y,
                width_px: self.mark_size / self.optics.pitch_in.x / grow,
                height_px: self.mark_size / self.optics.pitch_in.y / grow,
                angle_deg: 1.5,
                score: 0.97,
            },
        }
    }
}

pub(crate) type Shared = Arc<Mutex<World>>;

fn lock(s: &Shared) -> MutexGuard<'_, World> {
    s.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The fake machine.
pub(crate) struct FakeMachine(pub Shared);

/// Mach4's cancel line, as the fake writes and reads it.
pub(crate) const CANCEL_LINE: &str = "G69 G50 G52 X0 Y0";

impl FakeMachine {
    pub(crate) fn world(&self) -> MutexGuard<'_, World> {
        lock(&self.0)
    }

    /// Runs `lines` as one call of the machine (which [`World::fail_gcode_after`] counts).
    pub(crate) fn run_lines(&mut self, lines: &[String]) -> Result<(), MachineError> {
        let mut w = self.world();
        if let Some(n) = w.fail_gcode_after {
            if n == 0 {
                return Err(MachineError::new(MachineErrorKind::Stopped, "emergency stop"));
            }
            w.fail_gcode_after = Some(n - 1);
        }
        for line in lines {
            w.log.push(line.clone());
            if line == CANCEL_LINE {
                w.alignment = None;
                continue;
            }
            if let Some(chain) = alignment_modal(&w, line)? {
                w.alignment = Some(chain);
                continue;
            }
            let (mut x, mut y, mut z) = (None, None, None);
            for word in line.split_whitespace() {
                let (letter, num) = word.split_at(1);
                let bad = || MachineError::new(MachineErrorKind::RefusedGcode, format!("bad word {word}"));
                match (letter, num) {
                    ("G", "0" | "00" | "1" | "01") => {}
                    ("G", "90") => w.absolute = true,
                    ("G", "91") => w.absolute = false,
                    ("G", "20") => w.units = LengthUnit::Inch,
                    ("G", "21") => w.units = LengthUnit::Millimetre,
                    ("X", v) => x = Some(w.to_inch(v.parse().map_err(|_| bad())?)),
                    ("Y", v) => y = Some(w.to_inch(v.parse().map_err(|_| bad())?)),
                    ("Z", v) => z = Some(w.to_inch(v.parse().map_err(|_| bad())?)),
                    _ => {
                        return Err(MachineError::new(
                            MachineErrorKind::RefusedGcode,
                            format!("unsupported word {word} in {line:?}"),
                        ))
                    }
                }
            }
            if let Some(z) = z {
                if let Some(n) = w.refuse_z_after {
                    if n == 0 {
                        return Err(MachineError::new(MachineErrorKind::RefusedGcode, "Z is locked"));
                    }
                    w.refuse_z_after = Some(n - 1);
                }
                w.z = if w.absolute { z } else { w.z + z };
            }
            if x.is_some() || y.is_some() {
                let p = w.program;
                w.program = if w.absolute {
                    Point2::new(x.unwrap_or(p.x), y.unwrap_or(p.y))
                } else {
                    Point2::new(p.x + x.unwrap_or(0.0), p.y + y.unwrap_or(0.0))
                };
                w.settle();
            }
        }
        Ok(())
    }
}

/// The fake's text for `command`: Mach4's, written here independently of `vision-mcode`.
fn fake_text(command: &MachineCommand) -> Vec<String> {
    let p = |v: f64| fixed(v, POSITION_DECIMALS);
    match *command {
        MachineCommand::CancelAlignment => vec![CANCEL_LINE.to_string()],
        MachineCommand::ClearShift => vec!["G52 X0 Y0".to_string()],
        MachineCommand::SetShift(v) => vec![format!("G52 X{} Y{}", p(v.x), p(v.y))],
        MachineCommand::SetRotation { centre, deg } => {
            vec![format!("G68 X{} Y{} R{}", p(centre.x), p(centre.y), fixed(deg, ANGLE_DECIMALS))]
        }
        MachineCommand::SetScale(v) => {
            vec![format!("G51 X{} Y{}", fixed(v.x, SCALE_DECIMALS), fixed(v.y, SCALE_DECIMALS))]
        }
        MachineCommand::SetWorkRotation { deg } => vec![format!("G10 L2 P0 R{}", fixed(deg, ANGLE_DECIMALS))],
        MachineCommand::MoveTo(t) => vec![format!("G90 G0 X{} Y{}", p(t.x), p(t.y))],
        MachineCommand::MoveBy(d) => vec![format!("G91 G0 X{} Y{}", p(d.x), p(d.y)), "G90".to_string()],
        MachineCommand::MoveZBy(dz) => vec![format!("G91 G0 Z{}", p(dz)), "G90".to_string()],
        // The host's commands: no line (Mach4 is never handed them).
        MachineCommand::AlignMoves(_) | MachineCommand::CancelMoveAlignment => Vec::new(),
    }
}

impl Machine for FakeMachine {
    fn controller(&self) -> &'static dyn Controller {
        &Mach4
    }
    fn program_position(&self) -> Result<Point2<f64>, MachineError> {
        let w = self.world();
        Ok(Point2::new(w.inch_to_cur(w.program.x), w.inch_to_cur(w.program.y)))
    }
    fn save_modal_state(&mut self) -> Result<(), MachineError> {
        let mut w = self.world();
        let state = (w.absolute, w.units);
        w.saved_modal.push(state);
        Ok(())
    }
    fn restore_modal_state(&mut self) -> Result<(), MachineError> {
        let mut w = self.world();
        let (absolute, units) =
            w.saved_modal.pop().ok_or_else(|| MachineError::new(MachineErrorKind::Other, "nothing saved"))?;
        (w.absolute, w.units) = (absolute, units);
        Ok(())
    }
    fn alignment_active(&self) -> Result<Option<bool>, MachineError> {
        Ok(Some(self.world().alignment.is_some()))
    }
    fn gcode(&self, command: &MachineCommand) -> Result<Vec<String>, MachineError> {
        Ok(fake_text(command))
    }
    fn execute(&mut self, line: &str) -> Result<(), MachineError> {
        self.run_lines(&[line.to_string()])
    }
    /// One call of the machine, as [`Machine::run`]'s.
    fn command(&mut self, command: &MachineCommand) -> Result<Vec<String>, MachineError> {
        self.run(std::slice::from_ref(command))
    }
    /// All the commands' lines as one call of the machine.
    fn run(&mut self, commands: &[MachineCommand]) -> Result<Vec<String>, MachineError> {
        let lines: Vec<String> = commands.iter().flat_map(fake_text).collect();
        self.run_lines(&lines)?;
        Ok(lines)
    }
    fn active_tool(&self) -> Result<u32, MachineError> {
        Ok(self.world().tool)
    }
    fn tool_offset(&self, tool: u32) -> Result<Vector2<f64>, MachineError> {
        let w = self.world();
        let o = w
            .offsets
            .get(&tool)
            .copied()
            .ok_or_else(|| MachineError::new(MachineErrorKind::UnknownTool, format!("no tool {tool}")))?;
        Ok(o * w.inch_to_cur(1.0))
    }
    fn set_tool_offset(&mut self, tool: u32, offset: Vector2<f64>) -> Result<(), MachineError> {
        let mut w = self.world();
        if let Some(n) = w.fail_offset_after {
            if n == 0 {
                return Err(MachineError::new(MachineErrorKind::Other, "the tool table is locked"));
            }
            w.fail_offset_after = Some(n - 1);
        }
        let f = w.to_inch(1.0);
        match w.offsets.get_mut(&tool) {
            Some(o) => {
                *o = offset * f;
                Ok(())
            }
            None => Err(MachineError::new(MachineErrorKind::UnknownTool, format!("no tool {tool}"))),
        }
    }
    fn units(&self) -> Result<LengthUnit, MachineError> {
        Ok(self.world().units)
    }
    fn pound(&self, index: u32) -> Result<f64, MachineError> {
        let w = self.world();
        if index > w.last_pound {
            return Err(MachineError::new(
                MachineErrorKind::OutOfRange,
                format!("#{index} does not exist (the last is #{})", w.last_pound),
            ));
        }
        Ok(w.pounds.get(&index).copied().unwrap_or(0.0))
    }
    fn set_pound(&mut self, index: u32, value: f64) -> Result<(), MachineError> {
        let mut w = self.world();
        if w.fail_pound == Some(index) {
            return Err(MachineError::new(MachineErrorKind::OutOfRange, format!("#{index} is read-only")));
        }
        w.pounds.insert(index, value);
        Ok(())
    }
    fn dwell(&mut self, seconds: f64) -> Result<(), MachineError> {
        self.world().dwell_s += seconds;
        Ok(())
    }
    fn now(&self) -> Timestamp {
        Timestamp::from_unix(self.world().now_s, 3600)
    }
}

/// The alignment after one of M282's `G52 X Y` / `G68 X Y R` / `G51 X Y` lines (positions in
/// current units, stored in inches); `None` for any other line.
fn alignment_modal(w: &World, line: &str) -> Result<Option<AlignmentChain>, MachineError> {
    let mut words = line.split_whitespace();
    let code = words.next().unwrap_or_default();
    if !["G52", "G68", "G51"].contains(&code) {
        return Ok(None);
    }
    let mut value = |letter: char| -> Result<f64, MachineError> {
        let word = words.next().filter(|w| w.starts_with(letter));
        word.and_then(|w| w[1..].parse().ok()).ok_or_else(|| {
            MachineError::new(MachineErrorKind::RefusedGcode, format!("{code} needs {letter} in {line:?}"))
        })
    };
    let mut chain = w.alignment.unwrap_or(AlignmentChain::IDENTITY);
    match code {
        "G52" => chain.shift = Vector2::new(w.to_inch(value('X')?), w.to_inch(value('Y')?)),
        "G68" => {
            chain.center = Point2::new(w.to_inch(value('X')?), w.to_inch(value('Y')?));
            chain.rotation_deg = value('R')?;
        }
        _ => chain.scale = Vector2::new(value('X')?, value('Y')?),
    }
    Ok(Some(chain))
}

/// The fake camera.
pub(crate) struct FakeCamera(pub Shared);

impl CameraDriver for FakeCamera {
    fn name(&self) -> &str {
        lock(&self.0).camera_name
    }
    fn capabilities(&self) -> Capabilities {
        Capabilities { select_job: lock(&self.0).select_job, grab_image: true }
    }
    fn trigger(&mut self) -> Result<Reading, DriverError> {
        let mut w = lock(&self.0);
        w.triggers += 1;
        match w.script.pop_front() {
            Some(r) => r,
            None => Ok(w.see()),
        }
    }
    fn select_job(&mut self, job: u32) -> Result<(), DriverError> {
        let mut w = lock(&self.0);
        if !w.select_job {
            return Err(DriverError::new(DriverErrorKind::Unsupported, "no jobs"));
        }
        w.jobs.push(job);
        Ok(())
    }
    fn test_connection(&mut self) -> Result<String, DriverError> {
        Ok("FVR,fake".into())
    }
    fn frame_size(&mut self) -> Option<(u32, u32)> {
        lock(&self.0).frame
    }
    fn mark_spec(&self) -> Option<String> {
        lock(&self.0).mark_spec.map(str::to_string)
    }
    fn grab_image(&mut self, request: &ImageRequest<'_>) -> Result<std::path::PathBuf, DriverError> {
        let mut w = lock(&self.0);
        let since = request.since.duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
        w.grabs.push((since, request.stamp.to_string()));
        let Some(bytes) = w.image.clone() else {
            return Err(DriverError::new(DriverErrorKind::Timeout, "the fake camera kept no image — give it one"));
        };
        let path = request.dir.join(format!("vision_{}.bmp", request.stamp));
        std::fs::create_dir_all(request.dir)
            .and_then(|()| std::fs::write(&path, bytes))
            .map_err(|e| DriverError::new(DriverErrorKind::Other, e))?;
        Ok(path)
    }
    fn reading_warning(&self, reading: &Reading) -> Option<String> {
        reading.count.filter(|n| *n > 1).map(|n| format!("the fake camera saw {n} marks and reported the nearest"))
    }
}

/// A machine, a camera and a module sharing one world.
pub(crate) struct Rig {
    pub machine: FakeMachine,
    pub module: VisionModule,
    pub shared: Shared,
}

impl Rig {
    /// Vision enabled, calibrated for the true camera (0.00203 in square pixels, a mirrored
    /// image: K = 0.00203 in/px, InvertY), camera tool 98 active.
    pub(crate) fn new() -> Rig {
        Rig::with_world(World::default())
    }

    pub(crate) fn with_world(world: World) -> Rig {
        let shared: Shared = Arc::new(Mutex::new(world));
        lock(&shared).settle();
        let mut params = Params::default();
        params.set("VisionEnabled", true).expect("set");
        params.set("VisionCameraToolNumber", 98).expect("set");
        let (k, remap) = lock(&shared).optics.calibration();
        params.set_cal_k(k).expect("k");
        params.set_remap(remap);
        let module = VisionModule::new(params).with_driver(Box::new(FakeCamera(shared.clone())));
        Rig { machine: FakeMachine(shared.clone()), module, shared }
    }

    pub(crate) fn world(&self) -> MutexGuard<'_, World> {
        lock(&self.shared)
    }

    /// Runs G-code on the fake machine.
    pub(crate) fn run(&mut self, lines: &[String]) {
        self.machine.run_lines(lines).expect("fake machine runs it");
    }

    /// `G90 G0 X.. Y..` in current units.
    pub(crate) fn go(&mut self, x: f64, y: f64) {
        self.run(&[format!("G90 G0 X{x} Y{y}")]);
    }
}
