//! The 4-wide node of [`super::Bvh4`] (issue 8), made by collapsing a
//! binary build tree ([`super::collapse`]), and the child reference shared
//! by the wide trees.

use super::box4::Box4;
use super::collapse::WideSlots;
use super::node_box::NodeBox;

/// A reference to a child: an inner node (`count == 0`, `index` into the
/// node array), a leaf (`count > 0` triangles from `index` in leaf order), or
/// an unused slot ([`Child4::EMPTY`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub(crate) struct Child4 {
    pub index: u32,
    pub count: u32,
}

impl Child4 {
    /// An unused slot; its box in [`Box4`] is inverted so no ray enters it.
    pub const EMPTY: Child4 = Child4 {
        index: u32::MAX,
        count: 0,
    };
}

/// A 128-byte inner node (two cache lines): the padded boxes of up to four
/// children in structure-of-arrays layout, and the child references.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub(crate) struct Node4 {
    pub boxes: Box4,
    pub child: [Child4; 4],
}

impl WideSlots for Node4 {
    const WIDTH: usize = 4;
    const EMPTY: Self = Node4 {
        boxes: Box4::EMPTY,
        child: [Child4::EMPTY; 4],
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
