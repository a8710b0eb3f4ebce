//! The binning pass of the binned SAH build (Wald 2007,
//! "On fast construction of SAH-based bounding volume hierarchies"): one
//! walk over a node's references puts each into its bin along all three
//! axes, growing the bin's box and count.
//!
//! While binning, a bin keeps its upper corner negated, so that growing a box
//! by a reference is one minimum over both corners (the reference's upper
//! corner negated once): with AVX a bin's box and a reference are one 8-float
//! vector each, and a bin grows by one `vminps` where two 4-float operations
//! and their loads and stores would be needed. The corners are turned back when
//! the pass ends, so the sweep ([`super::sah_sweep`]) and the merge see plain
//! boxes. Negation is exact and `min(-a, -b) = -max(a, b)` holds for the
//! compare-and-pick forms used here, NaN included, so the bins are the same to
//! the bit.

use super::binning::{prefetch_ref, vmin, Bin, Bins, Box4f, Mapping, PrimRef, V4};

/// References ahead of the one being binned that [`Bins::bin`] asks the
/// cache for (2 KiB). The references of a node above the caches stream from
/// memory, and the hardware prefetcher alone left the build waiting on
/// them: with the software prefetch in both loops the 1M-triangle terrain
/// and the full dragon built 1.20-1.25x faster on one thread (16, 32, 48, 64
/// and 96 references tried; on an AMD Zen 3 host 64, 128 and 256 were
/// alike).
const BIN_AHEAD: usize = 64;

/// The empty bin with its boxes' upper corners negated.
const EMPTY_NEGATED: Bin = Bin {
    boxes: [Box4f {
        lo: [f32::INFINITY; 4],
        hi: [f32::INFINITY; 4],
    }; 3],
    counts: [0; 4],
};

/// `v` negated lane by lane.
#[inline(always)]
fn neg(v: V4) -> V4 {
    v.map(|x| -x)
}

