//! glTF 2.0 output of meshes stored once and placed by nodes: each mesh one
//! glTF mesh in its own coordinates (one primitive per run of triangles with
//! the same material), each placement one node with its transform as a
//! matrix, so that a mesh drawn many times (an assembly's repeated bolt) is
//! written once, as the file it came from stored it. The transforms are
//! written in `f64`, so that a model placed far from the origin keeps its
//! digits. The materials of all meshes are written one after another; a
//! camera and lights as [`super::write_gltf_scene`] writes them.

use super::gltf::{document, material_runs, Buffers};
use super::gltf_scene::scene_extras;
use super::json::json_string;
use raykit_core::glam::{DAffine3, DMat4, DVec3};
use raykit_core::{Aabb, Camera, Light, TriangleMesh};
use std::io::{self, Write};

/// One node of [`write_gltf_placed`]: mesh `mesh` placed by `to_world`.
#[derive(Clone, Debug, PartialEq)]
pub struct PlacedMesh {
    /// Index into the meshes written.
    pub mesh: usize,
    /// The node's transform, from the mesh's coordinates to the scene's.
    pub to_world: DAffine3,
    /// The node's name (none written when empty).
    pub name: String,
}

/// Write `meshes`, each once, one node per entry of `nodes`, and the
/// `camera` and `lights` (in the scene's coordinates), as GLB (`binary`) or
/// `.gltf`. Meshes no node places are written all the same;
/// a node naming a mesh that is not there, a transform that is not finite
/// or an invalid mesh (one without triangles among them) is refused.
pub fn write_gltf_placed(
    w: &mut dyn Write,
    meshes: &[TriangleMesh],
    nodes: &[PlacedMesh],
    camera: Option<&Camera>,
    lights: &[Light],
    binary: bool,
) -> io::Result<()> {
    let invalid = |msg: String| io::Error::new(io::ErrorKind::InvalidInput, msg);
    for (k, m) in meshes.iter().enumerate() {
        super::check(m).map_err(|e| invalid(format!("mesh {k}: {e}")))?;
    }
    let mut buf = Buffers::default();
    let mut materials = Vec::new();
    let mut mesh_json = Vec::with_capacity(meshes.len());
    for m in meshes {
        let offset = materials.len();
        materials.extend(m.materials.iter().cloned());
        let all: Vec<usize> = (0..m.num_triangles()).collect();
        let runs = material_runs(m, &all)
            .into_iter()
            .map(|(material, run)| (material.map(|i| i + offset), run))
            .collect();
        let prim = buf.primitive(
            &m.positions,
            m.normals.as_deref(),
            m.uvs.as_deref(),
            &m.indices,
            runs,
        );
        let name = m
            .parts
            .first()
            .map(|p| p.name.as_str())
            .filter(|n| !n.is_empty())
            .map(|n| format!(r#","name":{}"#, json_string(n)))
            .unwrap_or_default();
        mesh_json.push(format!(r#"{{"primitives":[{prim}]{name}}}"#));
    }
    let mut node_json = Vec::with_capacity(nodes.len());
    for (k, n) in nodes.iter().enumerate() {
        if n.mesh >= meshes.len() {
            return Err(invalid(format!(
                "node {k} places mesh {}, but there are {} meshes",
                n.mesh,
                meshes.len()
            )));
        }
        let cols = DMat4::from(n.to_world).to_cols_array();
        if !cols.iter().all(|x| x.is_finite()) {
            return Err(invalid(format!("node {k}: the transform is not finite")));
        }
        let name = if n.name.is_empty() {
            String::new()
        } else {
            format!(r#","name":{}"#, json_string(&n.name))
        };
        let matrix = if n.to_world == DAffine3::IDENTITY {
            String::new()
        } else {
            let c: Vec<String> = cols.iter().map(|x| format!("{x}")).collect();
            format!(r#","matrix":[{}]"#, c.join(","))
        };
        node_json.push(format!(r#"{{"mesh":{}{matrix}{name}}}"#, n.mesh));
    }
    let extras = scene_extras(
        &materials,
        camera.map(|c| (c, placed_bounds(meshes, nodes))),
        lights,
        &mut node_json,
    );
    let roots: Vec<usize> = (0..node_json.len()).collect();
    document(w, buf, &extras, &roots, &node_json, &mesh_json, binary)
}

/// The scene's bounds: each node's mesh's box corners carried by its
/// transform.
fn placed_bounds(meshes: &[TriangleMesh], nodes: &[PlacedMesh]) -> Aabb {
    let mut b = Aabb::EMPTY;
    for n in nodes {
        let m = meshes[n.mesh].bounds();
        for k in 0..8 {
            let corner = DVec3::new(
                if k & 1 == 0 { m.min.x } else { m.max.x } as f64,
                if k & 2 == 0 { m.min.y } else { m.max.y } as f64,
                if k & 4 == 0 { m.min.z } else { m.max.z } as f64,
            );
            b = b.grow(n.to_world.transform_point3(corner).as_vec3());
        }
    }
    b
}
