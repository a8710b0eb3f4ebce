//! Triangle references and their distribution to the two sides of a split
//! plane, shared by the median and game builds.

use super::clip::reference_box;
use super::tree::split_cell;
use super::TriangleSet;
use crate::aabb::Aabb;

/// A triangle as one node sees it: its id and the box of its tolerance band
/// inside the node's cell ([`reference_box`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ref {
    pub tri: u32,
    pub bounds: Aabb,
}

/// References of every non-degenerate triangle in the root cell.
pub(crate) fn root_refs(set: &TriangleSet, cell: &Aabb) -> Vec<Ref> {
    set.ids
        .iter()
        .filter_map(|&t| {
            let bounds = reference_box(&set.corners[t as usize], set.band[t as usize], cell)?;
            Some(Ref { tri: t, bounds })
        })
        .collect()
}

/// The references of the cells below and above `x[axis] = pos`: those on
/// one side keep their boxes, those straddling the plane are clipped to each
/// side's cell.
pub(crate) fn split_refs(
    set: &TriangleSet,
    refs: &[Ref],
    cell: &Aabb,
    axis: usize,
    pos: f32,
) -> (Vec<Ref>, Vec<Ref>) {
    let [lcell, rcell] = split_cell(cell, axis, pos);
    let mut left = Vec::with_capacity(refs.len() / 2 + 1);
    let mut right = Vec::with_capacity(refs.len() / 2 + 1);
    for r in refs {
        if r.bounds.max[axis] <= pos && r.bounds.min[axis] < pos {
            left.push(*r);
        } else if r.bounds.min[axis] >= pos && r.bounds.max[axis] > pos {
            right.push(*r);
        } else {
            let t = r.tri as usize;
            for (c, out) in [(&lcell, &mut left), (&rcell, &mut right)] {
                if let Some(b) = reference_box(&set.corners[t], set.band[t], c) {
                    out.push(Ref {
                        tri: r.tri,
                        bounds: b.intersection(r.bounds),
                    });
                }
            }
        }
    }
    (left, right)
}

/// The leaf of `refs`, triangle ids ascending.
pub(crate) fn leaf_of(refs: &[Ref]) -> super::KdBuildNode {
    let mut ids: Vec<u32> = refs.iter().map(|r| r.tri).collect();
    ids.sort_unstable();
    super::KdBuildNode::Leaf(ids)
}
