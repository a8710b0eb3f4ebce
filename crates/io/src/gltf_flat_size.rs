//! The size of a glTF scene once flattened into one triangle mesh, checked
//! before any of it is copied.
//!
//! glTF stores a mesh once and places it by nodes and by the copies of
//! `EXT_mesh_gpu_instancing`, so a file of a few megabytes can place a
//! large mesh thousands of times. Flattened, such a scene can need more
//! memory than the machine has, where the process is killed rather than
//! given an error, or more vertices than 32-bit indices address. The
//! flattened load counts what it would copy from the accessors' counts and
//! refuses both cases up front, pointing at the instanced load, which
//! stores each mesh once.

use crate::error::{ErrorKind, LoadError, Location};
use crate::gltf_shared_vertices::vertex_key;
use ::gltf::mesh::Mode;
use ::gltf::Semantic;
use std::collections::HashSet;
use std::path::Path;

/// Bytes the flattened load keeps per vertex: position, normal and texture
/// coordinate.
const BYTES_PER_VERTEX: u64 = 12 + 12 + 8;
/// Bytes the flattened load keeps per triangle: three indices, a material
/// and a part.
const BYTES_PER_TRIANGLE: u64 = 12 + 4 + 4;

/// Vertices and triangles of a mesh, or of a scene's placements of meshes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct FlatSize {
    /// Vertices copied (every placement copies its mesh's vertices).
    pub vertices: u64,
    /// Triangles copied.
    pub triangles: u64,
}

impl FlatSize {
    /// What one placement of `mesh` adds: its primitives of the triangle
    /// modes that have positions, counted as the loader reads them (a list
    /// gives a triangle per three indices, a strip or fan one per index
    /// after the second; without indices the vertices are the indices;
    /// primitives that share their vertex arrays share their vertices,
    /// [`crate::gltf_shared_vertices`]).
    pub(crate) fn of_mesh(mesh: &::gltf::Mesh<'_>) -> Self {
        let mut size = Self::default();
        let mut read = HashSet::new();
        for prim in mesh.primitives() {
            let Some(positions) = prim.get(&Semantic::Positions) else {
                continue;
            };
            let vertices = positions.count() as u64;
            let indices = prim.indices().map_or(vertices, |a| a.count() as u64);
            let triangles = match prim.mode() {
                Mode::Triangles => indices / 3,
                Mode::TriangleStrip | Mode::TriangleFan => indices.saturating_sub(2),
                _ => continue,
            };
            if vertex_key(&prim).is_none_or(|key| read.insert(key)) {
                size.vertices += vertices;
            }
            size.triangles += triangles;
        }
        size
    }

    /// Add `copies` placements of a mesh of size `of`.
    pub(crate) fn add_copies(&mut self, of: Self, copies: u64) {
        self.vertices = self
            .vertices
            .saturating_add(of.vertices.saturating_mul(copies));
        self.triangles = self
            .triangles
            .saturating_add(of.triangles.saturating_mul(copies));
    }

    /// Bytes the flattened load needs for this many vertices and triangles.
    pub(crate) fn bytes(&self) -> u64 {
        self.vertices
            .saturating_mul(BYTES_PER_VERTEX)
            .saturating_add(self.triangles.saturating_mul(BYTES_PER_TRIANGLE))
    }

    /// Refuse a flattened scene of this size from `path`, placed `placements`
    /// times, when its vertices exceed 32-bit indices or its bytes exceed
    /// `available` (the memory free for it, if known).
    pub(crate) fn check(
        &self,
        path: &Path,
        placements: usize,
        available: Option<u64>,
    ) -> Result<(), LoadError> {
        let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
        let too_big = available.filter(|&a| self.bytes() > a);
        let why = match (self.vertices > u64::from(u32::MAX), too_big) {
            (true, _) => format!("more vertices than 32-bit indices address ({})", u32::MAX),
            (false, Some(a)) => format!("more than the {:.1} GiB of memory available", gib(a)),
            (false, None) => return Ok(()),
        };
        Err(LoadError::new(
            path,
            ErrorKind::Unsupported,
            Location::Json("nodes".into()),
            format!(
                "the scene places meshes {placements} times (nodes and EXT_mesh_gpu_instancing \
                 copies); flattened into one mesh it would hold {} triangles and {} vertices, \
                 about {:.1} GiB: {why}. Load it as an instanced scene, which stores each mesh \
                 once: `raykit trace --instanced`, `raykit query count|all-hits --instanced`, or \
                 from Python `RaycastingScene.add_gltf`",
                self.triangles,
                self.vertices,
                gib(self.bytes())
            ),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The memory bound refuses what exceeds it and names it; unknown
    /// memory bounds nothing but the index range.
    #[test]
    fn the_memory_bound_refuses_what_exceeds_it() {
        let size = FlatSize {
            vertices: 1 << 20,
            triangles: 2 << 20,
        };
        let path = Path::new("scene.glb");
        let need = size.bytes();
        assert_eq!(
            need,
            (1 << 20) * BYTES_PER_VERTEX + (2 << 20) * BYTES_PER_TRIANGLE
        );
        assert!(size.check(path, 7, Some(need)).is_ok());
        assert!(size.check(path, 7, None).is_ok());
        let e = size.check(path, 7, Some(need - 1)).unwrap_err().to_string();
        assert!(
            e.contains("memory available") && e.contains("7 times"),
            "{e}"
        );
        let huge = FlatSize {
            vertices: u64::from(u32::MAX) + 1,
            triangles: 1,
        };
        let e = huge.check(path, 1, None).unwrap_err().to_string();
        assert!(e.contains("32-bit indices"), "{e}");
    }
}
