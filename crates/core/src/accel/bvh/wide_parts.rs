//! The parts of a wide BVH ([`super::Bvh4`], [`super::Bvh8`]) as one view,
//! so that the operations on a built tree that do not traverse it — the
//! refit of [`super::refit`] and the saved files of [`super::persist`] —
//! see its arrays without its traversal state.

use super::box4::Box4;
use super::box8::Box8;
use super::node4::Node4;
use super::node8::Node8;
use super::tri4::Tri4;
use super::wide_leaf::Leaves;
use super::wide_node::Child4;
use super::words::Words;
use crate::aabb::Aabb;
use crate::accel::node_box::NodeBox;
use crate::accel::{AccelKind, AccelStats};
use crate::tri::TriangleTest;

/// A wide inner node seen slot by slot.
pub trait WideNode: super::wide_node::WideSlots + Words {
    /// The child references, every slot.
    fn children(&self) -> &[Child4];
    /// The (padded) box stored in slot `slot`.
    fn slot_box(&self, slot: usize) -> Aabb;
    /// Store the padded box `b` in slot `slot`, keeping its reference.
    fn set_box(&mut self, slot: usize, b: &NodeBox);
    /// Reset the box of slot `slot` to the inverted box no ray enters.
    fn clear_box(&mut self, slot: usize);
}

macro_rules! wide_node {
    ($node:ty, $boxes:ident, $width:literal) => {
        impl WideNode for $node {
            fn children(&self) -> &[Child4] {
                &self.child
            }
            fn slot_box(&self, slot: usize) -> Aabb {
                self.boxes.get(slot)
            }
            fn set_box(&mut self, slot: usize, b: &NodeBox) {
                self.boxes.set(slot, b);
            }
            fn clear_box(&mut self, slot: usize) {
                for row in 0..6 {
                    self.boxes.planes[row][slot] = $boxes::EMPTY.planes[row][slot];
                }
            }
        }
        // SAFETY: `repr(C)`, 32-bit float box planes then `Child4`s (two
        // `u32`), sizes multiples of the 64-byte alignment, so no padding.
        unsafe impl Words for $node {}
        const _: () = assert!(std::mem::size_of::<$node>() == $width * 32);
    };
}
wide_node!(Node4, Box4, 4);
wide_node!(Node8, Box8, 8);

// SAFETY: `repr(C)`, 36 + 12 `f32` and 4 `u32` words, 192 bytes at a
// 64-byte alignment, so no padding.
unsafe impl Words for Tri4 {}
const _: () = assert!(std::mem::size_of::<Tri4>() == 192);

/// The 32-bit words of `v`, writable (to fix their byte order).
pub(crate) fn words_of_mut<W: Words>(v: &mut [W]) -> &mut [u32] {
    // SAFETY: `Words` types are whole 32-bit words at an alignment of at
    // least four, and every bit pattern is a value.
    unsafe {
        std::slice::from_raw_parts_mut(v.as_mut_ptr().cast::<u32>(), std::mem::size_of_val(v) / 4)
    }
}

/// `n` values of `W`, every bit zero: allocated zeroed, so that a vector
/// about to be overwritten (read from a file) costs no pass of its own,
/// and backed by huge pages where the system offers them (as the build's
/// arrays are, `huge_pages`).
pub(crate) fn zeroed<W: Words>(n: usize) -> Vec<W> {
    if n == 0 || std::mem::size_of::<W>() == 0 {
        return Vec::new();
    }
    let layout = std::alloc::Layout::array::<W>(n).expect("vector too large");
    // SAFETY: the layout is non-zero-sized; the vector takes the
    // allocation with the same layout, empty, is advised before anything
    // touches it, and then holds `n` all-zero values, which are valid
    // `Words` values.
    unsafe {
        let p = std::alloc::alloc_zeroed(layout).cast::<W>();
        if p.is_null() {
            std::alloc::handle_alloc_error(layout);
        }
        let mut v = Vec::from_raw_parts(p, 0, n);
        super::huge_pages::advise(&mut v);
        v.set_len(n);
        v
    }
}

/// A wide BVH's parts, borrowed.
pub(crate) struct PartsRef<'a, N, T: TriangleTest> {
    pub nodes: &'a [N],
    pub root_box: &'a NodeBox,
    pub root: Child4,
    pub leaves: &'a Leaves<T>,
    pub stats: &'a AccelStats,
    pub built_sah: Option<f64>,
}

/// A wide BVH's parts, the geometric ones writable (the topology is not).
pub(crate) struct PartsMut<'a, N, T: TriangleTest> {
    pub nodes: &'a mut [N],
    pub root_box: &'a mut NodeBox,
    pub root: Child4,
    pub leaves: &'a mut Leaves<T>,
    pub stats: &'a mut AccelStats,
    pub built_sah: &'a mut Option<f64>,
}

/// A wide BVH's parts, owned: what a loaded file makes a tree of.
pub(crate) struct PartsOwned<N, T: TriangleTest> {
    pub nodes: Vec<N>,
    pub root_box: NodeBox,
    pub root: Child4,
    pub leaves: Leaves<T>,
    pub stats: AccelStats,
    /// Most traversal stack entries a ray can need.
    pub stack: usize,
    pub built_sah: Option<f64>,
}

/// A wide BVH ([`super::WideBvh`] of either width) through its parts.
pub(crate) trait WideParts: Sized {
    /// The inner node.
    type Node: WideNode;
    /// The triangle test.
    type Test: TriangleTest;
    /// The structure's name in the registry.
    const KIND: AccelKind;
    /// Traversal stack entries the tree may need at most (exclusive).
    const STACK: usize;
    /// The parts, borrowed.
    fn parts(&self) -> PartsRef<'_, Self::Node, Self::Test>;
    /// The parts, geometry writable.
    fn parts_mut(&mut self) -> PartsMut<'_, Self::Node, Self::Test>;
    /// The tree of checked parts (`parts.stack < Self::STACK`).
    fn from_parts(parts: PartsOwned<Self::Node, Self::Test>) -> Self;
}
