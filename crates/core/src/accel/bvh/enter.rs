//! The choice of the next child in the single-ray traversal of the wide
//! BVHs (issue 8): written once for [`super::Bvh4`], [`super::Bvh8`] and
//! [`super::Bvh8`]'s interleaved walks.

use super::node4::Child4;
use super::prefetch::prefetch_entered;
use super::wide_leaf::LeafTest;

/// The child to visit next among `children` whose bit is set in `mask`
/// (the boxes the ray entered, at entry distances `t`), the others pushed
/// onto the stack at `st`, `sp`: near to far for nearest-hit queries (the
/// nearest next, the rest insertion-sorted straight onto the stack, farthest
/// deepest, as Embree's kernels order them; Wald et al. 2014), highest slot
/// first for any-hit queries (`ANY`); when two or more are entered, all of them are
/// fetched at once ([`super::prefetch`]; inner nodes from `nodes`, leaves
/// through `leaf`). `None` when none was entered.
///
/// # Safety
/// `st` must have room for `children.len() - 1` pushes above `sp` (the
/// stack bound that the builds check).
#[inline(always)]
pub(crate) unsafe fn enter<const ANY: bool, N>(
    nodes: &[N],
    children: &[Child4],
    t: &[f32],
    mask: u32,
    st: *mut (Child4, f32),
    sp: &mut usize,
    leaf: &impl LeafTest,
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
        // first (single rays, 1 thread; BENCHMARKS.md, step 3u).
        let last = 31 - mask.leading_zeros() as usize;
        let mut m = mask & !(1 << last);
        while m != 0 {
            let i = m.trailing_zeros() as usize;
            m &= m - 1;
            unsafe { st.add(*sp).write((children[i], t[i])) };
            *sp += 1;
        }
        return Some(children[last]);
    }
    let i1 = rest.trailing_zeros() as usize;
    rest &= rest - 1;
    if rest == 0 {
        let (near, far) = if t[i0] <= t[i1] { (i0, i1) } else { (i1, i0) };
        unsafe { st.add(*sp).write((children[far], t[far])) };
        *sp += 1;
        return Some(children[near]);
    }
    // Three or more: insertion sort straight onto the stack, farthest
    // deepest, then take the nearest off the top.
    let base = *sp;
    let mut top = *sp;
    let mut push = |e: (Child4, f32)| unsafe {
        let mut j = top;
        while j > base && (*st.add(j - 1)).1 < e.1 {
            st.add(j).write(st.add(j - 1).read());
            j -= 1;
        }
        st.add(j).write(e);
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
    Some(unsafe { st.add(*sp).read().0 })
}
