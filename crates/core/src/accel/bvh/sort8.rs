//! A node's entered children sorted far to near in vector registers and
//! pushed in two stores: the child choice of [`super::Bvh8`]'s
//! nearest-hit walks on CPUs with AVX-512, where three or more of a node's
//! eight children are entered. Embree's AVX-512 kernels order a node's hits
//! the same way, with a sorting network over keys that carry the entry
//! distance and the slot (Wald et al. 2014); the scalar insertion sort of
//! [`super::enter`] mispredicts on incoherent rays.
//!
//! A key is 64 bits: the entry distance's bits made order-preserving as an
//! unsigned integer in the high half, `7 - slot` in the low half. Sorted in
//! descending order, they give exactly the order of the insertion sort:
//! farther children deeper, and among equal distances the higher slot
//! nearer the top. So the walk visits the same nodes in the same order, and
//! every answer is the scalar path's bit for bit (ties between triangles
//! included). Children not entered get key 0 and sort last.

use super::stack::StackPtr;
use super::wide_node::Child4;

/// The partner lane of each lane in the six layers of the 19-comparator
/// sorting network for eight keys (Knuth, TAOCP vol. 3, 5.3.4), and which
/// lanes keep the larger key (the lower lane of each pair: far to near).
#[cfg(target_arch = "x86_64")]
const LAYERS: [([i64; 8], u8); 6] = [
    ([2, 3, 0, 1, 6, 7, 4, 5], 0x33),
    ([4, 5, 6, 7, 0, 1, 2, 3], 0x0F),
    ([1, 0, 3, 2, 5, 4, 7, 6], 0x55),
    ([0, 1, 4, 5, 2, 3, 6, 7], 0x0C),
    ([0, 4, 2, 6, 1, 5, 3, 7], 0x0A),
    ([0, 2, 1, 4, 3, 6, 5, 7], 0x2A),
];

/// Sort eight unsigned 64-bit keys in descending order: one permutation,
/// min, max and blend per layer of [`LAYERS`].
///
/// # Safety
/// The CPU must support AVX-512 F.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
pub(crate) unsafe fn sort_descending(
    keys: std::arch::x86_64::__m512i,
) -> std::arch::x86_64::__m512i {
    use std::arch::x86_64::*;
    let mut k = keys;
    for (perm, keep_max) in LAYERS {
        // SAFETY: AVX-512 F (the caller); `perm` is eight 64-bit lane
        // indices.
        let p =
            _mm512_permutexvar_epi64(unsafe { _mm512_loadu_si512(perm.as_ptr() as *const _) }, k);
        k = _mm512_mask_blend_epi64(keep_max, _mm512_min_epu64(k, p), _mm512_max_epu64(k, p));
    }
    k
}

/// The sort key of entry distances `t` (eight floats' bits): flipped so
/// that unsigned order is the floats' order (negative ones all bits,
/// others the sign bit), shifted into the high half, `7 - slot` below.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f")]
#[inline]
unsafe fn keys(bits: std::arch::x86_64::__m256i) -> std::arch::x86_64::__m512i {
    use std::arch::x86_64::*;
    let flip = _mm256_or_si256(_mm256_srai_epi32::<31>(bits), _mm256_set1_epi32(i32::MIN));
    let order = _mm512_cvtepu32_epi64(_mm256_xor_si256(bits, flip));
    _mm512_or_si512(
        _mm512_slli_epi64::<32>(order),
        _mm512_setr_epi64(7, 6, 5, 4, 3, 2, 1, 0),
    )
}

