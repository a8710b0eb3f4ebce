//! The choice of the next child in the single-ray traversal of the wide
//! BVHs: written once for [`super::Bvh4`], [`super::Bvh8`] and
//! [`super::Bvh8`]'s interleaved walks.

use super::prefetch::prefetch_node;
use super::stack::StackPtr;
use super::wide_leaf::LeafTest;
use super::wide_node::Child4;

/// The child to visit next among `children` whose bit is set in `mask`
/// (the boxes the ray entered, at entry distances `t`), the others pushed
/// onto the stack at `st`, `sp`: near to far for nearest-hit queries (the
/// nearest next, the rest insertion-sorted straight onto the stack, farthest
/// deepest, as Embree's kernels order them; Wald et al. 2014), highest slot
/// first for any-hit queries (`ANY`); when two or more are entered, all of them are
/// fetched at once ([`super::prefetch`]; inner nodes from `nodes`, leaves
/// through `leaf`). `None` when none was entered.
///
/// With `vector_sort` (8-wide nodes on CPUs with AVX-512), three or more
/// entered children of a nearest-hit query are ordered by the sorting
/// network of [`super::sort8`] instead of the insertion sort.
///
/// # Safety
/// `st` must have room for `children.len() - 1` pushes above `sp` (the
/// stack bound that the builds check), and its [`super::stack::SLACK`]
/// beyond. `vector_sort` only where the CPU has the features of
/// [`super::sort8::push_sorted`].
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn enter<const ANY: bool, N>(
    nodes: &[N],
    children: &[Child4],
    t: &[f32],
    mask: u32,
    st: StackPtr,
    sp: &mut usize,
    leaf: &impl LeafTest,
    vector_sort: bool,
) -> Option<Child4> {
    let mut rest = mask;
    if rest == 0 {
        return None;
    }
    let i0 = rest.trailing_zeros() as usize;
    rest &= rest - 1;
    if rest == 0 {
        return Some(children[i0]);
    }
    prefetch_entered::<ANY, _>(nodes, children, mask, leaf);
    // SAFETY (every access through `st`): the caller's room; reads are of
    // entries written by the pushes here.
    if ANY {
        // Any hit ends the query: no distance order, the highest entered
        // slot next and the others pushed in slot order, so that they are
        // popped highest first, as Embree's any-hit kernels go. On shadow
        // rays this was 1.09x faster on the scatter than the lowest slot
        // first (single rays, 1 thread; BENCHMARKS.md).
        let last = 31 - mask.leading_zeros() as usize;
        let mut m = mask & !(1 << last);
        while m != 0 {
            let i = m.trailing_zeros() as usize;
            m &= m - 1;
            unsafe { st.write(*sp, children[i], t[i]) };
            *sp += 1;
        }
        return Some(children[last]);
    }
    let i1 = rest.trailing_zeros() as usize;
    rest &= rest - 1;
    if rest == 0 {
        let (near, far) = if t[i0] <= t[i1] { (i0, i1) } else { (i1, i0) };
        unsafe { st.write(*sp, children[far], t[far]) };
        *sp += 1;
        return Some(children[near]);
    }
    #[cfg(target_arch = "x86_64")]
    if vector_sort {
        if let (Ok(c), Ok(d)) = (<&[Child4; 8]>::try_from(children), <&[f32; 8]>::try_from(t)) {
            // SAFETY: the caller's features and room.
            return Some(unsafe { super::sort8::push_sorted(c, d, mask, st, sp) });
        }
    }
    let _ = vector_sort;
    // Three or more: insertion sort straight onto the stack, farthest
    // deepest, then take the nearest off the top.
    let base = *sp;
    let mut top = *sp;
    let mut push = |e: (Child4, f32)| unsafe {
        let mut j = top;
        while j > base && *st.t.add(j - 1) < e.1 {
            let (c, d) = st.read(j - 1);
            st.write(j, c, d);
            j -= 1;
        }
        st.write(j, e.0, e.1);
        top += 1;
    };
    push((children[i0], t[i0]));
    push((children[i1], t[i1]));
    while rest != 0 {
        let i = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        push((children[i], t[i]));
    }
    *sp = top - 1;
    Some(unsafe { st.read(*sp).0 })
}

/// Request every child of `children` whose bit is set in `mask` (a node's
/// entered children), inner nodes from `nodes`, leaves through `leaf`
/// (for an any-hit query, `ANY`, a leaf's first pack only; see
/// [`prefetch_with`]).
#[inline(always)]
pub(crate) fn prefetch_entered<const ANY: bool, N>(
    nodes: &[N],
    children: &[Child4],
    mut mask: u32,
    leaf: &impl LeafTest,
) {
    while mask != 0 {
        prefetch_with::<ANY, N, _>(nodes, children[mask.trailing_zeros() as usize], leaf);
        mask &= mask - 1;
    }
}

/// Request child `c`: an inner node from `nodes`, a leaf through `leaf`:
/// all its packs for a nearest-hit query, the first for an any-hit query
/// (`ANY`), which stops at the first pack with a hit, unless its leaf test
/// goes through them all ([`LeafTest::EVERY_PACK`]).
#[inline(always)]
pub(crate) fn prefetch_with<const ANY: bool, N, L: LeafTest>(nodes: &[N], c: Child4, leaf: &L) {
    if c.count == 0 {
        prefetch_node(nodes, c.index as usize);
    } else {
        // Nearest-hit queries test every pack of a leaf: all are fetched.
        // Any-hit queries stop at the first pack with a hit: only the first.
        let count = if ANY && !L::EVERY_PACK {
            c.count.min(4)
        } else {
            c.count
        };
        leaf.prefetch(c.index as usize, count as usize);
    }
}
