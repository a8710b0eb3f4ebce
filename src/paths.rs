//! Guards on output paths: an output never replaces an input.

use anyhow::{bail, Result};
use std::path::Path;

/// Fail when `out` names the same file as one of `inputs` (after resolving
/// links and relative paths), so a command can never overwrite its input.
pub fn ensure_not_input(out: &Path, inputs: &[&Path]) -> Result<()> {
    let Ok(out_real) = out.canonicalize() else {
        return Ok(()); // the output does not exist yet
    };
    for input in inputs {
        if input.canonicalize().is_ok_and(|i| i == out_real) {
            bail!(
                "refusing to write {}: it is also an input of this command",
                out.display()
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_file_through_another_path_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.bin");
        std::fs::write(&a, b"x").unwrap();
        let same = dir.path().join(".").join("a.bin");
        assert!(ensure_not_input(&same, &[&a]).is_err());
        assert!(ensure_not_input(&dir.path().join("b.bin"), &[&a]).is_ok());
        std::fs::write(dir.path().join("b.bin"), b"y").unwrap();
        assert!(ensure_not_input(&dir.path().join("b.bin"), &[&a]).is_ok());
    }
}
