//! The kd-tree every builder produces, before it is laid out into compact
//! nodes: axis-aligned split planes and leaves listing mesh triangles.

use crate::aabb::Aabb;

/// A node of the pointer tree the builders produce.
#[derive(Debug)]
pub enum KdBuildNode {
    /// Mesh triangles whose tolerance band reaches into the leaf's cell.
    Leaf(Vec<u32>),
    /// A split plane `x[axis] = split`; `children[0]` is the cell below.
    Inner {
        /// Split axis (0, 1, 2).
        axis: u8,
        /// Split position.
        split: f32,
        /// Below and above the plane.
        children: Box<[KdBuildNode; 2]>,
    },
}

/// Size and cost figures of a pointer tree.
#[derive(Clone, Copy, Debug, Default)]
pub struct TreeShape {
    /// Inner nodes plus leaves.
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Empty leaves.
    pub empty_leaves: usize,
    /// Triangle references in all leaves.
    pub references: usize,
    /// Longest root-to-leaf path (the root has depth 0).
    pub depth: u32,
    /// SAH cost relative to the root cell (traversal cost `c_trav`,
    /// triangle cost 1).
    pub sah_cost: f64,
}

impl KdBuildNode {
    /// Shape figures of the subtree with cell `cell`.
    pub fn shape(&self, cell: &Aabb, c_trav: f64) -> TreeShape {
        let root_area = (cell.surface_area() as f64).max(f64::MIN_POSITIVE);
        let mut s = TreeShape::default();
        self.shape_into(cell, 0, root_area, c_trav, &mut s);
        s
    }

    fn shape_into(&self, cell: &Aabb, depth: u32, root_area: f64, c_trav: f64, s: &mut TreeShape) {
        s.nodes += 1;
        s.depth = s.depth.max(depth);
        let p = cell.surface_area() as f64 / root_area;
        match self {
            KdBuildNode::Leaf(tris) => {
                s.leaves += 1;
                s.empty_leaves += tris.is_empty() as usize;
                s.references += tris.len();
                s.sah_cost += p * tris.len() as f64;
            }
            KdBuildNode::Inner {
                axis,
                split,
                children,
            } => {
                s.sah_cost += p * c_trav;
                let [l, r] = split_cell(cell, *axis as usize, *split);
                children[0].shape_into(&l, depth + 1, root_area, c_trav, s);
                children[1].shape_into(&r, depth + 1, root_area, c_trav, s);
            }
        }
    }
}

/// The two cells a plane `x[axis] = split` cuts `cell` into.
pub fn split_cell(cell: &Aabb, axis: usize, split: f32) -> [Aabb; 2] {
    let mut l = *cell;
    let mut r = *cell;
    l.max[axis] = split;
    r.min[axis] = split;
    [l, r]
}
