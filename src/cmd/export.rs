//! `raykit export`: write a scene — a built-in one or any loadable file —
//! as glTF 2.0 with its materials, camera and lights, ready for `raykit
//! render` or any glTF viewer.

use anyhow::{bail, Context, Result};
use clap::Args;
use raykit_lab::args::scene_arg;
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `raykit export`.
#[derive(Args)]
#[command(
    after_help = "Examples:\n  raykit export --scene builtin:whitted --out whitted.gltf\n  \
raykit export --scene bunny.obj --out bunny.glb\n\n\
A scene without a camera or lights is written without them. Texture images are not written: \
materials keep their colour factors and the mesh its texture coordinates, and the export says \
how many textures it left out."
)]
pub struct ExportArgs {
    /// Scene: builtin:NAME[:key=value,...] (`raykit info scenes`) or a mesh file.
    #[arg(long)]
    scene: String,
    /// Output: `.gltf` (JSON with an embedded buffer) or `.glb`.
    #[arg(long)]
    out: PathBuf,
}

/// Load the scene and write it.
pub fn run(args: ExportArgs) -> Result<ExitCode> {
    let binary = match args.out.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("glb") => true,
        Some(e) if e.eq_ignore_ascii_case("gltf") => false,
        _ => bail!(
            "{}: the output must end in .gltf or .glb",
            args.out.display()
        ),
    };
    crate::paths::ensure_output(&args.out, &[std::path::Path::new(&args.scene)])?;
    let scene = scene_arg::load(&args.scene)?;
    raykit_io::write_atomic(&args.out, |w| {
        raykit_io::write_gltf_scene(w, &scene.mesh, scene.camera.as_ref(), &scene.lights, binary)
    })
    .with_context(|| format!("cannot write {}", args.out.display()))?;
    let textured = scene
        .mesh
        .materials
        .iter()
        .filter(|m| m.base_texture.is_some() || m.diffuse_texture.is_some())
        .count();
    if textured > 0 {
        eprintln!(
            "raykit: warning: {textured} of {} materials have a base-colour texture, which \
             {} does not hold (export writes no images): they keep their colour factors only",
            scene.mesh.materials.len(),
            args.out.display()
        );
    }
    eprintln!(
        "{}: {} triangles, {} materials, {} lights, {} -> {}",
        scene.name,
        scene.mesh.num_triangles(),
        scene.mesh.materials.len(),
        scene.lights.len(),
        if scene.camera.is_some() {
            "a camera"
        } else {
            "no camera"
        },
        args.out.display()
    );
    Ok(ExitCode::SUCCESS)
}
