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

/// The kd-tree with ropes and leaf boxes (Popov, Günther, Seidel &
/// Slusallek 2007) as flat arrays: the 8-byte nodes of [`FlatKdTree`], except
/// that a leaf's first word holds the leaf bit and the index of its leaf
/// record (the second word still its entry count), and the leaf records of
/// [`FlatKdRopes::LEAF_WORDS`] words each: the leaf's cell (min x, y, z, max
/// x, y, z as `f32` bits), its six ropes (the node across face
/// `2 · axis + (1 for the max face)`, `u32::MAX` on the scene boundary), its
/// first entry in the triangle-index list and its entry count.
#[derive(Clone, Debug)]
pub struct FlatKdRopes {
    /// Two words per node.
    pub nodes: Vec<u32>,
    /// [`FlatKdRopes::LEAF_WORDS`] words per leaf record.
    pub leaves: Vec<u32>,
    /// The leaves' entries: positions in `tris`.
    pub indices: Vec<u32>,
    /// Lower corner of the root cell.
    pub root_min: [f32; 3],
    /// Upper corner of the root cell.
    pub root_max: [f32; 3],
    /// The precomputed triangles.
    pub tris: FlatTriangles,
}

impl FlatKdRopes {
    /// Words per leaf record: six for the cell, six ropes, first and count.
    pub const LEAF_WORDS: usize = 14;

    /// Rope value of a face on the scene boundary.
    pub const NO_ROPE: u32 = u32::MAX;
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
