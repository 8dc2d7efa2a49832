//! The world description: everything that is physically true in a simulation, as TOML.
//!
//! Every length is in the world's [`World::unit`] (inch unless the file says `unit = "mm"`),
//! every angle in degrees counter-clockwise seen from +Z, every pixel quantity in native camera
//! pixels. Machine coordinates are the spindle's position; work coordinates are machine
//! coordinates minus [`MachineSetup::work_offset`] (the G54 the world starts with).
//!
//! The built-in default world ([`World::default_world`]) is `default_world.toml` in this crate,
//! a complete, commented example of the format.

use serde::{Deserialize, Serialize};
use vision_core::{cal_sheet, Controller};
use vision_locate::MarkKind;
use vision_math::{LengthUnit, Point2, Vector2};

use crate::error::SimError;

/// The length unit of a world file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
pub enum WorldUnit {
    /// Inches (`"in"`).
    #[default]
    #[serde(rename = "in")]
    Inch,
    /// Millimetres (`"mm"`).
    #[serde(rename = "mm")]
    Millimetre,
}

impl WorldUnit {
    /// The same unit as a [`LengthUnit`].
    #[must_use]
    pub fn length_unit(self) -> LengthUnit {
        match self {
            WorldUnit::Inch => LengthUnit::Inch,
            WorldUnit::Millimetre => LengthUnit::Millimetre,
        }
    }
}

/// The controller the simulated machine is (its G-code dialect and its alignment rules), by its
/// name in a world file: `"mach4"` (the default), `"linuxcnc"`, `"machinemotion"`
/// ([`vision_core::controller::CONTROLLERS`]).
#[derive(Debug, Clone, Copy)]
pub struct ControllerName(pub &'static dyn Controller);

impl ControllerName {
    /// The controller.
    #[must_use]
    pub fn get(self) -> &'static dyn Controller {
        self.0
    }
}

impl Default for ControllerName {
    fn default() -> Self {
        ControllerName(&vision_core::controller::Mach4)
    }
}

impl PartialEq for ControllerName {
    fn eq(&self, other: &Self) -> bool {
        self.0.name() == other.0.name()
    }
}

impl Serialize for ControllerName {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.0.name())
    }
}

impl<'de> Deserialize<'de> for ControllerName {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        vision_core::controller::by_name(&name).map(ControllerName).map_err(serde::de::Error::custom)
    }
}

/// A simulated world: the camera, the machine, and what lies on the table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct World {
    /// Unit of every length in the world (default inch).
    #[serde(default)]
    pub unit: WorldUnit,
    /// Seed of the pixel-noise generator: the same seed and the same program give the same run.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// The camera and how it is mounted.
    pub camera: CameraMount,
    /// The machine.
    pub machine: MachineSetup,
    /// What lies on the table (parts and calibration sheets).
    #[serde(default, rename = "fixture")]
    pub fixtures: Vec<Fixture>,
}

fn default_seed() -> u64 {
    1
}

