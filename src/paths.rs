//! Guards on output paths: an output's folder exists before the work
//! starts, an output never replaces an input, and two outputs of one
//! command never share a file.

use anyhow::{bail, Result};
use std::path::{Path, PathBuf};

/// Fail when an input that exists is not a regular file, when the folder of
/// `out` does not exist, so that a command stops before its work rather
/// than after it, or when `out` names the same file
/// as one of `inputs` (after resolving links and relative paths), so that a
/// command can never overwrite its input.
///
/// The files an input brings in (a glTF file's buffers and images, an OBJ
/// file's material libraries and textures) count as inputs, and an OBJ
/// output's material library `<stem>.mtl`, written beside it, as an output.
pub fn ensure_output(out: &Path, inputs: &[&Path]) -> Result<()> {
    ensure_outputs(&[out], inputs)
}

/// [`ensure_output`] for each of `outs` (the frames of an animation, say),
/// the files the inputs bring in found once.
pub fn ensure_outputs(outs: &[&Path], inputs: &[&Path]) -> Result<()> {
    // An input that is a device or a pipe would be read without end or wait
    // for a writer; refuse it before any work.
    for input in inputs {
        if let Ok(m) = std::fs::metadata(input) {
            if !m.is_file() {
                bail!("{}: {}", input.display(), raykit_io::not_a_regular_file(&m));
            }
        }
    }
    let mut brought: Option<Vec<(PathBuf, &Path)>> = None;
    for out in outs {
        ensure_folder(out)?;
        if out.is_dir() {
            bail!("cannot write {}: it is a folder", out.display());
        }
        // An OBJ (compressed or not) may bring its material library.
        let plain = match out.extension() {
            Some(e) if e.eq_ignore_ascii_case("gz") => out.with_extension(""),
            _ => out.to_path_buf(),
        };
        let is_obj = plain
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
        let library = is_obj.then(|| plain.with_extension("mtl"));
        for written in std::iter::once(*out).chain(library.as_deref()) {
            let Ok(real) = written.canonicalize() else {
                continue; // the file does not exist yet
            };
            if inputs
                .iter()
                .any(|input| input.canonicalize().is_ok_and(|i| i == real))
            {
                bail!(
                    "refusing to write {}: it is also an input of this command",
                    written.display()
                );
            }
            let brought = brought.get_or_insert_with(|| {
                let files = inputs.iter().flat_map(|&i| {
                    raykit_io::companion_files(i)
                        .into_iter()
                        .map(move |f| (f, i))
                });
                files
                    .filter_map(|(f, i)| Some((f.canonicalize().ok()?, i)))
                    .collect()
            });
            if let Some((_, input)) = brought.iter().find(|(f, _)| *f == real) {
                bail!(
                    "refusing to write {}: {} reads it",
                    written.display(),
                    input.display()
                );
            }
        }
    }
    Ok(())
}

/// Fail unless `path` (given with the flag `flag`) ends in one of
/// `extensions` (lower case, without the dot; any case matches): a file's
/// name says its format, so one whose name says otherwise is not written.
pub fn ensure_extension(path: &Path, flag: &str, extensions: &[&str]) -> Result<()> {
    let ok = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| extensions.iter().any(|x| e.eq_ignore_ascii_case(x)));
    if !ok {
        let names: Vec<String> = extensions.iter().map(|e| format!(".{e}")).collect();
        bail!(
            "{}: {flag} must end in {}",
            path.display(),
            names.join(" or ")
        );
    }
    Ok(())
}

/// The folder a file at `path` lies in (`.` for a bare name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// The file `path` names, with links and relative parts resolved as far as
/// it or its folder exists.
fn resolved(path: &Path) -> PathBuf {
    if let Ok(real) = path.canonicalize() {
        return real;
    }
    match (folder_of(path).canonicalize(), path.file_name()) {
        (Ok(dir), Some(name)) => dir.join(name),
        _ => path.to_path_buf(),
    }
}

/// Fail when two outputs of one command (`what_a` and `what_b`, named as
/// their flags) would be written to the same file, where one would
/// silently replace the other.
pub fn ensure_distinct(a: &Path, b: &Path, what_a: &str, what_b: &str) -> Result<()> {
    if resolved(a) == resolved(b) {
        bail!(
            "{what_a} {} and {what_b} {} name the same file: give {what_b} another path",
            a.display(),
            b.display()
        );
    }
    Ok(())
}

