//! The Vision module of a CNC control: parameters, alignment runs (M280–M282), calibration
//! (M283), job switching (M284), pound variables, and the traits a host implements:
//! [`CameraDriver`] for the camera and (later) `Machine` for the CNC.
//!
//! ```
//! use vision_core::{Judgment, Reading};
//! let r = Reading::position(888.0, 888.0);
//! assert_eq!(r.judgment, Judgment::Unknown);
//! assert!(r.found());
//! ```

pub mod driver;

pub use driver::{CameraDriver, Capabilities, DriverError, DriverErrorKind, Judgment, Reading};