/// The camera, its optics and its mount on the head.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraMount {
    /// Optical axis minus spindle, machine X/Y axes, world unit. (The camera tool's true X/Y
    /// tool-table offset when the reference pixel is the optical centre.)
    #[serde(deserialize_with = "exact::array")]
    pub offset: [f64; 2],
    /// Rotation of the image about +Z, degrees counter-clockwise: 0 means image +x along machine
    /// +X and image +y (down) along machine −Y. Any angle is allowed (90° multiples included).
    #[serde(default)]
    pub rotation_deg: f64,
    /// The image is mirrored (image x flipped), e.g. a camera looking through a mirror.
    #[serde(default)]
    pub mirror: bool,
    /// Size of one pixel's height on the table at `reference_working_distance`, world unit per
    /// pixel.
    pub units_per_pixel: f64,
    /// Pixel width over pixel height (1 = square pixels).
    #[serde(default = "one")]
    pub pixel_aspect: f64,
    /// Image size `[ResX, ResY]`, pixels.
    #[serde(default = "default_resolution", deserialize_with = "exact::array")]
    pub resolution: [u32; 2],
    /// Optical centre minus image centre `[x, y]`, native pixels (a lens not centred on the
    /// sensor).
    #[serde(default, deserialize_with = "exact::array")]
    pub center_bias_px: [f64; 2],
    /// Lens distortion `[k1, k2, p1, p2, k3]`, OpenCV's Brown–Conrady model on coordinates
    /// normalised by f = reference working distance / units per pixel (pixels), about the
    /// optical centre ([`crate::Lens`]); absent: none.
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "exact::option")]
    pub distortion: Option<[f64; 5]>,
    /// Lens-to-surface distance with the spindle at `focus_z`, world unit. The scale on the
    /// table is proportional to the distance, which grows one for one with the machine's Z (the
    /// camera rides on the head): `working_distance + (Z − focus_z)`.
    pub working_distance: f64,
    /// The spindle's machine Z at which `working_distance` holds, world unit (defaults to the
    /// start Z, `machine.start[2]`: a world whose head never moves in Z sees what it did before
    /// the camera followed Z).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focus_z: Option<f64>,
    /// The distance at which `units_per_pixel` holds, world unit (defaults to
    /// `working_distance`).
    #[serde(default)]
    pub reference_working_distance: Option<f64>,
    /// Standard deviation of the Gaussian noise added to each reported pixel coordinate, pixels.
    #[serde(default)]
    pub noise_px: f64,
    /// A mark is found only when its centre lies at least this far inside the image, pixels.
    #[serde(default = "default_margin")]
    pub margin_px: f64,
    /// Camera jobs selectable with M284; empty means every job 1–999 behaves like the base
    /// settings.
    #[serde(default, rename = "job")]
    pub jobs: Vec<Job>,
    /// What the camera's image looks like (`[camera.image]`), for the image-mode camera
    /// ([`crate::Sim::render_frame`]); absent: [`ImageLook::default`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image: Option<ImageLook>,
}

/// What the image-mode camera sees besides the geometry (which is the reading-mode camera's:
/// the same optics, the same marks): the print, the focus, the light and the sensor.
/// Reflectances are 0 (black) to 1 (white).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImageLook {
    /// The marks' shape: a dot of the fixture's diameter, a ring of that outer diameter, or a
    /// cross whose bars are that long tip to tip, turned with the fixture.
    pub mark: MarkKind,
    /// Reflectance of the ink (a light mark on a dark ground when above `ground`).
    pub ink: f64,
    /// Reflectance of the paper or part around the marks.
    pub ground: f64,
    /// Ring line or cross bar width, percent of the mark's diameter.
    pub line_width_pct: f64,
    /// Gaussian blur σ of the lens in focus, pixels.
    pub blur_px: f64,
    /// Extra blur σ per percent of working-distance change from `focus_distance`, pixels: a
    /// camera focused at one height sees a blurrier mark at another.
    pub defocus_px_per_pct: f64,
    /// The distance the lens is focused at, world unit (default: the reference working
    /// distance, else the working distance).
    pub focus_distance: Option<f64>,
    /// Sensor noise σ, grey levels (8 bit).
    pub noise_grey: f64,
    /// Illumination at the image centre, fraction of full scale for a white ground.
    pub light: f64,
    /// Uneven light: the illumination changes by this much across the image, percent.
    pub light_gradient_pct: f64,
    /// The direction the light grows in, degrees from image +x towards +y.
    pub light_angle_deg: f64,
    /// How many clutter items (scratches, specks smaller than a fifth of a mark, a part
    /// edge) each frame shows, away from the mark nearest the centre.
    pub clutter: u32,
}