/// Fail when the folder `path` would be written into does not exist or
/// does not take new files (read-only, or a file system such as /proc):
/// the outputs are written as new files there and renamed, so a command
/// with several outputs learns before its work, not after its first
/// output, that one cannot be written.
fn ensure_folder(path: &Path) -> Result<()> {
    let folder = folder_of(path);
    if !folder.is_dir() {
        let why = if folder.exists() {
            format!("{} is not a folder", folder.display())
        } else {
            format!("the folder {} does not exist", folder.display())
        };
        bail!("cannot write {}: {why}", path.display());
    }
    let probe = folder.join(format!(".raykit-probe.{}", std::process::id()));
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
        }
        // A probe left by an earlier run of this process id: the folder
        // takes files.
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
        Err(e) => bail!(
            "cannot write {}: the folder {} does not take new files ({e})",
            path.display(),
            folder.display()
        ),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_that_takes_no_files_is_named() {
        let e = ensure_output(Path::new("/proc/m.tif"), &[])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("/proc") && e.contains("does not take new files"),
            "{e}"
        );
    }

    #[test]
    fn a_missing_folder_is_named() {
        let dir = tempfile::tempdir().unwrap();
        assert!(ensure_output(&dir.path().join("m.tif"), &[]).is_ok());
        assert!(ensure_output(Path::new("m.tif"), &[]).is_ok());
        let missing = dir.path().join("nowhere").join("m.png");
        let e = ensure_output(&missing, &[]).unwrap_err().to_string();
        assert!(e.contains("m.png") && e.contains("nowhere"), "{e}");
    }

    #[test]
    fn two_outputs_naming_one_file_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("m.png");
        let via_dot = dir.path().join(".").join("m.png");
        assert!(ensure_distinct(&a, &via_dot, "--out", "--preview").is_err());
        assert!(ensure_distinct(&a, &dir.path().join("m.tif"), "--out", "--preview").is_ok());
        // Existing files, and a path through a link to the folder.
        std::fs::write(&a, b"x").unwrap();
        assert!(ensure_distinct(&a, &via_dot, "--out", "--preview").is_err());
        #[cfg(unix)]
        {
            let link = dir.path().join("link");
            std::os::unix::fs::symlink(dir.path(), &link).unwrap();
            assert!(ensure_distinct(&a, &link.join("m.png"), "--out", "--preview").is_err());
        }
    }

    #[test]
    fn files_an_input_reads_are_not_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let gltf = d.join("s.gltf");
        std::fs::write(
            &gltf,
            br#"{"asset":{"version":"2.0"},"buffers":[{"uri":"s.bin","byteLength":4}]}"#,
        )
        .unwrap();
        std::fs::write(d.join("s.bin"), b"abcd").unwrap();
        let e = ensure_output(&d.join("s.bin"), &[&gltf])
            .unwrap_err()
            .to_string();
        assert!(e.contains("s.bin") && e.contains("s.gltf reads it"), "{e}");
        assert!(ensure_output(&d.join("t.bin"), &[&gltf]).is_ok());

        // An OBJ output's material library must not replace an input's.
        let obj = d.join("in.obj");
        std::fs::write(&obj, b"mtllib out.mtl\n").unwrap();
        std::fs::write(d.join("out.mtl"), b"newmtl a\n").unwrap();
        let e = ensure_output(&d.join("out.obj"), &[&obj])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("out.mtl") && e.contains("in.obj reads it"),
            "{e}"
        );
        assert!(ensure_output(&d.join("other.obj"), &[&obj]).is_ok());
    }

    #[test]
    fn same_file_through_another_path_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.bin");
        std::fs::write(&a, b"x").unwrap();
        let same = dir.path().join(".").join("a.bin");
        assert!(ensure_output(&same, &[&a]).is_err());
        assert!(ensure_output(&dir.path().join("b.bin"), &[&a]).is_ok());
        std::fs::write(dir.path().join("b.bin"), b"y").unwrap();
        assert!(ensure_output(&dir.path().join("b.bin"), &[&a]).is_ok());
    }
}
