//! The node of [`super::SurfaceBvh`]: eight children's boxes in structure
//! of arrays, their references and triangle ranges; and the traversal stack
//! its walks share.

/// Children per node.
pub const WIDTH: usize = 8;

/// A child reference with no child.
pub(crate) const EMPTY: u32 = u32::MAX;

/// An inner node: the boxes of up to eight children (structure of arrays;
/// an unused slot has the empty box, `min = +inf`, `max = -inf`), and per
/// child either an inner node (`count == 0`, `child` its index), a leaf
/// (`count > 0` triangles from `first` in leaf order, `child` the first of
/// their corner groups, `super::corner_groups`) or nothing
/// (`child == EMPTY`).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct SurfaceNode {
    pub(crate) min: [[f32; WIDTH]; 3],
    pub(crate) max: [[f32; WIDTH]; 3],
    pub(crate) child: [u32; WIDTH],
    pub(crate) count: [u32; WIDTH],
    /// Triangles below each child, as a range of the leaf order.
    pub(crate) first: [u32; WIDTH],
    pub(crate) total: [u32; WIDTH],
}

impl Default for SurfaceNode {
    fn default() -> Self {
        SurfaceNode {
            min: [[f32::INFINITY; WIDTH]; 3],
            max: [[f32::NEG_INFINITY; WIDTH]; 3],
            child: [EMPTY; WIDTH],
            count: [0; WIDTH],
            first: [0; WIDTH],
            total: [0; WIDTH],
        }
    }
}

/// Stack entries kept on the machine stack; deeper trees use the heap.
pub(crate) const SMALL_STACK: usize = 256;

/// A traversal stack of at least `need` entries, all `T::default()`:
/// `small` when it is large enough (no allocation), else `big`.
#[inline(always)]
pub(crate) fn stack_of<'a, T: Copy + Default>(
    small: &'a mut [T; SMALL_STACK],
    big: &'a mut Vec<T>,
    need: usize,
) -> &'a mut [T] {
    if need <= SMALL_STACK {
        small
    } else {
        big.resize(need, T::default());
        big
    }
}
