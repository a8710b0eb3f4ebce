//! `--scene` / `--mesh` arguments: a mesh file or `builtin:NAME[:key=value,...]`.

use anyhow::{Context, Result};
use raykit_scene::Scene;
use std::path::Path;
use std::sync::Arc;

/// Prefix that selects a built-in scene.
pub const BUILTIN: &str = "builtin:";

/// Load the scene named by `spec`: a built-in scene or a mesh file. A glTF
/// file brings its own lights and camera (other formats give none; the
/// commands add defaults). Load warnings are printed to stderr as
/// `warning: FILE: message`.
pub fn load(spec: &str) -> Result<Scene> {
    if let Some(rest) = spec.strip_prefix(BUILTIN) {
        return raykit_scene::builtin(rest).with_context(|| format!("scene '{spec}'"));
    }
    let path = Path::new(spec);
    let loaded = raykit_io::load(path)?;
    for w in &loaded.warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
    Ok(Scene {
        name: path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| spec.to_string()),
        mesh: loaded.mesh,
        lights: loaded.lights,
        camera: loaded.camera,
    })
}

/// The loader `raykit serve` uses for `--scene` and `POST /api/scene`:
/// [`load`].
pub fn loader() -> raykit_serve::SceneLoader {
    Arc::new(|spec: &str| load(spec))
}
