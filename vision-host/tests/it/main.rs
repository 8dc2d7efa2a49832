//! vision-host's integration tests as one test binary, a module per subject: each file under
//! `tests/` is one more binary to compile and link.

mod linuxcnc;
mod panel;
mod program;
mod recentre;
mod session;
mod shared_profile;
