//! The 8-wide node of [`super::Bvh8`] and its construction by collapsing a
//! binary build tree (issue 8): Embree's BVH8 layout on AVX machines (Wald
//! et al. 2014), made the way [`super::node4`] makes the 4-wide tree.

use super::box8::Box8;
use super::collapse::WideSlots;
use super::node4::Child4;
use super::node_box::NodeBox;

/// A 256-byte inner node (four cache lines): the padded boxes of up to
/// eight children in structure-of-arrays layout, and the child references
/// (as in [`super::Bvh4`]: an inner node, a leaf or an unused slot).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub(crate) struct Node8 {
    pub boxes: Box8,
    pub child: [Child4; 8],
}

impl WideSlots for Node8 {
    const WIDTH: usize = 8;
    const EMPTY: Self = Node8 {
        boxes: Box8::EMPTY,
        child: [Child4::EMPTY; 8],
    };
    fn set_slot(&mut self, slot: usize, b: &NodeBox, child: Child4) {
        self.boxes.set(slot, b);
        self.child[slot] = child;
    }
    fn children_mut(&mut self) -> &mut [Child4] {
        &mut self.child
    }
    #[cfg(test)]
    fn slot(&self, slot: usize) -> (crate::aabb::Aabb, Child4) {
        (self.boxes.get(slot), self.child[slot])
    }
}
