//! Paper 000's compact kd-tree node (8 bytes) and the breadth-first layout
//! of the pointer tree into one array.

use super::tree::{split_cell, KdBuildNode};
use crate::aabb::Aabb;
use std::collections::VecDeque;

const LEAF: u32 = 1 << 31;
const AXIS_SHIFT: u32 = 29;
/// Largest child offset the 28 offset bits hold.
pub(crate) const MAX_OFFSET: u32 = (1 << 28) - 1;

/// An 8-byte kd-tree node (paper 000): a word with 1 bit leaf flag, 2 bits
/// split axis and a 28-bit offset of the first of the two children (stored
/// next to each other, so one offset serves both), and the split position as
/// an `f32`. A leaf's word holds the offset of its first entry in the
/// triangle-index list and the second word the number of entries.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct KdNode {
    word: u32,
    data: u32,
}

impl KdNode {
    /// An inner node.
    pub fn inner(axis: usize, first_child: u32, split: f32) -> KdNode {
        assert!(
            first_child <= MAX_OFFSET,
            "kd-tree too large for 28-bit child offsets"
        );
        KdNode {
            word: ((axis as u32) << AXIS_SHIFT) | first_child,
            data: split.to_bits(),
        }
    }

    /// A leaf listing `count` triangle indices from `first`.
    pub fn leaf(first: u32, count: u32) -> KdNode {
        assert!(
            first < LEAF,
            "triangle-index list too long for a kd-tree leaf"
        );
        KdNode {
            word: LEAF | first,
            data: count,
        }
    }

    /// True for a leaf.
    #[inline(always)]
    pub fn is_leaf(self) -> bool {
        self.word & LEAF != 0
    }

    /// Split axis of an inner node.
    #[inline(always)]
    pub fn axis(self) -> usize {
        ((self.word >> AXIS_SHIFT) & 3) as usize
    }

    /// Index of the child below the plane; the one above follows it.
    #[inline(always)]
    pub fn first_child(self) -> u32 {
        self.word & MAX_OFFSET
    }

    /// Split position of an inner node.
    #[inline(always)]
    pub fn split(self) -> f32 {
        f32::from_bits(self.data)
    }

    /// First entry of a leaf in the triangle-index list.
    #[inline(always)]
    pub fn first(self) -> usize {
        (self.word & !LEAF) as usize
    }

    /// Number of entries of a leaf.
    #[inline(always)]
    pub fn count(self) -> usize {
        self.data as usize
    }
}

/// A tree laid out breadth-first: nodes, the triangle-index list (mesh
/// triangle ids), and per node its cell and parent.
pub(crate) struct KdLayout {
    pub nodes: Vec<KdNode>,
    pub indices: Vec<u32>,
    #[cfg_attr(not(test), allow(dead_code))]
    pub cells: Vec<Aabb>,
    #[cfg_attr(not(test), allow(dead_code))]
    pub parents: Vec<u32>,
}

/// Lay `root` with cell `cell` out breadth-first: siblings are adjacent and
/// each level follows the one above it.
pub(crate) fn layout(root: &KdBuildNode, cell: &Aabb) -> KdLayout {
    let mut out = KdLayout {
        nodes: vec![KdNode::default()],
        indices: Vec::new(),
        cells: vec![*cell],
        parents: vec![u32::MAX],
    };
    let mut queue = VecDeque::from([(root, 0usize)]);
    while let Some((node, slot)) = queue.pop_front() {
        match node {
            KdBuildNode::Leaf(tris) => {
                out.nodes[slot] = KdNode::leaf(out.indices.len() as u32, tris.len() as u32);
                out.indices.extend_from_slice(tris);
            }
            KdBuildNode::Inner {
                axis,
                split,
                children,
            } => {
                let first = out.nodes.len();
                out.nodes[slot] = KdNode::inner(*axis as usize, first as u32, *split);
                let halves = split_cell(&out.cells[slot], *axis as usize, *split);
                for (c, half) in children.iter().zip(halves) {
                    queue.push_back((c, out.nodes.len()));
                    out.nodes.push(KdNode::default());
                    out.cells.push(half);
                    out.parents.push(slot as u32);
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_is_eight_bytes_and_round_trips() {
        assert_eq!(std::mem::size_of::<KdNode>(), 8);
        for axis in 0..3 {
            let n = KdNode::inner(axis, MAX_OFFSET, -1.25e-7);
            assert!(!n.is_leaf());
            assert_eq!(n.axis(), axis);
            assert_eq!(n.first_child(), MAX_OFFSET);
            assert_eq!(n.split(), -1.25e-7);
        }
        let l = KdNode::leaf(LEAF - 1, 123_456);
        assert!(l.is_leaf());
        assert_eq!((l.first(), l.count()), (LEAF as usize - 1, 123_456));
    }

    #[test]
    fn layout_is_breadth_first_with_adjacent_children() {
        // Depth-2 tree: root splits x, its left child splits y.
        let tree = KdBuildNode::Inner {
            axis: 0,
            split: 0.5,
            children: Box::new([
                KdBuildNode::Inner {
                    axis: 1,
                    split: 0.25,
                    children: Box::new([KdBuildNode::Leaf(vec![0]), KdBuildNode::Leaf(vec![1, 2])]),
                },
                KdBuildNode::Leaf(vec![3]),
            ]),
        };
        let cell = Aabb::new(glam::Vec3::ZERO, glam::Vec3::ONE);
        let l = layout(&tree, &cell);
        assert_eq!(l.nodes.len(), 5);
        assert_eq!(l.nodes[0].first_child(), 1);
        assert!(l.nodes[2].is_leaf());
        assert_eq!(l.nodes[1].first_child(), 3);
        assert_eq!(l.parents, vec![u32::MAX, 0, 0, 1, 1]);
        assert_eq!(l.cells[3].max.y, 0.25);
        assert_eq!(l.cells[2].min.x, 0.5);
        let leaf = l.nodes[4];
        assert_eq!(
            &l.indices[leaf.first()..leaf.first() + leaf.count()],
            &[1, 2]
        );
    }
}
