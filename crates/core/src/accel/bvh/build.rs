//! Binned SAH build (Wald 2007, "On fast construction of SAH-based bounding
//! volume hierarchies"): at each node the triangle centroids are sorted into
//! a fixed number of bins along each axis, the SAH cost of every bin
//! boundary is evaluated with prefix and suffix sweeps, and the node is split
//! at the cheapest boundary or becomes a leaf when that is cheaper.
//!
//! Subtrees above [`BuildOptions::parallel_threshold`] triangles are built in
//! parallel with `rayon::join`. The result is a pointer tree of
//! [`BuildNode`]s plus the triangle order, which each layout flattens.

use super::MAX_DEPTH;
use crate::aabb::Aabb;
use crate::accel::leaf::LeafTriangles;
use crate::accel::AccelStats;
use crate::mesh::TriangleMesh;
use crate::tri::TriangleTest;
use glam::Vec3;
use rayon::prelude::*;

/// Options of the BVH builds.
#[derive(Clone, Debug, PartialEq)]
pub struct BuildOptions {
    /// Most triangles per leaf (1..=31). Nodes with more are always split.
    pub max_leaf_size: usize,
    /// Number of SAH bins per axis.
    pub bins: usize,
    /// Cost of one node traversal relative to one triangle test.
    pub traversal_cost: f32,
    /// Triangles tested at once in a leaf (1..=16): the SAH counts a leaf of
    /// `n` triangles as `ceil(n / leaf_block)` tests, as Embree's builders
    /// do for its 4-triangle leaves (Wald et al. 2014). [`super::Bvh4`]
    /// over Möller sets 4; the other structures test one at a time.
    pub leaf_block: usize,
    /// Subtrees with more triangles than this are built on several threads.
    pub parallel_threshold: usize,
    /// Options of the kd-tree builds (the structures `kd-*`).
    pub kd: crate::accel::KdOptions,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            max_leaf_size: 4,
            bins: 32,
            traversal_cost: 1.0,
            leaf_block: 1,
            parallel_threshold: 4096,
            kd: Default::default(),
        }
    }
}

/// A node of the intermediate build tree.
#[derive(Debug)]
pub enum BuildNode {
    /// A leaf holding `count` triangles starting at `first` in the build's
    /// triangle order.
    Leaf {
        /// Bounds of the leaf's triangles.
        bounds: Aabb,
        /// First triangle in [`BuildTree::order`].
        first: u32,
        /// Number of triangles.
        count: u32,
    },
    /// An inner node with two children.
    Inner {
        /// Bounds of both children.
        bounds: Aabb,
        /// Split axis (0, 1, 2).
        axis: u8,
        /// The two children.
        children: Box<[BuildNode; 2]>,
    },
}

impl BuildNode {
    /// Bounds of the node.
    pub fn bounds(&self) -> Aabb {
        match self {
            BuildNode::Leaf { bounds, .. } | BuildNode::Inner { bounds, .. } => *bounds,
        }
    }

    /// Number of nodes in the subtree.
    pub fn count_nodes(&self) -> usize {
        match self {
            BuildNode::Leaf { .. } => 1,
            BuildNode::Inner { children, .. } => {
                1 + children[0].count_nodes() + children[1].count_nodes()
            }
        }
    }
}

/// The output of a build: the tree and the triangle order its leaves refer to.
#[derive(Debug)]
pub struct BuildTree {
    /// Root node.
    pub root: BuildNode,
    /// Mesh triangle indices in leaf order.
    pub order: Vec<u32>,
}

/// One triangle as the builder sees it.
#[derive(Clone, Copy)]
struct Ref {
    bounds: Aabb,
    centroid: Vec3,
    prim: u32,
}

/// Build a binned-SAH tree over the triangles of `mesh`.
///
/// An empty mesh gives a single empty leaf. Degenerate inputs (all centroids
/// equal) are split at the object median so the depth stays logarithmic.
pub fn build(mesh: &TriangleMesh, options: &BuildOptions) -> BuildTree {
    let mut refs: Vec<Ref> = (0..mesh.num_triangles())
        .into_par_iter()
        .map(|i| {
            let bounds = mesh.triangle_bounds(i);
            Ref {
                bounds,
                centroid: bounds.center(),
                prim: i as u32,
            }
        })
        .collect();
    let opts = BuildOptions {
        max_leaf_size: options.max_leaf_size.clamp(1, 31),
        bins: options.bins.clamp(2, 256),
        leaf_block: options.leaf_block.clamp(1, 16),
        ..options.clone()
    };
    let root = build_node(&mut refs, 0, 0, &opts);
    BuildTree {
        root,
        order: refs.iter().map(|r| r.prim).collect(),
    }
}

