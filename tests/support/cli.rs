//! Running the `raykit` binary from the command-line tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
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

/// A file of the test data: `data/` in the repository, or the folder
/// `RAYKIT_SHARED_DATA` names; fails naming the path when it is missing.
pub fn data(rel: &str) -> PathBuf {
    let dir = std::env::var_os("RAYKIT_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data"));
    let p = dir.join(rel);
    assert!(
        p.is_file(),
        "test data not found at {} (set RAYKIT_SHARED_DATA)",
        p.display()
    );
    p
}