impl Default for ImageLook {
    /// A black dot printed on white paper, slightly soft, σ = 2 grey levels of noise and a 20 %
    /// light gradient, no clutter.
    fn default() -> Self {
        ImageLook {
            mark: MarkKind::Dot,
            ink: 0.08,
            ground: 0.85,
            line_width_pct: 20.0,
            blur_px: 0.8,
            defocus_px_per_pct: 0.5,
            focus_distance: None,
            noise_grey: 2.0,
            light: 0.9,
            light_gradient_pct: 20.0,
            light_angle_deg: 30.0,
            clutter: 0,
        }
    }
}

fn one() -> f64 {
    1.0
}
fn default_resolution() -> [u32; 2] {
    [1776, 1776]
}
fn default_margin() -> f64 {
    20.0
}

/// A camera job (inspection program) with its own settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Job {
    /// Job number, 1–999.
    pub id: u32,
    /// What the job is (shown in reports).
    #[serde(default)]
    pub name: String,
    /// This job's pixel noise σ, pixels (default: the camera's).
    #[serde(default)]
    pub noise_px: Option<f64>,
    /// This job's detection margin, pixels (default: the camera's).
    #[serde(default)]
    pub margin_px: Option<f64>,
}

/// The machine: where it starts, its work offset, its tools.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MachineSetup {
    /// Spindle position at start, machine coordinates `[X, Y, Z]`, world unit.
    #[serde(default, deserialize_with = "exact::array")]
    pub start: [f64; 3],
    /// G54: the machine position of work zero `[X, Y, Z]`, world unit. Fixture poses are given
    /// in this work frame.
    #[serde(default, deserialize_with = "exact::array")]
    pub work_offset: [f64; 3],
    /// The camera's tool number (`VisionCameraToolNumber`).
    #[serde(default = "default_camera_tool")]
    pub camera_tool: u32,
    /// The camera tool's X/Y in the control's tool table at start, world unit. Omitted: the true
    /// offset, as a calibration would have left it.
    #[serde(default, deserialize_with = "exact::option")]
    pub camera_table_offset: Option<[f64; 2]>,
    /// The tool the machine starts with (0 = none).
    #[serde(default)]
    pub start_tool: u32,
    /// The cutting tools: their true offsets, which the tool table also holds.
    #[serde(default, rename = "tool")]
    pub tools: Vec<Tool>,
    /// Fastest speed of each axis (rapids), world unit per second (default 8 in/s =
    /// 203.2 mm/s). Used for cycle times.
    #[serde(default)]
    pub max_speed: Option<f64>,
    /// Largest acceleration, of the path and of each axis, world unit per second² (default
    /// 20 in/s² = 508 mm/s²). Used for cycle times.
    #[serde(default)]
    pub max_accel: Option<f64>,
    /// The controller the machine is, key `dialect` (default `"mach4"`): the interpreter follows
    /// its G-code dialect and the Vision M-codes its rules.
    #[serde(default, rename = "dialect", alias = "controller")]
    pub controller: ControllerName,
}

/// Default axis speed, inch per second.
const DEFAULT_MAX_SPEED_IN: f64 = 8.0;
/// Default acceleration, inch per second².
const DEFAULT_MAX_ACCEL_IN: f64 = 20.0;

impl MachineSetup {
    /// The controller the machine is.
    #[must_use]
    pub fn controller(&self) -> &'static dyn Controller {
        self.controller.get()
    }

    /// `(max_speed, max_accel)` in `unit` per second and per second², defaults filled in.
    #[must_use]
    pub fn motion_limits(&self, unit: WorldUnit) -> (f64, f64) {
        let f = LengthUnit::Inch.factor_to(unit.length_unit());
        (self.max_speed.unwrap_or(DEFAULT_MAX_SPEED_IN * f), self.max_accel.unwrap_or(DEFAULT_MAX_ACCEL_IN * f))
    }
}

fn default_camera_tool() -> u32 {
    98
}

/// A cutting tool.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tool {
    /// Tool number (≥ 1, not the camera tool).
    pub number: u32,
    /// Tool tip minus spindle `[X, Y, Z]`, world unit (true, and what the table holds).
    #[serde(default, deserialize_with = "exact::array")]
    pub offset: [f64; 3],
}

