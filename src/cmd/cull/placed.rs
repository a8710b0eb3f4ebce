//! A culled glTF assembly written with its instancing: each glTF mesh that
//! several nodes place (an assembly's repeated screw) is written once for
//! all the nodes that keep the same triangles of it, in the mesh's own
//! coordinates, and every kept node keeps its transform. The flattened mesh
//! that culling works on walks the same nodes in the same order
//! ([`raykit_io::load_gltf_instances`]), so its part `i` is instance `i` and
//! the part's triangles are the instance's mesh's, in order.

use raykit_core::TriangleMesh;
use raykit_io::{GltfInstances, PlacedMesh};
use std::collections::HashMap;

/// Each instance's triangles of `keep` (the flattened mesh's mask), as a
/// mask over its mesh's triangles.
fn instance_masks(scene: &GltfInstances, mesh: &TriangleMesh, keep: &[bool]) -> Vec<Vec<bool>> {
    let mut masks: Vec<Vec<bool>> = scene
        .instances
        .iter()
        .map(|i| Vec::with_capacity(scene.geometries[i.geometry as usize].num_triangles()))
        .collect();
    for t in 0..mesh.num_triangles() {
        masks[mesh.part_of(t) as usize].push(keep[t]);
    }
    masks
}

/// `keep` grown so that every instance of a mesh keeps what any of them
/// keeps (the union over a mesh's instances that keep anything), so that
/// each mesh is written once; instances that keep nothing stay removed.
pub(super) fn shared_keep(scene: &GltfInstances, mesh: &TriangleMesh, keep: &[bool]) -> Vec<bool> {
    let masks = instance_masks(scene, mesh, keep);
    let mut union: Vec<Vec<bool>> = scene
        .geometries
        .iter()
        .map(|g| vec![false; g.num_triangles()])
        .collect();
    for (i, m) in scene.instances.iter().zip(&masks) {
        for (u, &k) in union[i.geometry as usize].iter_mut().zip(m) {
            *u |= k;
        }
    }
    let any: Vec<bool> = masks.iter().map(|m| m.contains(&true)).collect();
    let mut out = Vec::with_capacity(keep.len());
    let mut next = vec![0usize; scene.instances.len()];
    for t in 0..mesh.num_triangles() {
        let part = mesh.part_of(t) as usize;
        let g = scene.instances[part].geometry as usize;
        out.push(any[part] && union[g][next[part]]);
        next[part] += 1;
    }
    out
}

/// The meshes to write and the nodes placing them: one mesh per distinct
/// (glTF mesh, kept triangles) among the instances that keep any, holding
/// those triangles in the mesh's coordinates; one node per such instance,
/// in the input's order.
pub(super) fn placed_meshes(
    scene: &GltfInstances,
    mesh: &TriangleMesh,
    keep: &[bool],
) -> (Vec<TriangleMesh>, Vec<PlacedMesh>) {
    let masks = instance_masks(scene, mesh, keep);
    let mut index: HashMap<(u32, &[bool]), usize> = HashMap::new();
    let mut meshes = Vec::new();
    let mut nodes = Vec::new();
    for (i, m) in scene.instances.iter().zip(&masks) {
        if !m.contains(&true) {
            continue;
        }
        let k = *index.entry((i.geometry, m.as_slice())).or_insert_with(|| {
            meshes.push(scene.geometries[i.geometry as usize].retain_triangles(m));
            meshes.len() - 1
        });
        nodes.push(PlacedMesh {
            mesh: k,
            to_world: i.to_world_f64,
            name: i.name.clone(),
        });
    }
    (meshes, nodes)
}
