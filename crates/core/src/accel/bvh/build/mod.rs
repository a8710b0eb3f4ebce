//! Binned SAH build (Wald 2007, "On fast construction of SAH-based bounding
//! volume hierarchies"): at each node the triangle centroids are sorted into
//! a fixed number of bins along each axis, the SAH cost of every bin
//! boundary is evaluated with prefix and suffix sweeps, and the node is split
//! at the cheapest boundary or becomes a leaf when that is cheaper.
//!
//! Subtrees above [`BuildOptions::parallel_threshold`] triangles are built in
//! parallel with `rayon::join`, and the nodes above 64k triangles are bounded
//! and binned in parallel chunks. The inner loops (32-byte references, one
//! binning pass for all three axes, the sweep, the in-place partition that also
//! bounds the children's centroids) are in [`super::binning`]. The result is a
//! pointer tree of [`BuildNode`]s plus the triangle order, which each layout
//! flattens; it does not depend on the number of threads.
//! [`BuildQuality::Fast`] selects the linear BVH of [`lbvh`] instead.

pub mod lbvh;
pub(crate) mod sweep;
#[cfg(test)]
mod tests;

use super::binning::{partition, Bins, Mapping, PrimRef, RangeInfo, Split};
use super::MAX_DEPTH;
use crate::aabb::Aabb;
use crate::accel::leaf::LeafTriangles;
use crate::accel::AccelStats;
use crate::mesh::TriangleMesh;
use crate::tri::TriangleTest;
use rayon::prelude::*;

/// Options of the BVH builds.
#[derive(Clone, Debug, PartialEq)]
pub struct BuildOptions {
    /// Most triangles per leaf (1..=31). Nodes with more are always split.
    pub max_leaf_size: usize,
    /// Most triangles per leaf of the wide BVHs whose leaves are packs of four
    /// ([`super::Bvh4`] and [`super::Bvh8`] over Möller), in place of
    /// `max_leaf_size` (1..=31). The SAH, counting a leaf's pack tests, chooses
    /// smaller leaves below it, as Embree's builders do for their `triangle4`
    /// leaves (Wald et al. 2014). 16 by default (larger leaves than 4 gave 2–5%
    /// faster shadow and primary rays and a faster build on the full dragon).
    pub packed_leaf_size: usize,
    /// Number of SAH bins per axis.
    pub bins: usize,
    /// Cost of one node traversal relative to one triangle test.
    pub traversal_cost: f32,
    /// Triangles tested at once in a leaf (1..=16): the SAH counts a leaf of
    /// `n` triangles as `ceil(n / leaf_block)` tests, as Embree's builders
    /// do for its 4-triangle leaves (Wald et al. 2014). [`super::Bvh4`]
    /// over Möller sets 4; the other structures test one at a time.
    pub leaf_block: usize,
    /// Keep splitting below the nodes the SAH would make leaves, marking
    /// them (the binary node's `leaf_ok`), down to single leaf blocks:
    /// a wide collapse then fills a node's free slots with the halves of
    /// its largest children, leaves or not, as Embree's wide builders do
    /// (Wald et al. 2014). The SAH builder only; [`super::Bvh4`] and
    /// [`super::Bvh8`] over packs of four set it for
    /// [`BuildQuality::High`].
    pub fill_wide_nodes: bool,
    /// Subtrees with more triangles than this are built on several threads.
    pub parallel_threshold: usize,
    /// Which builder makes the tree: the binned SAH (default) or the fast
    /// linear BVH for dynamic scenes.
    pub quality: BuildQuality,
    /// Options of the kd-tree builds (the structures `kd-*`).
    pub kd: crate::accel::KdOptions,
}

/// The BVH builders (fast builds, with the SAH cost reported so speed and
/// quality are visible together).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BuildQuality {
    /// Binned SAH (Wald 2007) with 32-byte references, one binning pass for
    /// the three axes and in-place partitions, as Embree's builders (Wald et
    /// al. 2014): the slower build, the better tree.
    #[default]
    Sah,
    /// [`BuildQuality::Sah`], and the wide BVHs over packs of four fill
    /// every node's free slots with the halves of its largest children,
    /// leaves or not, as Embree's wide builders do (Wald et al. 2014; see
    /// [`BuildOptions::fill_wide_nodes`]): about a quarter fewer pack tests
    /// per ray, 2–7% faster incoherent rays, a build about 8% slower. The
    /// other structures build as with `Sah`.
    High,
    /// Linear BVH (Karras 2012, "Maximizing parallelism in the construction
    /// of BVHs, octrees, and k-d trees"): Morton codes of the centroids,
    /// radix sort, the hierarchy from the codes' highest differing bits,
    /// leaves merged where the SAH prefers (module `build::lbvh`). Several
    /// times faster to build, a worse tree: for dynamic scenes.
    Fast,
}

