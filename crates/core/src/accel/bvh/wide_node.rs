//! What every wide node shares: the child reference [`Child4`], the
//! [`WideSlots`] interface through which the builds fill a node of either
//! width, and the macro that implements it for a node type.

use crate::accel::node_box::NodeBox;

/// A reference to a child: an inner node (`count == 0`, `index` into the
/// node array), a leaf (`count > 0` triangles from `index` in leaf order), or
/// an unused slot ([`Child4::EMPTY`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct Child4 {
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

/// A wide inner node the collapse fills: [`super::node4::Node4`] or
/// [`super::node8::Node8`].
pub trait WideSlots: Copy + Send + Sync {
    /// Child slots per node.
    const WIDTH: usize;
    /// A node with every slot unused (inverted boxes, [`Child4::EMPTY`]).
    const EMPTY: Self;
    /// Put `child`, whose padded box is `b`, in slot `slot`.
    fn set_slot(&mut self, slot: usize, b: &NodeBox, child: Child4);
    /// The child references, every slot.
    fn children_mut(&mut self) -> &mut [Child4];
    /// The box and reference in slot `slot`.
    #[cfg(test)]
    fn slot(&self, slot: usize) -> (crate::aabb::Aabb, Child4);
}

/// [`WideSlots`] for a node type with fields `boxes` (a box row type with
/// `EMPTY`, `set` and `get`) and `child` (`[Child4; WIDTH]`).
macro_rules! wide_slots {
    ($node:ty, $boxes:ident, $width:literal) => {
        impl $crate::accel::bvh::wide_node::WideSlots for $node {
            const WIDTH: usize = $width;
            const EMPTY: Self = Self {
                boxes: $boxes::EMPTY,
                child: [Child4::EMPTY; $width],
            };
            fn set_slot(&mut self, slot: usize, b: &NodeBox, child: Child4) {
                self.boxes.set(slot, b);
                self.child[slot] = child;
            }
            fn children_mut(&mut self) -> &mut [Child4] {
                &mut self.child
            }
            #[cfg(test)]
            fn slot(&self, slot: usize) -> ($crate::aabb::Aabb, Child4) {
                (self.boxes.get(slot), self.child[slot])
            }
        }
    };
}
pub(crate) use wide_slots;
