//! A simulated CNC machine and smart camera with known truth: the world mach-vision's
//! end-to-end proofs run in, and the CLI's built-in default.
//!
//! * [`World`]: the description (TOML) of what is physically true — the camera mount and
//!   optics, pixel noise and its seed, detection, the machine, and the fixtures (parts with
//!   fiducials, calibration sheets) with their true poses. Every field and its unit is documented
//!   on the types in [`world`]; `default_world.toml` ([`World::default_world`]) is a complete,
//!   commented example.
//! * [`Sim`]: one running world (shared by the camera and the machine).
//! * [`SimMachine`]: the G-code interpreter set up from the world as a CNC whose moves move the
//!   head; it runs whole programs, and gives host access through its interpreter's `Context`.
//! * [`SimCamera`]: a [`vision_core::CameraDriver`] that sees the table from the head's true
//!   position through the true optics ([`Optics`]) and reports the mark's pixel (reading mode).
//! * [`Sim::render_frame`]: the image mode — the frame that camera would see, rendered with
//!   `vision_locate::render` through the same optics ([`SimFrame`], [`ImageLook`]), for a
//!   driver that finds the mark itself.
//! * Truth: [`Sim::true_k`], [`Sim::true_camera_offset`], [`Sim::calibration_error`],
//!   [`SimMachine::cut_error`].
//!
//! # Decisions
//! * **The interpreter is the machine.** The head is where the interpreter's machine position
//!   is: the camera reads the position the interpreter publishes
//!   (`vision_gcode::Interpreter::watch_position`) whenever it triggers, including from inside
//!   an M-code handler while the interpreter is busy running it. Nothing mirrors the position
//!   from motion events, so a move, a host placing the machine and a tool change can never
//!   disagree with what the camera sees; a clone of the interpreter (a "where would this go?"
//!   question) moves nothing. Without a machine the head stays at the world's start.
//! * The crate depends on `vision-core`, `vision-gcode` and the pure `vision-locate` (its
//!   renderer) only. [`SimMachine`] is not itself a [`vision_core::Machine`]: the one bridge
//!   from an interpreter to that trait is
//!   `vision_host::ContextMachine`, which a host wraps around [`SimMachine::context`].
//! * The reading-mode camera reports the in-view mark nearest the image centre (count = marks
//!   in view); the image mode draws every mark that reaches into the frame, and the finder
//!   judges (two marks in its search window: NG).
//! * A fixture's pose is `R·diag(scale)·(nominal − pivot) + pivot + shift` in the work frame of
//!   the world's G54; a sheet pivots about its origin (where the operator zeroed the spindle),
//!   so a sheet offset is an operator zeroing error that no calibration can see.
//! * The true camera-tool offset is measured at the reference pixel `res/2 + PxCenterOffset`:
//!   an optical-centre bias the profile does not know is absorbed into the offset, as on a real
//!   machine.
//! * Noise is Gaussian, two samples per trigger, from a SplitMix64 stream seeded by the world.
//!
//! ```
//! use vision_core::CameraDriver;
//! use vision_driver_sim::{Sim, World};
//!
//! let sim = Sim::new(World::default_world())?;
//! let mut camera = sim.camera();
//! // The default world starts with the camera over calibration-sheet dot 1.
//! let reading = camera.trigger().expect("the simulated camera always answers");
//! assert!(reading.found());
//! # Ok::<(), vision_driver_sim::SimError>(())
//! ```

mod camera;
mod error;
mod fixture;
mod frames;
mod kept;
mod lens;
mod machine;
mod optics;
mod rng;
mod sim;
mod truth;
pub use truth::PERFECT_CENTRE_SIGMA_PX;
pub mod world;

pub use camera::SimCamera;
pub use error::SimError;
pub use fixture::TrueMark;
pub use frames::SimFrame;
pub use kept::{KeptParameter, KeptState, KeptTool, MAX_KEPT_BYTES};
pub use lens::Lens;
pub use machine::interpreter_dialect;
pub use machine::SimMachine;
pub use optics::Optics;
pub use sim::Sim;
pub use truth::CalibrationError;
/// The marks' shape in [`ImageLook`]: the finder's own type.
pub use vision_locate::MarkKind;
pub use world::{
    CameraMount, ControllerName, Fixture, ImageLook, Job, MachineSetup, Tool, World, WorldUnit, DEFAULT_WORLD_TOML,
};