impl BuildQuality {
    /// Every quality, in a fixed order.
    pub const ALL: [BuildQuality; 3] = [BuildQuality::Sah, BuildQuality::High, BuildQuality::Fast];

    /// The quality's name: `sah`, `high` or `fast`.
    pub fn name(self) -> &'static str {
        match self {
            BuildQuality::Sah => "sah",
            BuildQuality::High => "high",
            BuildQuality::Fast => "fast",
        }
    }
}

impl std::fmt::Display for BuildQuality {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Reads a [`BuildQuality::name`] in any case, and `lbvh` for `fast`.
impl std::str::FromStr for BuildQuality {
    type Err = crate::names::UnknownName;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let lower = s.to_ascii_lowercase();
        let lower = if lower == "lbvh" { "fast" } else { &lower };
        BuildQuality::ALL
            .into_iter()
            .find(|q| q.name() == lower)
            .ok_or_else(|| crate::names::UnknownName {
                what: "build quality",
                given: s.to_string(),
                choices: BuildQuality::ALL.iter().map(|q| q.name()).collect(),
            })
    }
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            max_leaf_size: 4,
            packed_leaf_size: 16,
            bins: 32,
            traversal_cost: 1.0,
            leaf_block: 1,
            fill_wide_nodes: false,
            parallel_threshold: 4096,
            quality: BuildQuality::Sah,
            kd: Default::default(),
        }
    }
}

/// Build presets, as Embree's build qualities (LOW, MEDIUM, HIGH; Wald et
/// al. 2014) and obvhs's presets: every other option at its default.
impl BuildOptions {
    /// The fastest build, a worse tree: the linear BVH
    /// ([`BuildQuality::Fast`]), for geometry that moves every frame.
    pub fn fast() -> Self {
        BuildOptions {
            quality: BuildQuality::Fast,
            ..Default::default()
        }
    }

    /// The default: the binned SAH ([`BuildQuality::Sah`]), a good tree at
    /// a fast build.
    pub fn balanced() -> Self {
        BuildOptions::default()
    }

    /// The best tree for many rays: the binned SAH with the wide nodes'
    /// free slots filled ([`BuildQuality::High`]), a build about 8% slower.
    pub fn best() -> Self {
        BuildOptions {
            quality: BuildQuality::High,
            ..Default::default()
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
        /// The two children.
        children: Box<[BuildNode; 2]>,
        /// The SAH prefers one leaf of the whole subtree to this split (only
        /// with [`BuildOptions::fill_wide_nodes`]; elsewhere such a node is
        /// a [`BuildNode::Leaf`]).
        leaf_ok: bool,
    },
}

impl BuildNode {
    /// Bounds of the node.
    pub fn bounds(&self) -> Aabb {
        match self {
            BuildNode::Leaf { bounds, .. } | BuildNode::Inner { bounds, .. } => *bounds,
        }
    }

