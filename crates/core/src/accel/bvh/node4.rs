//! The 4-wide node of [`super::Bvh4`].

use super::box4::Box4;
use super::wide_node::Child4;
use crate::accel::node_box::NodeBox;

/// A 128-byte inner node (two cache lines): the padded boxes of up to four
/// children in structure-of-arrays layout, and the child references.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub struct Node4 {
    pub(crate) boxes: Box4,
    pub(crate) child: [Child4; 4],
}

super::wide_node::wide_slots!(Node4, Box4, 4);
