//! The small subtrees below a node the SAH makes a leaf, when the build
//! fills wide nodes ([`super::BuildOptions::fill_wide_nodes`]):
//! split by an exact SAH sweep over the sorted centroids instead
//! of binning, since such a subtree holds at most 31 triangles and is
//! only looked at when a wide node has free slots to fill.
//!
//! Embree's wide builders (Wald et al. 2014, "Embree: a kernel framework
//! for efficient CPU ray tracing") split such a child with the same SAH
//! the rest of the build uses; the sweep along the axis of widest centroid
//! spread is that SAH restricted to one axis, evaluated at every position
//! rather than at bin borders.

use super::super::binning::{Box4f, PrimRef, RangeInfo};
use super::{blocks, BuildNode, BuildOptions};

/// Most references a swept subtree may hold (the leaf bound's maximum).
const MAX_SWEEP: usize = 32;

/// Build the subtree over `refs` (at `first` in the final order): a leaf
/// when its cost is no more than a traversal's, else split where
/// [`sweep_plan`] says.
///
/// `refs` must hold at most [`MAX_SWEEP`] references (the caller's leaf
/// bound, at most 31).
pub(crate) fn sweep_node(refs: &mut [PrimRef], first: usize, opts: &BuildOptions) -> BuildNode {
    let info = RangeInfo::of(refs).clean();
    let bounds = info.bounds.aabb();
    let Some((best, leaf_ok)) = sweep_plan(refs, &info, opts) else {
        return BuildNode::Leaf {
            bounds,
            first: first as u32,
            count: refs.len() as u32,
        };
    };
    let (l, r) = refs.split_at_mut(best);
    BuildNode::Inner {
        bounds,
        children: Box::new([
            sweep_node(l, first, opts),
            sweep_node(r, first + best, opts),
        ]),
        leaf_ok,
    }
}

/// How the sweep splits the node over `refs`, whose bounds are `info`:
/// `None` for a leaf (cost no more than a traversal's), else the length of
/// the left half after `refs` are sorted along the axis of widest centroid
/// spread, where the sweep finds the cheapest SAH, and whether a leaf would
/// still be cheaper than that split (`leaf_ok`).
pub(crate) fn sweep_plan(
    refs: &mut [PrimRef],
    info: &RangeInfo,
    opts: &BuildOptions,
) -> Option<(usize, bool)> {
    let n = refs.len();
    debug_assert!((1..=MAX_SWEEP).contains(&n));
    let leaf_cost = blocks(n as u32, opts);
    if n <= 1 || leaf_cost <= opts.traversal_cost {
        return None;
    }
    let axis = info.centers.aabb().largest_axis();
    refs.sort_unstable_by(|a, b| (a.lo[axis] + a.hi[axis]).total_cmp(&(b.lo[axis] + b.hi[axis])));
    // Area right of each position, then the left sweep picks the cheapest.
    let mut right = [0f32; MAX_SWEEP];
    let mut acc = Box4f::EMPTY;
    for i in (1..n).rev() {
        acc = acc.union(refs[i].bounds());
        right[i] = acc.half_area();
    }
    let inv = 1.0 / info.bounds.half_area().max(f32::MIN_POSITIVE);
    let mut left = Box4f::EMPTY;
    let (mut best, mut best_cost) = (1, f32::INFINITY);
    for k in 1..n {
        left = left.union(refs[k - 1].bounds());
        let c = opts.traversal_cost
            + (left.half_area() * blocks(k as u32, opts) + right[k] * blocks((n - k) as u32, opts))
                * inv;
        if c < best_cost {
            (best, best_cost) = (k, c);
        }
    }
    Some((best, best_cost >= leaf_cost))
}
