//! The `mach-vision` binary as its users meet it. Its integration tests as one test binary, a
//! module per subject: each file under `tests/` is one more binary to compile and link.

mod common;

mod acceptance;
mod as_printed;
mod bad_input;
mod bounded;
mod cam_job;
mod dialect;
mod docs;
mod fit;
mod grbl;
mod hostile_input;
mod image_camera;
mod lens;
mod linuxcnc;
mod locate;
mod locate_bounds;
mod option_props;
mod panel;
mod panel_folder;
mod plan;
mod run;
mod send;
mod shared_profile;
mod sheet;
mod trace;
mod trust;