impl Bins {
    /// Bin `refs` under `map` (the first `map.num_bins()` bins are reset):
    /// even references into the first set of bins, odd ones into the
    /// second, then the second merged into the first (exact: min, max and
    /// integer sums do not depend on the order).
    pub fn bin(&mut self, refs: &[PrimRef], map: &Mapping) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU has AVX.
            unsafe { self.bin_avx(refs, map) };
            return;
        }
        self.bin_portable(refs, map);
    }

    /// Reset the first `nb` bins of both sets to empty boxes (upper
    /// corners negated) and zero counts.
    fn start(&mut self, nb: usize) {
        if self.bins.len() < nb {
            *self = Bins::new(nb);
        }
        self.bins[..nb].fill(EMPTY_NEGATED);
        self.odd[..nb].fill(EMPTY_NEGATED);
    }

    /// Merge the odd set into the first and turn the upper corners back.
    fn finish(&mut self, nb: usize) {
        for (b, o) in self.bins[..nb].iter_mut().zip(&self.odd[..nb]) {
            for a in 0..3 {
                let (x, y) = (b.boxes[a], o.boxes[a]);
                b.boxes[a] = Box4f {
                    lo: vmin(x.lo, y.lo),
                    hi: neg(vmin(x.hi, y.hi)),
                };
                b.counts[a] += o.counts[a];
            }
        }
    }

    /// The pass in 4-float operations (SSE on x86_64).
    pub(super) fn bin_portable(&mut self, refs: &[PrimRef], map: &Mapping) {
        let nb = map.num_bins();
        self.start(nb);
        let (even, odd) = (&mut self.bins[..nb], &mut self.odd[..nb]);
        // Grow bin `k` of axis `a` by a reference's lower corner and
        // negated upper corner.
        let add = |bins: &mut [Bin], k: usize, a: usize, lo, nhi| {
            // SAFETY: `Mapping::bins` clamps to `last = nb - 1`, and both
            // slices hold `nb` bins.
            let b = unsafe { bins.get_unchecked_mut(k) };
            b.boxes[a].lo = vmin(b.boxes[a].lo, lo);
            b.boxes[a].hi = vmin(b.boxes[a].hi, nhi);
            b.counts[a] += 1;
        };
        let mut pairs = refs.chunks_exact(2);
        for pair in &mut pairs {
            let (p, q) = (&pair[0], &pair[1]);
            prefetch_ref(p, BIN_AHEAD as isize);
            let (kp, kq) = (map.bins(p), map.bins(q));
            let (np, nq) = (neg(p.hi), neg(q.hi));
            for a in 0..3 {
                add(even, kp[a], a, p.lo, np);
                add(odd, kq[a], a, q.lo, nq);
            }
        }
        if let [p] = pairs.remainder() {
            for (a, k) in map.bins(p).into_iter().enumerate() {
                add(even, k, a, p.lo, neg(p.hi));
            }
        }
        self.finish(nb);
    }

    /// The pass with a reference and a bin's box in one AVX register each;
    /// the byte offsets of a reference's three bins are formed in one
    /// vector (`112 k = 128 k - 16 k`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    pub(super) unsafe fn bin_avx(&mut self, refs: &[PrimRef], map: &Mapping) {
        use std::arch::x86_64::*;
        const _: () = assert!(std::mem::size_of::<Bin>() == 112);
        let nb = map.num_bins();
        self.start(nb);
        let even = self.bins[..nb].as_mut_ptr().cast::<u8>();
        let odd = self.odd[..nb].as_mut_ptr().cast::<u8>();
        // Flips the sign of the upper corner's lanes.
        let flip = _mm256_setr_ps(0.0, 0.0, 0.0, 0.0, -0.0, -0.0, -0.0, -0.0);
        let offsets = |p: &PrimRef| {
            let k = map.bin_lanes(p);
            _mm_sub_epi32(_mm_slli_epi32::<7>(k), _mm_slli_epi32::<4>(k))
        };
        // SAFETY: `at` is `112 k` with `k < nb` (`Mapping::bin_lanes`
        // clamps to `last = nb - 1`), so the box of axis `a` (32 bytes at
        // `32 a`) and its count (at `96 + 4 a`) lie in bin `k` of a set of
        // `nb` bins that `start` made; `Bin` is `repr(C)`, its boxes two
        // 4-float corners in order, one unaligned 8-float access.
        let add = |bins: *mut u8, at: i32, a: usize, r: __m256| unsafe {
            let b = bins.add(at as usize + 32 * a).cast::<f32>();
            _mm256_storeu_ps(b, _mm256_min_ps(_mm256_loadu_ps(b), r));
            *bins.add(at as usize + 96 + 4 * a).cast::<u32>() += 1;
        };
        let three = |bins: *mut u8, at: __m128i, r: __m256| {
            add(bins, _mm_cvtsi128_si32(at), 0, r);
            add(bins, _mm_extract_epi32::<1>(at), 1, r);
            add(bins, _mm_extract_epi32::<2>(at), 2, r);
        };
        let load = |p: &PrimRef| _mm256_xor_ps(_mm256_loadu_ps(p.lo.as_ptr()), flip);
        let mut pairs = refs.chunks_exact(2);
        for pair in &mut pairs {
            let (p, q) = (&pair[0], &pair[1]);
            prefetch_ref(p, BIN_AHEAD as isize);
            let (op, oq) = (offsets(p), offsets(q));
            let (rp, rq) = (load(p), load(q));
            three(even, op, rp);
            three(odd, oq, rq);
        }
        if let [p] = pairs.remainder() {
            three(even, offsets(p), load(p));
        }
        self.finish(nb);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::binning::{tests::refs, RangeInfo};

    /// Every pass this CPU can run gives exactly the bins of one plain
    /// pass: per bin and axis the union of the boxes (`Box4f::union`,
    /// corners as they are) and the count.
    #[test]
    fn every_binning_pass_equals_one_plain_pass() {
        for (n, nb, seed) in [
            (1, 4, 1),
            (2, 4, 2),
            (7, 5, 3),
            (1000, 32, 4),
            (4097, 17, 5),
        ] {
            let r = refs(n, seed);
            let map = Mapping::new(&RangeInfo::of(&r).centers, nb);
            let mut boxes = vec![[Box4f::EMPTY; 3]; nb];
            let mut counts = vec![[0u32; 3]; nb];
            for p in &r {
                for a in 0..3 {
                    let k = map.bin(p, a);
                    boxes[k][a] = boxes[k][a].union(Box4f { lo: p.lo, hi: p.hi });
                    counts[k][a] += 1;
                }
            }
            let mut passes: Vec<(&str, Bins)> = Vec::new();
            let mut bins = Bins::new(32);
            bins.bin_portable(&r, &map);
            passes.push(("portable", bins));
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx") {
                let mut bins = Bins::new(32);
                // SAFETY: the CPU has AVX.
                unsafe { bins.bin_avx(&r, &map) };
                passes.push(("avx", bins));
            } else {
                eprintln!("no AVX on this CPU: the AVX binning pass is not tested");
            }
            for (name, bins) in &passes {
                for k in 0..nb {
                    for a in 0..3 {
                        let at = format!("{name}: n {n}, bin {k}, axis {a}");
                        assert_eq!(bins.bins[k].counts[a], counts[k][a], "{at}");
                        let (got, want) = (bins.bins[k].boxes[a], boxes[k][a]);
                        assert_eq!(got.lo.map(f32::to_bits), want.lo.map(f32::to_bits), "{at}");
                        assert_eq!(got.hi.map(f32::to_bits), want.hi.map(f32::to_bits), "{at}");
                    }
                }
            }
        }
    }
}