fn bounds_of(refs: &[Ref]) -> (Aabb, Aabb) {
    refs.iter().fold((Aabb::EMPTY, Aabb::EMPTY), |(b, c), r| {
        (b.union(r.bounds), c.grow(r.centroid))
    })
}

fn build_node(refs: &mut [Ref], first: usize, depth: usize, opts: &BuildOptions) -> BuildNode {
    let (bounds, centroids) = if refs.len() > 64 * 1024 {
        refs.par_chunks(16 * 1024).map(bounds_of).reduce(
            || (Aabb::EMPTY, Aabb::EMPTY),
            |a, b| (a.0.union(b.0), a.1.union(b.1)),
        )
    } else {
        bounds_of(refs)
    };
    let n = refs.len();
    let leaf = || BuildNode::Leaf {
        bounds,
        first: first as u32,
        count: n as u32,
    };
    if n <= 1 {
        return leaf();
    }
    let split = if depth + 40 < MAX_DEPTH {
        find_sah_split(refs, &bounds, &centroids, opts)
    } else {
        None
    };
    let mid = match split {
        Some(s) => {
            let leaf_cost = blocks(n as u32, opts);
            if s.cost >= leaf_cost && n <= opts.max_leaf_size {
                return leaf();
            }
            partition(refs, &s)
        }
        None if n <= opts.max_leaf_size => return leaf(),
        None => {
            // No useful SAH split (coincident centroids, or too deep): split
            // at the object median along the widest centroid axis.
            let axis = centroids.largest_axis();
            let mid = n / 2;
            refs.select_nth_unstable_by(mid, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
            mid
        }
    };
    let axis = match split {
        Some(s) => s.axis as u8,
        None => centroids.largest_axis() as u8,
    };
    let (left, right) = refs.split_at_mut(mid);
    let (l, r) = if n > opts.parallel_threshold {
        rayon::join(
            || build_node(left, first, depth + 1, opts),
            || build_node(right, first + mid, depth + 1, opts),
        )
    } else {
        (
            build_node(left, first, depth + 1, opts),
            build_node(right, first + mid, depth + 1, opts),
        )
    };
    BuildNode::Inner {
        bounds,
        axis,
        children: Box::new([l, r]),
    }
}

#[derive(Clone, Copy, Debug)]
struct Split {
    axis: usize,
    /// Triangles whose centroid falls in a bin below `bin` go left.
    bin: usize,
    /// Binning transform of the axis: `bin = (c - lo) * scale`.
    lo: f32,
    scale: f32,
    bins: usize,
    /// SAH cost in units of one triangle test, relative to this node's area.
    cost: f32,
}

impl Split {
    #[inline]
    fn bin_of(&self, c: f32) -> usize {
        (((c - self.lo) * self.scale) as usize).min(self.bins - 1)
    }
}

/// Evaluate all bin boundaries on all three axes; `None` when every axis has
/// coincident centroids.
fn find_sah_split(
    refs: &[Ref],
    bounds: &Aabb,
    centroids: &Aabb,
    opts: &BuildOptions,
) -> Option<Split> {
    let nb = opts.bins;
    let parent_area = bounds.surface_area().max(f32::MIN_POSITIVE);
    let mut best: Option<Split> = None;
    let mut bin_bounds = vec![Aabb::EMPTY; nb];
    let mut bin_count = vec![0u32; nb];
    let mut right_area = vec![0.0f32; nb];
    let mut right_count = vec![0u32; nb];
    for axis in 0..3 {
        let lo = centroids.min[axis];
        let extent = centroids.max[axis] - lo;
        if extent.is_nan() || extent <= 0.0 {
            continue;
        }
        let probe = Split {
            axis,
            bin: 0,
            lo,
            scale: nb as f32 / extent,
            bins: nb,
            cost: 0.0,
        };
        bin_bounds.fill(Aabb::EMPTY);
        bin_count.fill(0);
        for r in refs {
            let b = probe.bin_of(r.centroid[axis]);
            bin_bounds[b] = bin_bounds[b].union(r.bounds);
            bin_count[b] += 1;
        }
        // Suffix sweep: area and count of bins [i, nb).
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0u32);
        for i in (1..nb).rev() {
            acc = acc.union(bin_bounds[i]);
            cnt += bin_count[i];
            right_area[i] = acc.surface_area();
            right_count[i] = cnt;
        }
        // Prefix sweep, evaluating the boundary before bin i.
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0u32);
        for i in 1..nb {
            acc = acc.union(bin_bounds[i - 1]);
            cnt += bin_count[i - 1];
            if cnt == 0 || right_count[i] == 0 {
                continue;
            }
            let cost = opts.traversal_cost
                + (acc.surface_area() * blocks(cnt, opts)
                    + right_area[i] * blocks(right_count[i], opts))
                    / parent_area;
            if best.is_none_or(|b| cost < b.cost) {
                best = Some(Split {
                    bin: i,
                    cost,
                    ..probe
                });
            }
        }
    }
    best
}

