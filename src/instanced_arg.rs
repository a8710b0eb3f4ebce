//! Several `--mesh` arguments (or one with `--instanced`) as one instanced
//! scene: each mesh file becomes a geometry placed once where it stands; a
//! glTF file brings one geometry per glTF mesh and one instance per node
//! (its instancing kept); a built-in scene is one geometry.

use anyhow::{Context, Result};
use raykit_core::accel::BuildOptions;
use raykit_core::glam::Affine3A;
use raykit_core::instancing::{InstancedScene, SceneBuilder};
use raykit_lab::args::scene_arg;
use raykit_lab::measure::timed;
use serde_json::{json, Value};
use std::path::Path;

/// The scene built from the `--mesh` arguments, with timings and, per
/// argument, the ranges of geometry and instance ids it gave.
pub struct InstancedInput {
    /// The scene.
    pub scene: InstancedScene,
    /// Seconds spent reading files.
    pub load_s: f64,
    /// Seconds spent building the BVHs (bottom and top levels).
    pub build_s: f64,
    /// Per `--mesh`: `{"mesh", "geometries": [first, count], "instances":
    /// [first, count]}` for the JSON line.
    pub inputs: Vec<Value>,
}

/// Whether `spec` names a glTF or GLB file.
fn is_gltf(spec: &str) -> bool {
    let lower = spec.to_ascii_lowercase();
    lower.ends_with(".gltf") || lower.ends_with(".glb")
}

/// Load every `--mesh` into one scene and build it with `options` on the
/// current rayon pool.
pub fn load(specs: &[String], options: &BuildOptions) -> Result<InstancedInput> {
    let mut builder = SceneBuilder::new();
    let mut inputs = Vec::new();
    let mut load_s = 0.0;
    for spec in specs {
        let (g0, i0) = (builder.num_geometries(), builder.num_instances());
        if is_gltf(spec) && !spec.starts_with(scene_arg::BUILTIN) {
            let path = Path::new(spec);
            let (loaded, s) = timed(|| raykit_io::load_gltf_instances(path));
            load_s += s;
            let loaded = loaded?;
            for w in &loaded.warnings {
                eprintln!("warning: {}: {w}", path.display());
            }
            let (_, left_out) = loaded.add_to(&mut builder)?;
            for w in left_out {
                eprintln!("warning: {w}");
            }
        } else {
            let (scene, s) = timed(|| scene_arg::load(spec));
            load_s += s;
            let g = builder
                .add_geometry(scene?.mesh)
                .with_context(|| format!("--mesh {spec}"))?;
            builder.add_named_instance(spec, g, Affine3A::IDENTITY)?;
        }
        inputs.push(json!({
            "mesh": spec,
            "geometries": [g0, builder.num_geometries() - g0],
            "instances": [i0, builder.num_instances() - i0],
        }));
    }
    let (scene, build_s) = timed(|| builder.build(options));
    Ok(InstancedInput {
        scene,
        load_s,
        build_s,
        inputs,
    })
}

/// The scene's size figures and inputs for a command's JSON line.
pub fn stats_json(input: &InstancedInput) -> Value {
    let s = input.scene.stats();
    json!({
        "geometries": s.geometries,
        "instances": s.instances,
        "stored_triangles": s.stored_triangles,
        "instanced_triangles": s.instanced_triangles,
        "scene_bytes": s.bytes,
        "inputs": input.inputs,
    })
}
