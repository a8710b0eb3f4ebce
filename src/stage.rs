//! A spinner on stderr naming the stage a long command is in, with the time
//! it has run; drawn only when stderr is a terminal.

use indicatif::{ProgressBar, ProgressFinish, ProgressStyle};
use std::time::Duration;

/// A ticking spinner showing `message`; change it with `set_message`. It is
/// removed when dropped (so an error stops it) or by `finish_and_clear`.
pub fn spinner(message: String) -> ProgressBar {
    let bar = ProgressBar::new_spinner()
        .with_style(
            ProgressStyle::with_template("{spinner} {msg} [{elapsed}]").expect("valid template"),
        )
        .with_finish(ProgressFinish::AndClear);
    bar.set_message(message);
    bar.enable_steady_tick(Duration::from_millis(100));
    bar
}
