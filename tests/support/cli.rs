//! Running the `raykit` binary from the command-line tests.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

/// Run `raykit ARGS` and collect its output.
pub fn raykit(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raykit"))
        .args(args)
        .output()
        .expect("the raykit binary runs")
}

/// A path as a command-line argument.
pub fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 temp path")
}

/// Captured output as text.
pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}
