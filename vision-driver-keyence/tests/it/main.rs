//! vision-driver-keyence's integration tests as one test binary, a module per subject: each file
//! under `tests/` is one more binary to compile and link. The allocation-counting tests stay a
//! binary of their own, since a global allocator is per binary.

mod common;

mod emulator;
mod loopback;
mod settings_props;