/// Push the children of `children` whose bit is set in `mask` (at least
/// one; the entry distances in `t`) onto the stack at `st`, `sp`, farthest
/// deepest, and return the nearest instead of pushing it, exactly as
/// [`super::enter`]'s insertion sort does.
///
/// # Safety
/// The CPU must support AVX2, AVX-512 F and VL. The stack must have room
/// for eight entries from `sp` (its [`super::stack::SLACK`] past the
/// traversal's bound).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512vl")]
#[inline]
pub(crate) unsafe fn push_sorted(
    children: &[Child4; 8],
    t: &[f32; 8],
    mask: u32,
    st: StackPtr,
    sp: &mut usize,
) -> Child4 {
    use std::arch::x86_64::*;
    debug_assert!(mask != 0 && mask < 256);
    // SAFETY: the features are the caller's; the loads read the 32 bytes of
    // `t` and the 64 of `children` (`Child4` is two `u32`, `repr(C)`); the
    // stores write eight entries from `sp`, within the caller's room.
    unsafe {
        let bits = _mm256_loadu_si256(t.as_ptr() as *const __m256i);
        let sorted = sort_descending(_mm512_maskz_mov_epi64(mask as u8, keys(bits)));
        let order = _mm512_sub_epi64(
            _mm512_set1_epi64(7),
            _mm512_and_si512(sorted, _mm512_set1_epi64(7)),
        );
        let kids = _mm512_loadu_si512(children.as_ptr() as *const _);
        _mm512_storeu_si512(
            st.child.add(*sp) as *mut _,
            _mm512_permutexvar_epi64(order, kids),
        );
        let dist = _mm256_permutevar8x32_epi32(bits, _mm512_cvtepi64_epi32(order));
        _mm256_storeu_si256(st.t.add(*sp) as *mut __m256i, dist);
        let near = mask.count_ones() as usize - 1;
        let near_slot = _mm_cvtsi128_si64(_mm512_castsi512_si128(_mm512_permutexvar_epi64(
            _mm512_set1_epi64(near as i64),
            order,
        )));
        *sp += near;
        children[near_slot as usize]
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::accel::bvh::stack::Stack;
    use crate::rng::Pcg32;
    use std::arch::x86_64::*;

    fn avx512() -> bool {
        let ok = is_x86_feature_detected!("avx2")
            && is_x86_feature_detected!("avx512f")
            && is_x86_feature_detected!("avx512vl");
        if !ok {
            eprintln!("note: no AVX-512 on this CPU: the vector child sort and its network are not tested here");
        }
        ok
    }

    fn sort(keys: [u64; 8]) -> [u64; 8] {
        let mut out = [0u64; 8];
        // SAFETY: AVX-512 checked by the callers; loads and stores of local
        // arrays of eight `u64`.
        unsafe {
            let v = sort_descending(_mm512_loadu_si512(keys.as_ptr() as *const _));
            _mm512_storeu_si512(out.as_mut_ptr() as *mut _, v);
        }
        out
    }

    /// The network sorts every 0-1 input (so every input, by the 0-1
    /// principle), and random keys with ties and the top bit set, as the
    /// standard library's sort does; the layers pair lanes and keep the
    /// larger key in the lower lane of each pair.
    #[test]
    fn network_sorts_like_the_standard_library() {
        if !avx512() {
            return;
        }
        for (perm, keep_max) in LAYERS {
            let mut m = 0;
            for (i, &j) in perm.iter().enumerate() {
                assert_eq!(perm[j as usize], i as i64, "not an involution: {perm:?}");
                if (j as usize) > i {
                    m |= 1 << i;
                }
            }
            assert_eq!(m, keep_max, "{perm:?}");
        }
        for bits in 0..256u32 {
            let keys: [u64; 8] = std::array::from_fn(|i| ((bits >> i) & 1) as u64);
            let mut want = keys;
            want.sort_unstable_by(|a, b| b.cmp(a));
            assert_eq!(sort(keys), want, "{keys:?}");
        }
        let mut rng = Pcg32::new(5);
        for _ in 0..20_000 {
            let keys: [u64; 8] = std::array::from_fn(|_| match rng.below(3) {
                0 => rng.below(4) as u64,
                1 => (rng.next_u32() as u64) << 32 | rng.next_u32() as u64,
                _ => 1 << 63 | rng.below(16) as u64,
            });
            let mut want = keys;
            want.sort_unstable_by(|a, b| b.cmp(a));
            assert_eq!(sort(keys), want, "{keys:?}");
        }
    }

    /// For random masks and distances (ties, zeros and negative distances
    /// included), the stack receives exactly the entered children but the
    /// nearest, far to near, each with its own distance bit for bit, and the
    /// nearest comes back: the order of the scalar insertion sort of
    /// `enter` (equal distances: the higher slot nearer the top).
    #[test]
    fn pushes_entered_children_far_to_near() {
        if !avx512() {
            return;
        }
        let mut rng = Pcg32::new(6);
        for _ in 0..20_000 {
            let children: [Child4; 8] = std::array::from_fn(|i| Child4 {
                index: rng.next_u32(),
                count: i as u32,
            });
            let t: [f32; 8] = std::array::from_fn(|_| match rng.below(5) {
                0 => 0.0,
                1 => 1.5,
                2 => -rng.range_f32(0.0, 2.0),
                _ => rng.range_f32(0.0, 100.0),
            });
            let mask = 1 + rng.below(255);
            let below = rng.below(20) as usize;
            let mut stack = Stack::<32>::new();
            let st = stack.ptr();
            let mut sp = below;
            // SAFETY: AVX-512 checked above; `below + 8 <= 32 + SLACK`.
            let near = unsafe { push_sorted(&children, &t, mask, st, &mut sp) };
            // The insertion sort's order, spelled out: descending distance,
            // then ascending slot (a stable sort of the slots in order).
            let mut want: Vec<usize> = (0..8).filter(|i| mask & (1 << i) != 0).collect();
            want.sort_by(|&a, &b| t[b].partial_cmp(&t[a]).unwrap());
            assert_eq!(sp, below + want.len() - 1);
            assert_eq!(near, children[*want.last().unwrap()]);
            for (j, &slot) in want[..want.len() - 1].iter().enumerate() {
                // SAFETY: written by the push.
                let (c, d) = unsafe { st.read(below + j) };
                assert_eq!(c, children[slot], "{mask:b} {t:?}");
                assert_eq!(d.to_bits(), t[slot].to_bits());
            }
        }
    }
}
