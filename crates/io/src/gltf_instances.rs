//! glTF with its instancing kept: one geometry per glTF mesh (all its
//! primitives, in the mesh's own coordinates) and one instance per node that
//! references a mesh (one per copy of an `EXT_mesh_gpu_instancing` node),
//! with the node's world transform, ready for an
//! [`InstancedScene`](raykit_core::instancing::InstancedScene). The flattened
//! load ([`crate::load_mesh`]) walks the same nodes in the same order, so
//! instance `i` is the flattened mesh's part `i`, and triangle `p` of its
//! geometry is the part's `p`-th triangle.

use crate::error::{ErrorKind, LoadError, Location};
use crate::gltf::{open_gltf, walk_nodes, Builder};
use crate::gltf_gpu_instancing::mesh_placements;
use raykit_core::glam::{Affine3A, DAffine3, DMat4};
use raykit_core::instancing::{SceneBuilder, SceneError};
use raykit_core::TriangleMesh;
use std::path::{Path, PathBuf};

/// One node that places a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfInstance {
    /// Index into [`GltfInstances::geometries`].
    pub geometry: u32,
    /// The node's world transform (its own composed with its parents'),
    /// rounded to `f32`.
    pub to_world: Affine3A,
    /// The same transform in `f64`, composed from the file's values: a
    /// scene placed far from the coordinates' origin (a UTM or geocentric
    /// translation) keeps its digits here, which `to_world` loses.
    pub to_world_f64: DAffine3,
    /// The node's index in the file's `nodes`.
    pub node: u32,
    /// The node's name, else its mesh's, else empty.
    pub name: String,
}

/// A glTF file's meshes, each stored once, and the nodes placing them.
#[derive(Clone, Debug)]
pub struct GltfInstances {
    /// The file read.
    pub path: PathBuf,
    /// One mesh per glTF mesh referenced by a walked node, in the order of
    /// first reference, in the mesh's own coordinates (materials per
    /// geometry).
    pub geometries: Vec<TriangleMesh>,
    /// The glTF mesh index of each geometry.
    pub mesh_index: Vec<u32>,
    /// One instance per walked node with a mesh, in the flattened load's
    /// part order.
    pub instances: Vec<GltfInstance>,
    /// Things skipped or approximated.
    pub warnings: Vec<String>,
}

/// Load the glTF or GLB file at `path` with its instancing kept.
pub fn load_gltf_instances(path: &Path) -> Result<GltfInstances, LoadError> {
    let bytes = crate::input::read_file_cause_in_message(path)?;
    parse_gltf_instances(path, &bytes)
}

/// The instancing of the file at `path` whose flattened load is `flat`, for
/// output that keeps it: `None` when `path` is not glTF or GLB, or when
/// `flat` is not that file's flattened load
/// ([`GltfInstances::matches_flattened`]).
pub fn load_gltf_instances_of(
    path: &Path,
    flat: &TriangleMesh,
) -> Result<Option<GltfInstances>, LoadError> {
    if !crate::MeshFormat::from_path(path).is_some_and(crate::MeshFormat::is_gltf) {
        return Ok(None);
    }
    let scene = load_gltf_instances(path)?;
    Ok(scene.matches_flattened(flat).then_some(scene))
}

