//! Grbl-family controllers (Grbl 1.1, grblHAL) as mach-vision drives them: a streaming client
//! and an emulator.
//!
//! * [`stream`]: the sender side — a connection over TCP or a serial device, character counting
//!   within the controller's receive buffer, send-response for lines that write settings,
//!   `ok`/`error:N`/`ALARM:N`, status reports polled at 5 Hz, feed hold, resume, soft reset.
//! * [`response`]: what a Grbl controller sends, parsed into typed values.
//! * [`state`]: the offsets (`$#`), parser state (`$G`) and settings (`$$`) it prints.
//! * [`emit`]: the events of a program run in `vision_gcode` as the lines a Grbl 1.1 firmware
//!   accepts (absolute moves in its work coordinates, arcs its arc check passes).
//! * [`emulator`]: a Grbl 1.1 / grblHAL controller on loopback TCP or a pseudo-terminal, with
//!   motion timed from its acceleration and rate settings, for tests and demonstrations.

pub mod emit;
pub mod emulator;
pub mod response;
pub mod state;
pub mod stream;