/// Something on the table with marks on it: a part with fiducials, a calibration sheet, or both
/// on one print.
///
/// Where the marks really are, in work coordinates:
/// `true = R(rotation_deg)·diag(scale)·(nominal − center) + center + shift`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fixture {
    /// Name (shown in reports).
    #[serde(default)]
    pub name: String,
    /// A calibration sheet from `CAL_SHEETS` whose dots this fixture carries (in the world unit;
    /// they come first, in walk order).
    #[serde(default)]
    pub sheet: Option<u32>,
    /// Further marks, nominal work coordinates, world unit.
    #[serde(default, deserialize_with = "exact::list")]
    pub marks: Vec<[f64; 2]>,
    /// Printed mark diameter, world unit (default: the sheet's, else 0.25 in).
    #[serde(default)]
    pub diameter: Option<f64>,
    /// True shift, world unit.
    #[serde(default, deserialize_with = "exact::array")]
    pub shift: [f64; 2],
    /// True rotation, degrees counter-clockwise.
    #[serde(default)]
    pub rotation_deg: f64,
    /// True scale along the fixture's X and Y (a print scale error, or a part that grew).
    #[serde(default = "unit_scale", deserialize_with = "exact::array")]
    pub scale: [f64; 2],
    /// Pivot of the rotation and scale, nominal work coordinates (default: the sheet origin for
    /// a sheet, else the centroid of the marks).
    #[serde(default, deserialize_with = "exact::option")]
    pub center: Option<[f64; 2]>,
    /// Whether the fixture is on the table (a world can hold fixtures that tests swap in).
    #[serde(default = "yes")]
    pub present: bool,
}

fn unit_scale() -> [f64; 2] {
    [1.0, 1.0]
}
fn yes() -> bool {
    true
}

/// The built-in default world's text.
pub const DEFAULT_WORLD_TOML: &str = include_str!("default_world.toml");

impl World {
    /// The built-in default world: a calibrated camera and one printed demo target that carries
    /// calibration sheet 1 and every fiducial the manual's example programs visit.
    #[must_use]
    pub fn default_world() -> World {
        // The embedded file is checked by a test; a broken build would fail there first.
        World::from_toml(DEFAULT_WORLD_TOML).unwrap_or_else(|e| unreachable!("built-in world: {e}"))
    }

    /// Parses and validates a world file.
    ///
    /// # Errors
    /// [`SimError::Parse`] for TOML that does not match the schema (unknown fields included),
    /// [`SimError::Invalid`] for values out of range.
    pub fn from_toml(text: &str) -> Result<World, SimError> {
        let world: World =
            toml::from_str(text).map_err(|e| SimError::Parse { reason: vision_core::text::toml_error(&e, text) })?;
        world.validate()?;
        Ok(world)
    }

    /// The world as TOML.
    ///
    /// # Errors
    /// [`SimError::Parse`] if serialisation fails (it does not for a validated world).
    pub fn to_toml(&self) -> Result<String, SimError> {
        toml::to_string_pretty(self).map_err(|e| SimError::Parse { reason: e.to_string() })
    }

    /// The world unit as a [`LengthUnit`].
    #[must_use]
    pub fn length_unit(&self) -> LengthUnit {
        self.unit.length_unit()
    }

    /// Work point `p` (the frame of `machine.work_offset`, where fixtures are placed) in machine
    /// coordinates; world unit.
    #[must_use]
    pub fn work_to_machine(&self, p: Point2<f64>) -> Point2<f64> {
        p + Vector2::new(self.machine.work_offset[0], self.machine.work_offset[1])
    }