/// [`load_gltf_instances`] on the file's bytes.
pub fn parse_gltf_instances(path: &Path, data: &[u8]) -> Result<GltfInstances, LoadError> {
    let opened = open_gltf(path, data)?;
    let doc = &opened.doc;
    let mut warnings = opened.warnings.clone();
    let mut nodes: Vec<(u32, u32, DMat4, String)> = Vec::new();
    walk_nodes(path, doc, &opened.locals, &mut |node, world| {
        if let Some(mesh) = node.mesh() {
            let name = node.name().or(mesh.name()).unwrap_or("").to_string();
            let placed = mesh_placements(path, doc, &opened.buffers, data.len(), node, world)?;
            for world in placed {
                nodes.push((
                    node.index() as u32,
                    mesh.index() as u32,
                    world,
                    name.clone(),
                ));
            }
        }
        Ok(())
    })?;
    let mut geometry_of = vec![None; doc.meshes().len()];
    let mut mesh_index = Vec::new();
    let mut geometries = Vec::new();
    let mut instances = Vec::new();
    for (node, mesh, world, name) in nodes {
        let geometry = match geometry_of[mesh as usize] {
            Some(g) => g,
            None => {
                let gltf_node = doc.nodes().nth(node as usize).expect("walked node");
                let gltf_mesh = doc.meshes().nth(mesh as usize).expect("node's mesh");
                let mut b = Builder::new(path, doc, &opened.buffers, data.len(), &mut warnings);
                b.add_instance(&gltf_node, &gltf_mesh, &DMat4::IDENTITY)?;
                let (m, _) = b.finish();
                if let Err(e) = m.validate() {
                    if !m.indices.is_empty() {
                        return Err(LoadError::at_json(
                            path,
                            format!("meshes[{mesh}]"),
                            format!("the loaded mesh is invalid: {e}"),
                        ));
                    }
                }
                let g = geometries.len() as u32;
                geometries.push(m);
                mesh_index.push(mesh);
                geometry_of[mesh as usize] = Some(g);
                g
            }
        };
        instances.push(GltfInstance {
            geometry,
            to_world: Affine3A::from_mat4(world.as_mat4()),
            to_world_f64: DAffine3::from_mat4(world),
            node,
            name,
        });
    }
    if geometries.iter().all(|g| g.indices.is_empty()) {
        return Err(LoadError::new(
            path,
            ErrorKind::Empty,
            Location::Json("scene".into()),
            "the file has no triangles (reached the end of the file)",
        ));
    }
    Ok(GltfInstances {
        path: path.to_path_buf(),
        geometries,
        mesh_index,
        instances,
        warnings,
    })
}

impl GltfInstances {
    /// Triangles stored: each geometry's once.
    pub fn stored_triangles(&self) -> usize {
        self.geometries.iter().map(|g| g.num_triangles()).sum()
    }

    /// Triangles placed in the world: what the flattened load holds.
    pub fn instanced_triangles(&self) -> usize {
        self.instances
            .iter()
            .map(|i| self.geometries[i.geometry as usize].num_triangles())
            .sum()
    }

    /// Whether `flat` is this file's flattened load as culling or export
    /// may have it: one part per instance, in order, each with as many
    /// triangles as its geometry (then triangle `p` of part `i` is triangle
    /// `p` of instance `i`'s geometry).
    pub fn matches_flattened(&self, flat: &TriangleMesh) -> bool {
        let mut per_part = vec![0usize; self.instances.len()];
        for t in 0..flat.num_triangles() {
            match per_part.get_mut(flat.part_of(t) as usize) {
                Some(n) => *n += 1,
                None => return false,
            }
        }
        self.instances
            .iter()
            .zip(&per_part)
            .all(|(i, &n)| self.geometries[i.geometry as usize].num_triangles() == n)
    }

    /// Add the geometries and instances to `builder` (geometry ids offset
    /// by the geometries it already holds); returns the id of the first
    /// geometry added. A node whose world transform is singular (a zero
    /// scale hides a node in many files) places only zero-area triangles,
    /// which no ray hits: it is left out and named in the returned warnings;
    /// one that is not finite is an error naming the node.
    pub fn add_to(&self, builder: &mut SceneBuilder) -> Result<(u32, Vec<String>), LoadError> {
        let first = builder.num_geometries() as u32;
        for g in &self.geometries {
            builder.add_geometry(g.clone()).map_err(|e| self.error(e))?;
        }
        let mut warnings = Vec::new();
        for inst in &self.instances {
            let label = format!("nodes[{}]", inst.node);
            let name = if inst.name.is_empty() {
                label.clone()
            } else {
                format!("{label} {:?}", inst.name)
            };
            match builder.add_named_instance(&name, first + inst.geometry, inst.to_world) {
                Ok(_) => {}
                Err(SceneError::BadTransform {
                    problem: problem @ raykit_core::instancing::TransformError::NotInvertible { .. },
                    ..
                }) => warnings.push(format!(
                    "{}: {name} left out of the instanced scene: {problem}",
                    self.path.display()
                )),
                Err(e) => {
                    return Err(LoadError::at_json(&self.path, label, e.to_string()));
                }
            }
        }
        Ok((first, warnings))
    }

    fn error(&self, e: SceneError) -> LoadError {
        LoadError::new(
            &self.path,
            ErrorKind::Malformed,
            Location::File,
            e.to_string(),
        )
    }
}