/// Move the refs whose centroid bin is below the split's to the front;
/// returns how many there are (never 0 nor all, since the sweep only offers
/// boundaries with triangles on both sides).
fn partition(refs: &mut [Ref], split: &Split) -> usize {
    let mut i = 0;
    let mut j = refs.len();
    while i < j {
        if split.bin_of(refs[i].centroid[split.axis]) < split.bin {
            i += 1;
        } else {
            j -= 1;
            refs.swap(i, j);
        }
    }
    i
}

/// The SAH's intersection cost of `n` triangles: the number of leaf tests,
/// `ceil(n / leaf_block)`.
#[inline]
fn blocks(n: u32, opts: &BuildOptions) -> f32 {
    n.div_ceil(opts.leaf_block as u32) as f32
}

/// Shape figures of a build tree: node and leaf counts, depth and SAH cost
/// (see [`crate::accel::AccelStats::sah_cost`]).
pub fn tree_shape(root: &BuildNode, traversal_cost: f64) -> (usize, usize, u32, f64) {
    let root_area = (root.bounds().surface_area() as f64).max(f64::MIN_POSITIVE);
    let mut nodes = 0;
    let mut leaves = 0;
    let mut depth = 0;
    let mut cost = 0.0;
    let mut stack = vec![(root, 0u32)];
    while let Some((node, d)) = stack.pop() {
        nodes += 1;
        depth = depth.max(d);
        let rel = node.bounds().surface_area() as f64 / root_area;
        match node {
            BuildNode::Leaf { count, .. } => {
                leaves += 1;
                cost += rel * *count as f64;
            }
            BuildNode::Inner { children, .. } => {
                cost += rel * traversal_cost;
                stack.push((&children[0], d + 1));
                stack.push((&children[1], d + 1));
            }
        }
    }
    (nodes, leaves, depth, cost)
}

impl BuildTree {
    /// Precompute the triangles in leaf order and describe the structure
    /// whose flattened nodes take `node_bytes`; consumes the tree.
    pub(crate) fn into_leaves<T: TriangleTest>(
        self,
        mesh: &TriangleMesh,
        node_bytes: usize,
        options: &BuildOptions,
    ) -> (LeafTriangles<T>, AccelStats) {
        let stats = self.stats(node_bytes, options);
        let tris = LeafTriangles::new(mesh, self.order);
        let stats = AccelStats {
            bytes: node_bytes + tris.bytes(),
            ..stats
        };
        (tris, stats)
    }

    /// The shape figures of the tree, for a structure whose flattened nodes
    /// take `node_bytes` (`bytes` counts the nodes alone: add the leaves').
    pub(crate) fn stats(&self, node_bytes: usize, options: &BuildOptions) -> AccelStats {
        let (nodes, leaves, depth, sah_cost) =
            tree_shape(&self.root, options.traversal_cost as f64);
        AccelStats {
            nodes,
            leaves,
            bytes: node_bytes,
            node_bytes,
            depth,
            sah_cost,
            triangle_refs: self.order.len(),
        }
    }
}
