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
A scene without a camera or lights is written without them. A glTF or GLB file keeps its \
instancing: each mesh is written once, and each node that places it with its transform. Texture \
images are not written: materials keep their colour factors and the mesh its texture \
coordinates, and the export says how many textures it left out."
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
    let placed = placed_scene(&args.scene, &scene.mesh)?;
    raykit_io::write_atomic(&args.out, |w| match &placed {
        Some((meshes, nodes)) => raykit_io::write_gltf_placed(
            w,
            meshes,
            nodes,
            scene.camera.as_ref(),
            &scene.lights,
            binary,
        ),
        None => raykit_io::write_gltf_scene(
            w,
            &scene.mesh,
            scene.camera.as_ref(),
            &scene.lights,
            binary,
        ),
    })
    .with_context(|| format!("cannot write {}", args.out.display()))?;
    if let Some((meshes, nodes)) = &placed {
        eprintln!(
            "{}: instancing kept: {} nodes placing {} meshes",
            args.scene,
            nodes.len(),
            meshes.len()
        );
    }
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

/// A glTF or GLB file's meshes, each once, and the nodes placing them, when
/// `spec` names such a file whose flattened load is `flat`
/// ([`raykit_io::load_gltf_instances_of`]); `None` for a built-in scene or
/// another format, which are written flattened.
fn placed_scene(
    spec: &str,
    flat: &raykit_core::TriangleMesh,
) -> Result<Option<(Vec<raykit_core::TriangleMesh>, Vec<raykit_io::PlacedMesh>)>> {
    let Some(scene) = raykit_io::load_gltf_instances_of(std::path::Path::new(spec), flat)
        .with_context(|| format!("{spec}: reading its instancing"))?
    else {
        return Ok(None);
    };
    // Meshes without triangles (which the flattened output drops too) are
    // left out with their nodes; the others keep their order.
    let mut index = vec![None; scene.geometries.len()];
    let mut meshes = Vec::new();
    for (g, m) in scene.geometries.into_iter().enumerate() {
        if m.num_triangles() > 0 {
            index[g] = Some(meshes.len());
            meshes.push(m);
        }
    }
    let nodes = scene
        .instances
        .iter()
        .filter_map(|i| {
            index[i.geometry as usize].map(|mesh| raykit_io::PlacedMesh {
                mesh,
                to_world: i.to_world_f64,
                name: i.name.clone(),
            })
        })
        .collect();
    Ok(Some((meshes, nodes)))
}