    /// Checks every value; the simulator relies on this.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the first bad field.
    pub fn validate(&self) -> Result<(), SimError> {
        let c = &self.camera;
        lengths("camera.offset", &c.offset)?;
        angle("camera.rotation_deg", c.rotation_deg)?;
        // At most 10 units per pixel: a 1776-pixel image then spans 17 760 units.
        positive("camera.units_per_pixel", c.units_per_pixel, 10.0)?;
        between("camera.pixel_aspect", c.pixel_aspect, 0.1, 10.0)?;
        positive("camera.working_distance", c.working_distance, MAX_LENGTH)?;
        if let Some(r) = c.reference_working_distance {
            positive("camera.reference_working_distance", r, MAX_LENGTH)?;
        }
        if let Some(z) = c.focus_z {
            lengths("camera.focus_z", &[z])?;
        }
        for (i, r) in c.resolution.iter().enumerate() {
            if !(2..=100_000).contains(r) {
                return invalid(format!("camera.resolution[{i}]"), "must be 2..100000 pixels");
            }
        }
        pixels("camera.center_bias_px", &c.center_bias_px, false)?;
        pixels("camera.noise_px", &[c.noise_px], true)?;
        let half = f64::from(c.resolution[0].min(c.resolution[1])) / 2.0;
        let margin_ok = |m: f64| m.is_finite() && m >= 0.0 && m < half;
        if !margin_ok(c.margin_px) {
            return invalid("camera.margin_px", "must be ≥ 0 and less than half the smaller image side");
        }
        crate::lens::Lens::new(c)?;
        if let Some(look) = &c.image {
            look.validate()?;
        }
        let mut ids = Vec::new();
        for j in &c.jobs {
            if !(1..=999).contains(&j.id) || ids.contains(&j.id) {
                return invalid(format!("camera.job id {}", j.id), "job ids must be unique and 1..999");
            }
            ids.push(j.id);
            if let Some(n) = j.noise_px {
                pixels("camera.job.noise_px", &[n], true)?;
            }
            if j.margin_px.is_some_and(|m| !margin_ok(m)) {
                return invalid("camera.job.margin_px", "must be ≥ 0 and less than half the smaller image side");
            }
        }
        let m = &self.machine;
        lengths("machine.start", &m.start)?;
        lengths("machine.work_offset", &m.work_offset)?;
        if let Some(o) = &m.camera_table_offset {
            lengths("machine.camera_table_offset", o)?;
        }
        if m.camera_tool == 0 {
            return invalid("machine.camera_tool", "the camera needs a tool number ≥ 1");
        }
        let mut numbers = vec![m.camera_tool];
        for t in &m.tools {
            if t.number == 0 || numbers.contains(&t.number) {
                return invalid(
                    format!("machine.tool {}", t.number),
                    "tool numbers must be ≥ 1, unique, and not the camera tool",
                );
            }
            numbers.push(t.number);
            lengths("machine.tool.offset", &t.offset)?;
        }
        if let Some(v) = m.max_speed {
            // The planner's own range is checked where cycle times are planned.
            positive("machine.max_speed", v, f64::MAX)?;
        }
        if let Some(v) = m.max_accel {
            positive("machine.max_accel", v, f64::MAX)?;
        }
        if m.start_tool != 0 && !numbers.contains(&m.start_tool) {
            return invalid("machine.start_tool", "must be 0, the camera tool or a listed tool");
        }
        for f in &self.fixtures {
            f.validate()?;
        }
        Ok(())
    }
}

impl ImageLook {
    fn validate(&self) -> Result<(), SimError> {
        let unit = |field: &str, v: f64| {
            if (0.0..=1.0).contains(&v) {
                Ok(())
            } else {
                invalid(format!("camera.image.{field}"), "must be 0 to 1")
            }
        };
        unit("ink", self.ink)?;
        unit("ground", self.ground)?;
        unit("light", self.light)?;
        if (self.ink - self.ground).abs() < 0.05 {
            return invalid("camera.image.ink", "must differ from ground by at least 0.05, or the mark is invisible");
        }
        let range = |field: &str, v: f64, max: f64| {
            if v.is_finite() && (0.0..=max).contains(&v) {
                Ok(())
            } else {
                invalid(format!("camera.image.{field}"), format!("must be 0 to {max}"))
            }
        };
        range("line_width_pct", self.line_width_pct, 50.0)?;
        if self.mark != MarkKind::Dot && self.line_width_pct < 1.0 {
            return invalid("camera.image.line_width_pct", "must be at least 1 for a ring or a cross");
        }
        range("blur_px", self.blur_px, 50.0)?;
        range("defocus_px_per_pct", self.defocus_px_per_pct, 50.0)?;
        range("noise_grey", self.noise_grey, 100.0)?;
        range("light_gradient_pct", self.light_gradient_pct, 90.0)?;
        angle("camera.image.light_angle_deg", self.light_angle_deg)?;
        if let Some(f) = self.focus_distance {
            positive("camera.image.focus_distance", f, MAX_LENGTH)?;
        }
        if self.clutter > 1000 {
            return invalid("camera.image.clutter", "must be at most 1000 items");
        }
        Ok(())
    }
}

