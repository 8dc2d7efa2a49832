//! The panel folder: what a controller's session publishes for `mach-vision panel --profile P`
//! to show, without any server in the controller's process.
//!
//! For profile `P.toml` the folder is `P.panel/` beside it ([`panel_dir`]), holding
//! `state.json` ([`PanelState`]: parameters, telemetry, the last call, the run's captures, the
//! calibrations seen, a time and a sequence number) and `frame.png` (the last image M281 D1
//! kept: a PNG as it is, a JPEG or BMP re-encoded, [`frame_png`]). Both are replaced
//! atomically. [`Publisher`] writes them off the controller's thread; [`read`] reads the state
//! back with typed errors.

mod publisher;
mod state;

pub use publisher::{frame_png, Publisher, MAX_DOTS, MAX_FRAME_SIDE, SETTLE};
pub use state::{
    panel_dir, parse, read, LastCall, PanelCalibration, PanelDot, PanelReadError, PanelState, PanelUnit, PanelValue,
    CALIBRATION_PARAMS, FORMAT, FRAME_FILE, MAX_CALIBRATIONS, MAX_STATE_BYTES, STATE_FILE,
};
