//! The 4-wide node of [`super::Bvh4`], made by collapsing a
//! binary build tree ([`super::collapse`]), and the child reference shared
//! by the wide trees.

use super::box4::Box4;
use crate::accel::node_box::NodeBox;

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

super::collapse::wide_slots!(Node4, Box4, 4);