    /// The subtree's triangles as a range of the build order: `(first,
    /// count)`. A subtree's leaves are consecutive in that order, so the
    /// range runs from its first leaf's start to its last leaf's end, each
    /// found down one edge of the subtree (its depth, not its size).
    pub fn triangle_range(&self) -> (u32, u32) {
        let mut left = self;
        while let BuildNode::Inner { children, .. } = left {
            left = &children[0];
        }
        let mut right = self;
        while let BuildNode::Inner { children, .. } = right {
            right = &children[1];
        }
        match (left, right) {
            (
                BuildNode::Leaf { first, .. },
                BuildNode::Leaf {
                    first: last, count, ..
                },
            ) => (*first, last + count - first),
            _ => unreachable!("both walks end at leaves"),
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

/// Build a tree over the triangles of `mesh` with the builder that
/// `options.quality` names: the binned SAH ([`BuildQuality::Sah`]) or the
/// linear BVH ([`BuildQuality::Fast`], see [`lbvh`]).
///
/// An empty mesh gives a single empty leaf. Degenerate inputs (all centroids
/// equal) are split at the object median so the depth stays logarithmic.
/// The result does not depend on the number of threads.
///
/// # Panics
/// When a triangle refers to a vertex the mesh does not have
/// ([`TriangleMesh::assert_indices_in_range`]).
pub fn build(mesh: &TriangleMesh, options: &BuildOptions) -> BuildTree {
    mesh.assert_indices_in_range();
    let opts = clamped(options);
    match opts.quality {
        BuildQuality::Sah | BuildQuality::High => sah_build(mesh, &opts),
        BuildQuality::Fast => lbvh::build(mesh, &opts),
    }
}

/// `options` with the leaf bound, the bins and the leaf block within the
/// builders' limits.
pub(crate) fn clamped(options: &BuildOptions) -> BuildOptions {
    BuildOptions {
        max_leaf_size: options.max_leaf_size.clamp(1, 31),
        bins: options.bins.clamp(2, 256),
        leaf_block: options.leaf_block.clamp(1, 16),
        ..options.clone()
    }
}

/// Ranges longer than this are bounded and binned in parallel chunks.
const PAR_BIN: usize = 64 * 1024;
/// Chunk length of the parallel passes.
const CHUNK: usize = 16 * 1024;

/// The references of every triangle of `mesh` and their bounds (in
/// parallel; the bounds are exact, so the result does not depend on how the
/// work is split).
pub(crate) fn prim_refs(mesh: &TriangleMesh) -> (Vec<PrimRef>, RangeInfo) {
    let mut refs = super::huge_pages::with_capacity(mesh.num_triangles());
    (0..mesh.num_triangles())
        .into_par_iter()
        .with_min_len(4096)
        .map(|i| PrimRef::new(&mesh.triangle_bounds(i), i as u32))
        .collect_into_vec(&mut refs);
    let info = range_info(&refs);
    (refs, info)
}

/// Bounds of `refs`, in parallel chunks when there are many.
pub(crate) fn range_info(refs: &[PrimRef]) -> RangeInfo {
    if refs.len() > PAR_BIN {
        refs.par_chunks(CHUNK)
            .map(RangeInfo::of)
            .reduce(|| RangeInfo::EMPTY, RangeInfo::merge)
            .clean()
    } else {
        RangeInfo::of(refs).clean()
    }
}

/// The binned SAH build over arbitrary boxes instead of a mesh's
/// triangles: `order` and the leaves refer to indices into `boxes`. The
/// top level of a two-level BVH is built this way over its instances'
/// world boxes (Wald et al. 2014). Every box must be finite and not empty.
/// `options.quality` is ignored (always the binned SAH).
pub fn build_over_boxes(boxes: &[Aabb], options: &BuildOptions) -> BuildTree {
    let opts = clamped(options);
    let refs: Vec<PrimRef> = boxes
        .iter()
        .enumerate()
        .map(|(i, b)| PrimRef::new(b, i as u32))
        .collect();
    let info = range_info(&refs);
    sah_over_refs(refs, info, &opts)
}

fn sah_build(mesh: &TriangleMesh, opts: &BuildOptions) -> BuildTree {
    let (refs, info) = prim_refs(mesh);
    sah_over_refs(refs, info, opts)
}

fn sah_over_refs(mut refs: Vec<PrimRef>, info: RangeInfo, opts: &BuildOptions) -> BuildTree {
    let mut bins = Bins::new(opts.bins);
    let root = sah_node(&mut refs, info, 0, 0, opts, &mut bins);
    BuildTree {
        root,
        order: order_of(&refs),
    }
}

/// The mesh triangle indices of `refs`, in their order.
pub(crate) fn order_of(refs: &[PrimRef]) -> Vec<u32> {
    refs.par_iter()
        .with_min_len(4096)
        .map(|r| r.prim())
        .collect()
}

/// Bins of a node of `n` references: `4 + n / 20`, at most `max`, as
/// Embree's binned builder (Wald et al. 2014) does, so that small nodes do
/// not pay for sweeping bins they cannot fill.
#[inline]
fn bins_for(n: usize, max: usize) -> usize {
    (4 + n / 20).min(max)
}

/// What the SAH build does with a node, decided from its references
/// before any of them moves: the binary build ([`sah_node`]) carries it out
/// at once, the direct wide build ([`super::wide_build`]) when it opens the
/// node.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Plan {
    /// A leaf of all the node's references.
    Leaf,
    /// Split at the binned SAH's cheapest boundary; `leaf_ok` when one leaf
    /// would be cheaper (only with [`BuildOptions::fill_wide_nodes`]: the
    /// halves are then split by [`sweep`]).
    Binned {
        split: Split,
        map: Mapping,
        leaf_ok: bool,
    },
    /// No useful SAH split (coincident centroids, or too deep): split at
    /// the object median along the widest centroid axis.
    Median { axis: usize },
}

/// The plan for the node over `refs`, whose bounds `info` the caller knows,
/// at `depth` in the binary tree; `bins` is this thread's scratch.
pub(crate) fn plan(
    refs: &[PrimRef],
    info: &RangeInfo,
    depth: usize,
    opts: &BuildOptions,
    bins: &mut Bins,
) -> Plan {
    let n = refs.len();
    let leaf_cost = blocks(n as u32, opts);
    // Any split costs at least one traversal, so a small node whose leaf
    // cost is no more is a leaf without binning (the same decision).
    if n <= 1 || (n <= opts.max_leaf_size && leaf_cost <= opts.traversal_cost) {
        return Plan::Leaf;
    }
    let split = if depth + 40 < MAX_DEPTH {
        let nb = bins_for(n, opts.bins);
        let map = Mapping::new(&info.centers, nb);
        if n > PAR_BIN {
            *bins = refs
                .par_chunks(CHUNK)
                .map(|c| {
                    let mut b = Bins::new(nb);
                    b.bin(c, &map);
                    b
                })
                .reduce_with(|mut a, b| {
                    a.merge(&b, nb);
                    a
                })
                .expect("n > 0");
        } else {
            bins.bin(refs, &map);
        }
        let area = info.bounds.half_area();
        bins.best_split(nb, area, opts.traversal_cost, opts.leaf_block as u32)
            .map(|s| (s, map))
    } else {
        None
    };
    match split {
        Some((split, map)) => {
            let leaf_ok = split.cost >= leaf_cost && n <= opts.max_leaf_size;
            if leaf_ok && !opts.fill_wide_nodes {
                return Plan::Leaf;
            }
            Plan::Binned {
                split,
                map,
                leaf_ok,
            }
        }
        None if n <= opts.max_leaf_size => Plan::Leaf,
        None => Plan::Median {
            axis: info.centers.aabb().largest_axis(),
        },
    }
}

/// The two halves of a node split as `plan` says (not [`Plan::Leaf`]):
/// the references reordered, left half first; returns the split axis, the
/// left half's length and both halves' bounds.
pub(crate) fn split_refs(
    refs: &mut [PrimRef],
    plan: &Plan,
) -> (usize, usize, RangeInfo, RangeInfo) {
    match *plan {
        Plan::Binned { split, map, .. } => {
            let (lc, rc) = partition(refs, &map, &split);
            let l = RangeInfo {
                bounds: split.left,
                centers: lc,
            };
            let r = RangeInfo {
                bounds: split.right,
                centers: rc,
            };
            (split.axis, split.left_count, l.clean(), r.clean())
        }
        Plan::Median { axis } => {
            let mid = refs.len() / 2;
            refs.select_nth_unstable_by(mid, |a, b| {
                (a.lo[axis] + a.hi[axis]).total_cmp(&(b.lo[axis] + b.hi[axis]))
            });
            let (l, r) = refs.split_at(mid);
            (axis, mid, range_info(l), range_info(r))
        }
        Plan::Leaf => unreachable!("a leaf is not split"),
    }
}

/// Build the subtree over `refs` (at `first` in the final order), whose
/// bounds `info` the caller knows; `bins` is this thread's scratch.
fn sah_node(
    refs: &mut [PrimRef],
    info: RangeInfo,
    first: usize,
    depth: usize,
    opts: &BuildOptions,
    bins: &mut Bins,
) -> BuildNode {
    let bounds = info.bounds.aabb();
    let plan = plan(refs, &info, depth, opts, bins);
    let leaf_ok = match plan {
        Plan::Leaf => {
            return BuildNode::Leaf {
                bounds,
                first: first as u32,
                count: refs.len() as u32,
            }
        }
        Plan::Binned { leaf_ok, .. } => leaf_ok,
        Plan::Median { .. } => false,
    };
    let n = refs.len();
    let (_, mid, linfo, rinfo) = split_refs(refs, &plan);
    let (left, right) = refs.split_at_mut(mid);
    let (l, r) = if leaf_ok {
        // Only seen when a wide node has slots to fill: swept, not binned.
        (
            sweep::sweep_node(left, first, opts),
            sweep::sweep_node(right, first + mid, opts),
        )
    } else if n > opts.parallel_threshold {
        rayon::join(
            || sah_node(left, linfo, first, depth + 1, opts, bins),
            || {
                let mut own = Bins::new(opts.bins);
                sah_node(right, rinfo, first + mid, depth + 1, opts, &mut own)
            },
        )
    } else {
        (
            sah_node(left, linfo, first, depth + 1, opts, bins),
            sah_node(right, rinfo, first + mid, depth + 1, opts, bins),
        )
    };
    BuildNode::Inner {
        bounds,
        children: Box::new([l, r]),
        leaf_ok,
    }
}

/// The SAH's intersection cost of `n` triangles: the number of leaf tests,
/// `ceil(n / leaf_block)` ([`super::sah_sweep::leaf_tests`]).
#[inline]
pub(crate) fn blocks(n: u32, opts: &BuildOptions) -> f32 {
    super::sah_sweep::leaf_tests(n, opts.leaf_block as u32)
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