impl Fixture {
    fn validate(&self) -> Result<(), SimError> {
        let at = |field: &str| format!("fixture {:?}: {field}", self.name);
        if let Some(n) = self.sheet {
            if cal_sheet(n).is_none() {
                return invalid(at("sheet"), format!("no calibration sheet {n} in CAL_SHEETS"));
            }
        } else if self.marks.is_empty() {
            return invalid(at("marks"), "a fixture needs marks or a sheet");
        }
        for m in &self.marks {
            lengths(&at("marks"), m)?;
        }
        if let Some(d) = self.diameter {
            positive(&at("diameter"), d, MAX_LENGTH)?;
        }
        lengths(&at("shift"), &self.shift)?;
        angle(&at("rotation_deg"), self.rotation_deg)?;
        between(&at("scale[0]"), self.scale[0], 0.1, 10.0)?;
        between(&at("scale[1]"), self.scale[1], 0.1, 10.0)?;
        if let Some(c) = &self.center {
            lengths(&at("center"), c)?;
        }
        Ok(())
    }
}

fn invalid<T>(field: impl Into<String>, reason: impl Into<String>) -> Result<T, SimError> {
    Err(SimError::Invalid { field: field.into(), reason: reason.into() })
}

/// The largest coordinate, offset or distance a world may give, world units.
///
/// Decision: a world describes a machine on a table; a kilometre in millimetres (40 000 in in
/// inches) is beyond any machine, and bounding every length keeps the simulation's sums and
/// squares exact enough that an absurd value is refused here, naming its field, not later.
pub const MAX_LENGTH: f64 = 1e6;
/// The largest angle, degrees (a thousand turns: any orientation, and still precise).
pub const MAX_ANGLE_DEG: f64 = 360_000.0;
/// The largest pixel quantity (bias, noise), pixels.
pub const MAX_PIXELS: f64 = 100_000.0;

/// Lengths (coordinates, offsets): finite and within ±[`MAX_LENGTH`].
fn lengths(field: &str, values: &[f64]) -> Result<(), SimError> {
    if values.iter().all(|v| v.is_finite() && v.abs() <= MAX_LENGTH) {
        Ok(())
    } else {
        invalid(field, format!("must be finite numbers within ±{MAX_LENGTH} world units"))
    }
}

fn angle(field: &str, v: f64) -> Result<(), SimError> {
    if v.is_finite() && v.abs() <= MAX_ANGLE_DEG {
        Ok(())
    } else {
        invalid(field, format!("must be an angle within ±{MAX_ANGLE_DEG} degrees"))
    }
}

/// A number in `(0, max]`.
fn positive(field: &str, v: f64, max: f64) -> Result<(), SimError> {
    if v.is_finite() && v > 0.0 && v <= max {
        Ok(())
    } else {
        invalid(field, format!("must be a positive number, at most {max}"))
    }
}

/// A number in `[min, max]` (a ratio or a factor).
fn between(field: &str, v: f64, min: f64, max: f64) -> Result<(), SimError> {
    if (min..=max).contains(&v) {
        Ok(())
    } else {
        invalid(field, format!("must be between {min} and {max}"))
    }
}

