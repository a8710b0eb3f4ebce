//! What a refit found, and why one was refused.

use std::fmt;

/// The SAH degradation past which [`WideBvh::refit_or_rebuild`](super::WideBvh::refit_or_rebuild) rebuilds
/// when given no other limit: 1.5, the refit tree costing 50% more than
/// the built one. The SAH cost estimates the traversal work per ray, so
/// past it rays may trace up to 1.5× slower; a rebuild costs about ten
/// refits on the full dragon (BENCHMARKS.md), which such a slowdown repays
/// once the rays traced per deformation take about two rebuilds' time. A
/// caller tracing few rays per deformation can pass 2 (common in practice).
pub const DEFAULT_MAX_DEGRADATION: f64 = 1.5;

/// What a refit found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefitReport {
    /// SAH cost (`stored_sah`) of the tree as built (or loaded).
    pub built_sah: f64,
    /// SAH cost of the refit tree, or of the rebuilt one when `rebuilt`.
    pub sah: f64,
    /// SAH cost of the refit tree before any rebuild.
    pub refit_sah: f64,
    /// Whether [`WideBvh::refit_or_rebuild`](super::WideBvh::refit_or_rebuild) rebuilt the tree.
    pub rebuilt: bool,
}

impl RefitReport {
    /// How much worse the refit tree is than the tree as built:
    /// `refit_sah / built_sah` (1 when the mesh moved rigidly).
    pub fn degradation(&self) -> f64 {
        self.refit_sah / self.built_sah
    }
}

/// Why a mesh cannot refit a tree: it is not the mesh the tree was built
/// over with moved vertices.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RefitError {
    /// The mesh has another number of triangles.
    TriangleCount {
        /// Triangles in the tree.
        tree: usize,
        /// Triangles in the mesh.
        mesh: usize,
    },
    /// A triangle names a vertex the mesh does not have.
    VertexIndex {
        /// The triangle.
        triangle: usize,
        /// The vertex index it holds.
        index: u32,
        /// Vertices in the mesh.
        vertices: usize,
    },
    /// The structure has no refit (only the wide BVHs do).
    Unsupported,
}

impl fmt::Display for RefitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RefitError::TriangleCount { tree, mesh } => write!(
                f,
                "refit: the tree holds {tree} triangles, the mesh {mesh}: not the same mesh"
            ),
            RefitError::VertexIndex {
                triangle,
                index,
                vertices,
            } => write!(
                f,
                "refit: triangle {triangle} names vertex {index}, the mesh has {vertices}"
            ),
            RefitError::Unsupported => write!(
                f,
                "refit: this structure cannot be refit (bvh4 and bvh8 can); build it again"
            ),
        }
    }
}

impl std::error::Error for RefitError {}
