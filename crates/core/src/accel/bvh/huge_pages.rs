//! Transparent huge pages for the build's large arrays: the
//! references, the leaf packs and the wide nodes are asked to be backed by
//! 2 MiB pages before they are first written, as Embree's allocator asks
//! for its build arrays (`madvise(MADV_HUGEPAGE)`, Wald et al. 2014).
//!
//! Each first write to a 4 KiB page of a fresh allocation is a page fault;
//! the 1M-triangle terrain's build took about 15,000 of them per build
//! while Embree's MEDIUM build of the same mesh faulted its arrays in 2 MiB
//! pages, about 45 per build. Advised, nine builds of ours took 28,000
//! faults instead of 156,000 (the mesh's generation included), and the
//! build against Embree MEDIUM gained in three alternated rounds on the
//! AMD Zen 3 host; the traced tree also takes fewer TLB
//! entries. A hint: where the kernel offers no huge pages (or on other
//! systems) nothing changes.

/// Arrays smaller than this are left alone (they span under two huge
/// pages).
const MIN_BYTES: usize = 4 << 20;

/// Bytes of a huge page.
const HUGE: usize = 2 << 20;

/// The whole huge pages within the bytes `[start, end)`, if the range is
/// worth advising (at least [`MIN_BYTES`]).
fn huge_range(start: usize, end: usize) -> Option<(usize, usize)> {
    if end.saturating_sub(start) < MIN_BYTES {
        return None;
    }
    let lo = start.next_multiple_of(HUGE);
    let hi = end / HUGE * HUGE;
    (hi > lo).then_some((lo, hi))
}

/// Ask for huge pages under the spare capacity of `v` (from its length to
/// its capacity, shrunk to whole 2 MiB pages), which nothing has written
/// yet when the vector was just allocated.
pub(crate) fn advise<T>(v: &mut Vec<T>) {
    let size = std::mem::size_of::<T>();
    let start = v.as_mut_ptr().wrapping_add(v.len()) as usize;
    let end = (v.as_mut_ptr() as usize).wrapping_add(v.capacity() * size);
    let Some((lo, hi)) = huge_range(start, end) else {
        return;
    };
    #[cfg(target_os = "linux")]
    // SAFETY: `[lo, hi)` lies within the vector's allocation, which stays
    // mapped while `v` lives; MADV_HUGEPAGE changes how pages are backed,
    // never their contents, and a failure is harmless.
    unsafe {
        libc::madvise(lo as *mut libc::c_void, hi - lo, libc::MADV_HUGEPAGE);
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (lo, hi);
}

/// An empty vector with room for `n` elements, advised as [`advise`] says.
pub(crate) fn with_capacity<T>(n: usize) -> Vec<T> {
    let mut v = Vec::with_capacity(n);
    advise(&mut v);
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The advised range is the whole huge pages inside the given one,
    /// checked against a page-by-page count.
    #[test]
    fn advised_range_is_the_whole_huge_pages_inside() {
        let mb = 1 << 20;
        for (start, end) in [
            (0, 4 * mb),
            (1, 8 * mb),
            (3 * mb + 5, 12 * mb - 1),
            (2 * mb, 6 * mb),
            (mb, 5 * mb),
            (7, 3 * mb),
        ] {
            let pages: Vec<usize> = (0..16)
                .map(|k| k * HUGE)
                .filter(|&p| p >= start && p + HUGE <= end)
                .collect();
            let want = match (pages.first(), pages.last()) {
                (Some(&a), Some(&b)) if end - start >= MIN_BYTES => Some((a, b + HUGE)),
                _ => None,
            };
            assert_eq!(huge_range(start, end), want, "{start} {end}");
        }
    }

    /// Advising a fresh vector leaves it usable: every element written is
    /// read back.
    #[test]
    fn an_advised_vector_keeps_what_is_written() {
        let mut v: Vec<u64> = with_capacity(3 << 20);
        v.extend((0..3u64 << 20).map(|i| i.wrapping_mul(0x9e37_79b9_7f4a_7c15)));
        assert!(v
            .iter()
            .enumerate()
            .all(|(i, &x)| x == (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)));
    }
}
