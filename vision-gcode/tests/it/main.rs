//! vision-gcode's integration tests as one test binary, a module per subject: each file under
//! `tests/` is one more binary to compile and link. The allocation-counting tests stay a binary of
//! their own, since a global allocator is per binary.

mod common;

mod chain_props;
mod comment_props;
mod expr_props;
mod flow;
mod fuzz;
mod handler;
mod interpreter;
mod linuxcnc;
mod peck_units;
mod ranges;
mod seed002;
mod vision_programs;
