//! `--scene` / `--mesh` arguments: a mesh file or `builtin:NAME[:key=value,...]`.

use anyhow::{Context, Result};
use raykit_core::glam::DVec3;
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
    load_with(spec, raykit_io::load).map(|(scene, _)| scene)
}

/// [`load`], with a mesh file far from its coordinates' origin read in
/// `f64` and stored relative to a point near it
/// ([`raykit_io::load_keeping_precision`]): the scene and that point.
/// What renders a picture uses it: in `f32`, a model 5·10⁶ from the origin
/// (UTM coordinates) is stored in steps of 0.5.
pub fn load_keeping_precision(spec: &str) -> Result<(Scene, DVec3)> {
    load_with(spec, raykit_io::load_keeping_precision)
}

fn load_with(
    spec: &str,
    read: fn(&Path) -> Result<raykit_io::LoadedMesh, raykit_io::LoadError>,
) -> Result<(Scene, DVec3)> {
    if let Some(rest) = spec.strip_prefix(BUILTIN) {
        let scene = raykit_scene::builtin(rest).with_context(|| format!("scene '{spec}'"))?;
        return Ok((scene, DVec3::ZERO));
    }
    let path = Path::new(spec);
    let loaded = read(path)?;
    for w in &loaded.warnings {
        eprintln!("warning: {}: {w}", path.display());
    }
    let scene = Scene {
        name: path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| spec.to_string()),
        mesh: loaded.mesh,
        lights: loaded.lights,
        camera: loaded.camera,
    };
    Ok((scene, DVec3::from_array(loaded.origin)))
}

/// The loader `raykit serve` uses for `--scene` and `POST /api/scene`:
/// [`load`].
pub fn loader() -> raykit_serve::SceneLoader {
    Arc::new(|spec: &str| load(spec))
}