/// Pixel quantities: finite, within ±[`MAX_PIXELS`] (and ≥ 0 when `non_negative`).
fn pixels(field: &str, values: &[f64], non_negative: bool) -> Result<(), SimError> {
    let lo = if non_negative { 0.0 } else { -MAX_PIXELS };
    if values.iter().all(|v| (lo..=MAX_PIXELS).contains(v)) {
        Ok(())
    } else {
        invalid(field, format!("must be between {lo} and {MAX_PIXELS} pixels"))
    }
}

/// Fixed-size arrays that refuse extra or missing elements (the TOML reader drops extras).
mod exact {
    use serde::de::{Deserialize, Deserializer, Error};

    fn fixed<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(v: Vec<T>) -> Result<[T; N], D::Error> {
        let n = v.len();
        v.try_into().map_err(|_| D::Error::invalid_length(n, &format!("an array of {N} elements").as_str()))
    }

    pub(super) fn array<'de, D, T, const N: usize>(d: D) -> Result<[T; N], D::Error>
    where
        D: Deserializer<'de>,
        T: Deserialize<'de>,
    {
        fixed::<D, T, N>(Vec::deserialize(d)?)
    }

    pub(super) fn option<'de, D, T, const N: usize>(d: D) -> Result<Option<[T; N]>, D::Error>
    where
        D: Deserializer<'de>,
        T: Deserialize<'de>,
    {
        Option::<Vec<T>>::deserialize(d)?.map(fixed::<D, T, N>).transpose()
    }

