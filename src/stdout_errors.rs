//! A standard output that cannot be written (a full disk, a closed pipe)
//! ends the command with an error naming it, not a panic.
//!
//! `println!` panics when its write fails ("failed printing to stdout").
//! Tables, reports and listings go through it in many places, so the
//! failure is caught where every panic goes: a panic hook that recognises
//! it, removes the temporary files of outputs still being written (those
//! finished are already in place), says what failed and exits with status
//! 1. Every other panic keeps the default report.

use std::io::Write;

/// Install the hook; call once, first thing in `main`.
pub fn install() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let message = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("");
        match message.strip_prefix("failed printing to stdout: ") {
            Some(cause) => {
                let _unfinished = raykit_io::remove_unfinished_outputs();
                // Not eprintln!: with stderr closed too it would panic again.
                let _ = writeln!(std::io::stderr(), "raykit: error: stdout: {cause}");
                std::process::exit(1);
            }
            None => default(info),
        }
    }));
}
