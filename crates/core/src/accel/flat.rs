//! Structures as flat arrays of 32-bit words, for devices that trace them
//! with kernels of their own (the GPU backend, `crates/gpu`).
//!
//! The arrays are exactly what the CPU traverses — the same nodes, the same
//! triangle order, the same precomputed triangle records — so a device that
//! runs the same arithmetic reports the same hits.

/// Precomputed triangles in a structure's leaf order: `words_per_tri` words
/// each (see [`crate::tri::TriangleTest::write_words`]), and the mesh
/// triangle index of each.
#[derive(Clone, Debug)]
pub struct FlatTriangles {
    /// The triangle test whose records these are (`moller`, `plucker`,
    /// `projection`).
    pub test: &'static str,
    /// Words per triangle record.
    pub words_per_tri: usize,
    /// The records, back to back.
    pub words: Vec<u32>,
    /// Mesh triangle index of each record.
    pub prims: Vec<u32>,
}

/// The kd-tree as flat arrays: the 8-byte nodes (two words each:
/// leaf bit, 2 axis bits and 28-bit first-child offset; split bits or leaf
/// count), the triangle-index list, the root cell and the triangles.
#[derive(Clone, Debug)]
pub struct FlatKdTree {
    /// Two words per node, as [`crate::accel::kdtree`]'s `KdNode`.
    pub nodes: Vec<u32>,
    /// The leaves' entries: positions in `tris`.
    pub indices: Vec<u32>,
    /// Lower corner of the root cell.
    pub root_min: [f32; 3],
    /// Upper corner of the root cell.
    pub root_max: [f32; 3],
    /// Longest root-to-leaf path: a stack of this many entries suffices.
    pub depth: u32,
    /// The precomputed triangles.
    pub tris: FlatTriangles,
}

/// The threaded BVH (Smits 1998) as flat arrays: eight words per node in
/// pre-order (padded box min and max as `f32` bits, escape index, leaf
/// range with the count in the top 5 bits and the first triangle below,
/// count 0 for inner nodes) and the triangles.
#[derive(Clone, Debug)]
pub struct FlatThreadedBvh {
    /// Eight words per node.
    pub nodes: Vec<u32>,
    /// The precomputed triangles.
    pub tris: FlatTriangles,
}

impl FlatTriangles {
    /// Number of triangle records.
    pub fn len(&self) -> usize {
        self.prims.len()
    }

    /// True when there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.prims.is_empty()
    }
}

/// A child slot of a [`FlatNode8`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlatChild {
    /// An unused slot.
    Empty,
    /// An inner node: its index in [`FlatBvh8::nodes`].
    Inner(u32),
    /// A leaf: `count` triangles from position `first` of
    /// [`FlatBvh8::prims`].
    Leaf {
        /// First position in the leaf order.
        first: u32,
        /// Triangles in the leaf.
        count: u32,
    },
}

/// An inner node of the 8-wide BVH: the padded box of each child slot and
/// the child references (unused slots hold inverted boxes and
/// [`FlatChild::Empty`]).
#[derive(Clone, Copy, Debug)]
pub struct FlatNode8 {
    /// Lower corner of each slot's padded box.
    pub min: [[f32; 3]; 8],
    /// Upper corner of each slot's padded box.
    pub max: [[f32; 3]; 8],
    /// The slots' references.
    pub child: [FlatChild; 8],
}

/// The 8-wide BVH ([`crate::accel::Bvh8`]) as plain nodes and the mesh
/// triangle indices in leaf order, for devices that store the tree in a
/// layout of their own (the GPU's compressed wide BVH).
#[derive(Clone, Debug)]
pub struct FlatBvh8 {
    /// Inner nodes, the root's first when the root is an inner node.
    pub nodes: Vec<FlatNode8>,
    /// The root reference (an inner node, one leaf, or empty for no
    /// triangles).
    pub root: FlatChild,
    /// The root's padded box (lower, upper corner).
    pub root_box: ([f32; 3], [f32; 3]),
    /// Mesh triangle index at each leaf position.
    pub prims: Vec<u32>,
}
