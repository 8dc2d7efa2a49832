//! What several of the test modules share.

use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Runs the binary with `args` under an address-space limit of `megabytes`, killed after
/// `seconds`: its output, or `None` when it ran out of time (it blocked). Standard input is
/// empty, so nothing waits on the terminal.
pub(crate) fn bounded(args: &[&str], megabytes: u64, seconds: u64) -> Option<Output> {
    let script = format!("ulimit -v {} && exec \"$0\" \"$@\"", megabytes * 1024);
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(script)
        .arg(env!("CARGO_BIN_EXE_mach-vision"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("sh");
    let deadline = Instant::now() + Duration::from_secs(seconds);
    while Instant::now() < deadline {
        if child.try_wait().expect("wait").is_some() {
            return Some(child.wait_with_output().expect("output"));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    let _ = child.wait();
    None
}

/// A fresh scratch folder `mach-vision-MODULE-NAME-PID` under the system's temp folder: the
/// test module's, for this test process.
pub(crate) fn scratch(module: &str, name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("mach-vision-{module}-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch dir");
    d
}