    pub(super) fn list<'de, D, T, const N: usize>(d: D) -> Result<Vec<[T; N]>, D::Error>
    where
        D: Deserializer<'de>,
        T: Deserialize<'de>,
    {
        Vec::<Vec<T>>::deserialize(d)?.into_iter().map(fixed::<D, T, N>).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_world_parses_validates_and_round_trips() {
        let w = World::from_toml(DEFAULT_WORLD_TOML).expect("built-in world");
        assert_eq!(w, World::default_world());
        let again = World::from_toml(&w.to_toml().expect("toml")).expect("round trip");
        assert_eq!(again, w);
    }

    #[test]
    fn bad_values_name_the_field() {
        let bad = |edit: &dyn Fn(&mut World)| {
            let mut w = World::default_world();
            edit(&mut w);
            match w.validate() {
                Err(SimError::Invalid { field, .. }) => field,
                other => panic!("expected Invalid, got {other:?}"),
            }
        };
        assert_eq!(bad(&|w| w.camera.units_per_pixel = 0.0), "camera.units_per_pixel");
        assert_eq!(bad(&|w| w.camera.pixel_aspect = f64::NAN), "camera.pixel_aspect");
        assert_eq!(bad(&|w| w.camera.resolution = [0, 10]), "camera.resolution[0]");
        assert_eq!(bad(&|w| w.camera.margin_px = 5000.0), "camera.margin_px");
        assert_eq!(bad(&|w| w.camera.noise_px = -1.0), "camera.noise_px");
        assert_eq!(bad(&|w| w.machine.camera_tool = 0), "machine.camera_tool");
        assert_eq!(bad(&|w| w.machine.start[2] = f64::INFINITY), "machine.start");
        assert_eq!(bad(&|w| w.machine.max_accel = Some(0.0)), "machine.max_accel");
        assert!(bad(&|w| w.fixtures[0].sheet = Some(99)).contains("sheet"));
        assert!(bad(&|w| w.fixtures[0].scale = [0.0, 1.0]).contains("scale[0]"));
        assert!(bad(&|w| {
            w.fixtures[0].sheet = None;
            w.fixtures[0].marks.clear();
        })
        .contains("marks"));
        // Absurd but finite values are refused here, naming the field, not later elsewhere.
        assert_eq!(bad(&|w| w.camera.units_per_pixel = 1e300), "camera.units_per_pixel");
        assert_eq!(bad(&|w| w.camera.rotation_deg = 1e300), "camera.rotation_deg");
        assert_eq!(bad(&|w| w.camera.offset = [1e300, 0.0]), "camera.offset");
        assert_eq!(bad(&|w| w.camera.working_distance = 1e300), "camera.working_distance");
        assert_eq!(bad(&|w| w.camera.center_bias_px = [0.0, 1e300]), "camera.center_bias_px");
        assert_eq!(bad(&|w| w.camera.noise_px = 1e300), "camera.noise_px");
        assert_eq!(bad(&|w| w.machine.work_offset = [0.0, 0.0, 1e300]), "machine.work_offset");
        assert!(bad(&|w| w.fixtures[0].rotation_deg = -1e300).contains("rotation_deg"));
        assert!(bad(&|w| w.fixtures[0].scale = [1.0, 1e300]).contains("scale[1]"));
        assert!(bad(&|w| w.fixtures[0].shift = [1e300, 0.0]).contains("shift"));
    }

    #[test]
    fn arrays_with_extra_or_missing_elements_are_refused() {
        let offset = DEFAULT_WORLD_TOML.lines().find(|l| l.starts_with("offset = ")).expect("camera offset line");
        for (edit, what) in [
            ("offset = [-3.25, 1.75, 99, \"junk\"]", "junk"),
            ("offset = [-3.25, 1.75, 99]", "3"),
            ("offset = [-3.25]", "1"),
        ] {
            let text = DEFAULT_WORLD_TOML.replacen(offset, edit, 1);
            match World::from_toml(&text) {
                Err(SimError::Parse { reason }) => assert!(reason.contains(what), "{edit}: {reason}"),
                other => panic!("{edit}: expected a parse error, got {other:?}"),
            }
        }
        for (from, to) in [
            ("start = [10.9, 2.15, 0.0]", "start = [10.9, 2.15, 0.0, 1.0]"),
            ("offset = [0.0, 0.0, 0.0]", "offset = [0.0, 0.0]"),
            ("# camera_table_offset omitted", "camera_table_offset = [0.0] #"),
            ("# camera_table_offset omitted", "camera_table_offset = [0.0, 1.0, 2.0] #"),
        ] {
            assert!(DEFAULT_WORLD_TOML.contains(from), "{from}");
            let text = DEFAULT_WORLD_TOML.replacen(from, to, 1);
            assert!(matches!(World::from_toml(&text), Err(SimError::Parse { .. })), "{to}");
        }
        let text =
            DEFAULT_WORLD_TOML.replacen("# camera_table_offset omitted", "camera_table_offset = [0.0, 1.0] #", 1);
        assert_eq!(World::from_toml(&text).map(|w| w.machine.camera_table_offset), Ok(Some([0.0, 1.0])));
        assert_eq!(
            World::from_toml(DEFAULT_WORLD_TOML).map(|w| w.camera.offset),
            Ok(World::default_world().camera.offset)
        );
    }

    #[test]
    fn unknown_fields_and_bad_toml_are_refused() {
        let text = DEFAULT_WORLD_TOML.replace("[camera]", "[camera]\nzoom = 2");
        assert!(matches!(World::from_toml(&text), Err(SimError::Parse { .. })));
        assert!(matches!(World::from_toml("camera = 3"), Err(SimError::Parse { .. })));
        assert!(matches!(World::from_toml(""), Err(SimError::Parse { .. })));
    }

    #[test]
    fn a_minimal_world_takes_the_defaults() {
        let w = World::from_toml(
            "[camera]\noffset = [1.0, 2.0]\nunits_per_pixel = 0.002\nworking_distance = 6.0\n[machine]\n",
        )
        .expect("minimal");
        assert_eq!(w.unit, WorldUnit::Inch);
        assert_eq!(w.camera.resolution, [1776, 1776]);
        assert_eq!(w.machine.camera_tool, 98);
        assert_eq!(w.machine.motion_limits(WorldUnit::Millimetre), (8.0 * 25.4, 20.0 * 25.4));
        assert!(w.fixtures.is_empty());
    }
}
