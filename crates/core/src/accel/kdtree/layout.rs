//! The compact kd-tree node (8 bytes) of the per-ray-stack GPU traversal and
//! the breadth-first layout of the pointer tree into one array.

use super::tree::{split_cell, KdBuildNode};
use crate::aabb::Aabb;

const LEAF: u32 = 1 << 31;
const AXIS_SHIFT: u32 = 29;
/// Largest child offset the 28 offset bits hold.
pub(crate) const MAX_OFFSET: u32 = (1 << 28) - 1;

/// An 8-byte kd-tree node: a word with 1 bit leaf flag, 2 bits
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

    /// The node's two words as stored.
    pub fn words(self) -> [u32; 2] {
        [self.word, self.data]
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

/// Lay `root` with cell `cell` out as subtrees laid out breadth-first (the
/// per-ray-stack GPU layout): the two children of a node are always adjacent;
/// the tree is cut into subtrees of `levels` levels, each laid out
/// breadth-first, the subtrees below one after the other depth first. `levels =
/// 0` lays the whole tree out breadth-first, level by level, as one subtree.
///
/// Short subtrees keep a node's descendants for the next few levels within
/// a few cache lines (with 8-byte nodes, 3 levels below a sibling pair are
/// 14 nodes, 112 bytes), which a CPU traversal notices; the whole-tree order
/// spreads each level over the array.
pub(crate) fn layout(root: &KdBuildNode, cell: &Aabb, levels: u32) -> KdLayout {
    let mut out = KdLayout {
        nodes: vec![KdNode::default()],
        indices: Vec::new(),
        cells: vec![*cell],
        parents: vec![u32::MAX],
    };
    let levels = if levels == 0 { u32::MAX } else { levels };
    // Subtree tops waiting to be laid out, last first (a stack keeps the
    // order depth first); each entry is a sibling pair or the root.
    let mut tops: Vec<Vec<(&KdBuildNode, usize)>> = vec![vec![(root, 0)]];
    while let Some(top) = tops.pop() {
        let mut level = top;
        let mut depth = 0;
        while !level.is_empty() && depth < levels {
            let mut next = Vec::new();
            for (node, slot) in level {
                place(&mut out, node, slot, &mut next);
            }
            level = next;
            depth += 1;
        }
        // The nodes left are placed but not yet filled in: each sibling
        // pair tops a subtree of its own.
        let pairs: Vec<Vec<(&KdBuildNode, usize)>> = level.chunks(2).map(|c| c.to_vec()).collect();
        tops.extend(pairs.into_iter().rev());
    }
    out
}

/// Fill in `node` at `slot`: a leaf appends its triangles to the index
/// list; an inner node gets two adjacent slots for its children, which are
/// pushed onto `next`.
fn place<'a>(
    out: &mut KdLayout,
    node: &'a KdBuildNode,
    slot: usize,
    next: &mut Vec<(&'a KdBuildNode, usize)>,
) {
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
                next.push((c, out.nodes.len()));
                out.nodes.push(KdNode::default());
                out.cells.push(half);
                out.parents.push(slot as u32);
            }
        }
    }
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

    /// A complete tree of the given depth with distinct leaves.
    fn complete(depth: u32, next_leaf: &mut u32) -> KdBuildNode {
        if depth == 0 {
            *next_leaf += 1;
            return KdBuildNode::Leaf(vec![*next_leaf - 1]);
        }
        KdBuildNode::Inner {
            axis: (depth % 3) as u8,
            split: 0.5,
            children: Box::new([
                complete(depth - 1, next_leaf),
                complete(depth - 1, next_leaf),
            ]),
        }
    }

    /// Walk the laid-out tree from the root and list its leaves in order,
    /// checking that every child follows its parent.
    fn leaves_in_order(l: &KdLayout) -> Vec<u32> {
        let mut out = Vec::new();
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let n = l.nodes[i];
            if n.is_leaf() {
                out.extend_from_slice(&l.indices[n.first()..n.first() + n.count()]);
            } else {
                let c = n.first_child() as usize;
                assert!(c > i && l.parents[c] == i as u32 && l.parents[c + 1] == i as u32);
                stack.push(c + 1);
                stack.push(c);
            }
        }
        out
    }

    #[test]
    fn every_subtree_depth_gives_the_same_tree() {
        let tree = complete(9, &mut 0);
        let cell = Aabb::new(glam::Vec3::ZERO, glam::Vec3::ONE);
        let want: Vec<u32> = (0..512).collect();
        for levels in [0, 1, 2, 3, 6, 20] {
            let l = layout(&tree, &cell, levels);
            assert_eq!(l.nodes.len(), 1023);
            assert_eq!(leaves_in_order(&l), want, "levels {levels}");
        }
        // With 2 levels, the root's grandchildren follow its children.
        let l = layout(&tree, &cell, 2);
        assert_eq!(l.nodes[0].first_child(), 1);
        assert_eq!(l.nodes[1].first_child(), 3);
        assert_eq!(l.nodes[2].first_child(), 5);
        // The left child's subtree (3 levels down) comes before the right
        // child's: depth first between subtrees.
        assert!(l.nodes[3].first_child() < l.nodes[5].first_child());
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
        let l = layout(&tree, &cell, 0);
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
