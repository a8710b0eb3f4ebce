//! The spatial-median kd-tree: the simple baseline for the SAH and Kim's (2013)
//! split-plane heuristic.

use super::refs::{leaf_of, root_refs, split_refs, Ref};
use super::tree::{split_cell, KdBuildNode};
use super::{KdOptions, TriangleSet};
use crate::aabb::Aabb;

/// Build by splitting every cell in the middle of its longest axis until it
/// holds at most `max_leaf_size` triangles, reaches the depth limit, or a
/// split leaves every triangle on both sides.
pub(crate) fn build(set: &TriangleSet, cell: &Aabb, opts: &KdOptions) -> KdBuildNode {
    let refs = root_refs(set, cell);
    let max_depth = opts.depth_limit(refs.len());
    node(set, refs, *cell, 0, max_depth, opts)
}

fn node(
    set: &TriangleSet,
    refs: Vec<Ref>,
    cell: Aabb,
    depth: u32,
    max_depth: u32,
    opts: &KdOptions,
) -> KdBuildNode {
    let n = refs.len();
    if n <= opts.max_leaf_size.max(1) || depth >= max_depth {
        return leaf_of(&refs);
    }
    let axis = cell.largest_axis();
    let pos = 0.5 * (cell.min[axis] + cell.max[axis]);
    if !(pos > cell.min[axis] && pos < cell.max[axis]) {
        return leaf_of(&refs);
    }
    let (l, r) = split_refs(set, &refs, &cell, axis, pos);
    if l.len() == n && r.len() == n {
        return leaf_of(&refs);
    }
    drop(refs);
    let [lc, rc] = split_cell(&cell, axis, pos);
    let (left, right) = if n > opts.parallel_threshold {
        rayon::join(
            || node(set, l, lc, depth + 1, max_depth, opts),
            || node(set, r, rc, depth + 1, max_depth, opts),
        )
    } else {
        (
            node(set, l, lc, depth + 1, max_depth, opts),
            node(set, r, rc, depth + 1, max_depth, opts),
        )
    };
    KdBuildNode::Inner {
        axis: axis as u8,
        split: pos,
        children: Box::new([left, right]),
    }
}
