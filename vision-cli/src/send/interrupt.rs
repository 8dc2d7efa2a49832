//! Ctrl-C while streaming: a feed hold at once (the machine brakes on its path and keeps its
//! position), then the operator's choice — resume, or a soft reset that abandons the job. With
//! no terminal to ask on, a second Ctrl-C is the reset.

use std::io::{BufRead, IsTerminal};
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::Arc;

use vision_grbl::stream::Control;

use crate::Failure;

/// Installs the handler for this process (once).
///
/// # Errors
/// [`Failure::Input`] when the handler cannot be installed.
pub(crate) fn install(control: Control, interrupted: Arc<AtomicBool>) -> Result<(), Failure> {
    let presses = AtomicU8::new(0);
    ctrlc::set_handler(move || {
        let press = presses.fetch_add(1, Ordering::SeqCst).saturating_add(1);
        if press == 1 || !std::io::stdin().is_terminal() {
            let _ = control.feed_hold();
        }
        if std::io::stdin().is_terminal() {
            eprintln!("\nmach-vision: feed hold — the machine stops on its path. Resume (r) or soft-reset and abandon the job (x)?");
            let mut answer = String::new();
            let _ = std::io::stdin().lock().read_line(&mut answer);
            if answer.trim().eq_ignore_ascii_case("x") {
                interrupted.store(true, Ordering::SeqCst);
                let _ = control.soft_reset();
            } else {
                presses.store(0, Ordering::SeqCst);
                let _ = control.resume();
            }
        } else if press == 1 {
            eprintln!("mach-vision: feed hold — the machine stops on its path; Ctrl-C again soft-resets the controller and abandons the job");
        } else {
            eprintln!("mach-vision: soft reset — the job is abandoned");
            interrupted.store(true, Ordering::SeqCst);
            let _ = control.soft_reset();
        }
    })
    .map_err(|e| Failure::Input(format!("cannot watch for Ctrl-C: {e}")))
}
