//! The 8-wide node of [`super::Bvh8`]: Embree's BVH8 layout on
//! AVX machines (Wald et al. 2014), made by collapsing a binary build tree
//! ([`super::collapse`]) as the 4-wide one is.

use super::box8::Box8;
use super::wide_node::Child4;
use crate::accel::node_box::NodeBox;

/// A 256-byte inner node (four cache lines): the padded boxes of up to
/// eight children in structure-of-arrays layout, and the child references
/// (as in [`super::Bvh4`]: an inner node, a leaf or an unused slot).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub struct Node8 {
    pub(crate) boxes: Box8,
    pub(crate) child: [Child4; 8],
}

super::wide_node::wide_slots!(Node8, Box8, 8);
