//! `--scene` / `--mesh` arguments: a mesh file or `builtin:NAME[:key=value,...]`.

use anyhow::{Context, Result};
use raykit_scene::Scene;
use std::path::Path;

/// Prefix that selects a built-in scene.
pub const BUILTIN: &str = "builtin:";

/// Load the scene named by `spec`: a built-in scene or a mesh file (a file
/// gives a scene with no lights and no camera; the commands add defaults).
pub fn load(spec: &str) -> Result<Scene> {
    if let Some(rest) = spec.strip_prefix(BUILTIN) {
        return raykit_scene::builtin(rest).with_context(|| format!("scene '{spec}'"));
    }
    let path = Path::new(spec);
    let mesh = raykit_io::load_mesh(path)?;
    Ok(Scene {
        name: path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| spec.to_string()),
        mesh,
        lights: Vec::new(),
        camera: None,
    })
}
