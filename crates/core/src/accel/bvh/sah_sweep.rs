//! The SAH sweep over a node's bins (Wald 2007, "On fast construction of
//! SAH-based bounding volume hierarchies"): the bounds and counts of the bins
//! above each boundary are gathered from the top bin down, those below it from
//! the bottom up, and the boundary of least SAH cost over the three axes is the
//! split.
//!
//! On x86_64 the three axes are swept at once, one per SSE lane, as
//! Embree's binner evaluates them (Wald et al. 2014, "Embree: a kernel
//! framework for efficient CPU ray tracing"): each bin's three boxes are
//! transposed into six vectors (a corner coordinate of every axis), so the
//! unions, areas and costs are vertical operations in the order the
//! portable sweep does them per axis, and the split is the same to the
//! bit. The sweep runs at every node the build bins, most of them small:
//! one axis at a time it took 16% of the 1M-triangle terrain's build
//! instructions (458M of 2.94G on one thread), in the lanes 215M.

use super::binning::{Bins, Box4f, Split};

/// The SAH's intersection cost of `n` triangles in leaves tested `block`
/// at a time: `ceil(n / block)` tests, by shift where `block` is a power of
/// two (the sweep evaluates this twice per candidate split, and with the
/// integer division it took 7% more samples).
#[inline(always)]
pub(crate) fn leaf_tests(n: u32, block: u32) -> f32 {
    if block.is_power_of_two() {
        ((n >> block.trailing_zeros()) + (n & (block - 1) != 0) as u32) as f32
    } else {
        n.div_ceil(block) as f32
    }
}

impl Bins {
    /// The cheapest bin boundary of the first `nb` bins over the three axes
    /// under the SAH with [`leaf_tests`] per leaf of `n` triangles
    /// (`leaf_block` at a time) and `c_trav` per node, relative to
    /// `parent_half_area`; `None` when no boundary has references on both
    /// sides with a cost that is a number. Ties go to the lower axis, then
    /// the lower boundary. Kept out of line (see
    /// [`super::binning::partition`]).
    #[inline(never)]
    pub fn best_split(
        &mut self,
        nb: usize,
        parent_half_area: f32,
        c_trav: f32,
        leaf_block: u32,
    ) -> Option<Split> {
        let inv = 1.0 / parent_half_area.max(f32::MIN_POSITIVE);
        #[cfg(target_arch = "x86_64")]
        let best = if leaf_block.is_power_of_two() {
            // SAFETY: SSE2 is part of x86_64; the sweep reads and writes
            // the first `nb` entries of arrays that hold at least `nb`.
            unsafe { self.best_sse(nb, inv, c_trav, leaf_block.trailing_zeros()) }
        } else {
            self.best_portable(nb, inv, c_trav, leaf_block)
        };
        #[cfg(not(target_arch = "x86_64"))]
        let best = self.best_portable(nb, inv, c_trav, leaf_block);
        let (axis, bin, cost, left_count) = best?;
        let mut left = Box4f::EMPTY;
        let mut right = Box4f::EMPTY;
        for i in 0..nb {
            if i < bin {
                left = left.union(self.bins[i].boxes[axis]);
            } else {
                right = right.union(self.bins[i].boxes[axis]);
            }
        }
        Some(Split {
            axis,
            bin,
            cost,
            left_count: left_count as usize,
            left,
            right,
        })
    }

    /// The sweep one axis at a time: `(axis, boundary, cost, left count)`
    /// of the cheapest candidate, `inv` being one over the node's half
    /// area.
    pub(super) fn best_portable(
        &mut self,
        nb: usize,
        inv: f32,
        c_trav: f32,
        leaf_block: u32,
    ) -> Option<(usize, usize, f32, u32)> {
        let scratch = &mut self.scratch[..nb];
        let mut acc = [Box4f::EMPTY; 3];
        let mut cnt = [0u32; 3];
        for i in (1..nb).rev() {
            for a in 0..3 {
                acc[a] = acc[a].union(self.bins[i].boxes[a]);
                cnt[a] += self.bins[i].counts[a];
                scratch[i].right_area[a] = acc[a].half_area();
                scratch[i].right_count[a] = cnt[a];
            }
        }
        let mut best: Option<(usize, usize, f32, u32)> = None;
        for a in 0..3 {
            let mut acc = Box4f::EMPTY;
            let mut cnt = 0u32;
            for (i, right) in scratch.iter().enumerate().skip(1) {
                acc = acc.union(self.bins[i - 1].boxes[a]);
                cnt += self.bins[i - 1].counts[a];
                let rc = right.right_count[a];
                if cnt == 0 || rc == 0 {
                    continue;
                }
                let c = c_trav
                    + (acc.half_area() * leaf_tests(cnt, leaf_block)
                        + right.right_area[a] * leaf_tests(rc, leaf_block))
                        * inv;
                if !c.is_nan() && best.is_none_or(|b| c < b.2) {
                    best = Some((a, i, c, cnt));
                }
            }
        }
        best
    }

    /// [`Bins::best_portable`] with the three axes in the lanes of SSE
    /// vectors, for a power-of-two leaf block (`2^shift`): every lane
    /// computes what the portable sweep computes for its axis, in the same
    /// order, so the chosen boundary and its cost are the same.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn best_sse(
        &mut self,
        nb: usize,
        inv: f32,
        c_trav: f32,
        shift: u32,
    ) -> Option<(usize, usize, f32, u32)> {
        use std::arch::x86_64::*;
        let bins = &self.bins[..nb];
        let scratch = &mut self.scratch[..nb];
        let ld = |v: &[f32; 4]| _mm_loadu_ps(v.as_ptr());
        let zero = _mm_setzero_ps();
        // Half the surface area of the boxes of the three lanes (as
        // `Box4f::half_area`: `maxps` against 0 turns NaN into 0).
        let area = |lo: &[__m128; 3], hi: &[__m128; 3]| {
            let d: [__m128; 3] =
                std::array::from_fn(|c| _mm_max_ps(_mm_sub_ps(hi[c], lo[c]), zero));
            _mm_add_ps(
                _mm_add_ps(_mm_mul_ps(d[0], d[1]), _mm_mul_ps(d[1], d[2])),
                _mm_mul_ps(d[2], d[0]),
            )
        };
        let (inf, ninf) = (_mm_set1_ps(f32::INFINITY), _mm_set1_ps(f32::NEG_INFINITY));
        // From the top bin down: transpose every bin into the scratch and
        // gather the bins above each boundary.
        let (mut acc_lo, mut acc_hi) = ([inf; 3], [ninf; 3]);
        let mut rc = _mm_setzero_si128();
        for i in (0..nb).rev() {
            let b = &bins[i].boxes;
            let lo = transpose3(ld(&b[0].lo), ld(&b[1].lo), ld(&b[2].lo));
            let hi = transpose3(ld(&b[0].hi), ld(&b[1].hi), ld(&b[2].hi));
            let s = &mut scratch[i];
            for c in 0..3 {
                _mm_storeu_ps(s.lo[c].as_mut_ptr(), lo[c]);
                _mm_storeu_ps(s.hi[c].as_mut_ptr(), hi[c]);
            }
            if i == 0 {
                break;
            }
            for c in 0..3 {
                acc_lo[c] = _mm_min_ps(acc_lo[c], lo[c]);
                acc_hi[c] = _mm_max_ps(acc_hi[c], hi[c]);
            }
            rc = _mm_add_epi32(rc, _mm_loadu_si128(bins[i].counts.as_ptr().cast()));
            _mm_storeu_ps(s.right_area.as_mut_ptr(), area(&acc_lo, &acc_hi));
            _mm_storeu_si128(s.right_count.as_mut_ptr().cast(), rc);
        }
        // From the bottom up: the bins below each boundary, the cost, and
        // per lane the first cheapest candidate.
        let count = _mm_cvtsi32_si128(shift as i32);
        let rem = _mm_set1_epi32(((1u32 << shift) - 1) as i32);
        let (zi, one) = (_mm_setzero_si128(), _mm_set1_epi32(1));
        // `leaf_tests` of four counts: `(n >> shift) + 1 - (n & rem == 0)`.
        let tests = |n: __m128i| {
            let q = _mm_add_epi32(_mm_srl_epi32(n, count), one);
            _mm_cvtepi32_ps(_mm_add_epi32(q, _mm_cmpeq_epi32(_mm_and_si128(n, rem), zi)))
        };
        let blend = |m: __m128i, a: __m128i, b: __m128i| {
            _mm_or_si128(_mm_and_si128(m, a), _mm_andnot_si128(m, b))
        };
        let (c_trav, inv) = (_mm_set1_ps(c_trav), _mm_set1_ps(inv));
        let (mut acc_lo, mut acc_hi) = ([inf; 3], [ninf; 3]);
        let mut lc = zi;
        let (mut best_c, mut best_i, mut best_lc, mut have) = (inf, zi, zi, zi);
        for i in 1..nb {
            let below = &scratch[i - 1];
            for c in 0..3 {
                acc_lo[c] = _mm_min_ps(acc_lo[c], ld(&below.lo[c]));
                acc_hi[c] = _mm_max_ps(acc_hi[c], ld(&below.hi[c]));
            }
            lc = _mm_add_epi32(lc, _mm_loadu_si128(bins[i - 1].counts.as_ptr().cast()));
            let s = &scratch[i];
            let rcount = _mm_loadu_si128(s.right_count.as_ptr().cast());
            let cost = _mm_add_ps(
                c_trav,
                _mm_mul_ps(
                    _mm_add_ps(
                        _mm_mul_ps(area(&acc_lo, &acc_hi), tests(lc)),
                        _mm_mul_ps(ld(&s.right_area), tests(rcount)),
                    ),
                    inv,
                ),
            );
            // A candidate has references on both sides and a cost that is
            // a number; it is taken when it is the lane's first or cheaper
            // than the lane's best.
            let empty = _mm_or_si128(_mm_cmpeq_epi32(lc, zi), _mm_cmpeq_epi32(rcount, zi));
            let valid = _mm_andnot_si128(empty, _mm_castps_si128(_mm_cmpord_ps(cost, cost)));
            let cheaper = _mm_castps_si128(_mm_cmplt_ps(cost, best_c));
            let take = _mm_andnot_si128(_mm_andnot_si128(cheaper, have), valid);
            best_c = _mm_castsi128_ps(blend(
                take,
                _mm_castps_si128(cost),
                _mm_castps_si128(best_c),
            ));
            best_i = blend(take, _mm_set1_epi32(i as i32), best_i);
            best_lc = blend(take, lc, best_lc);
            have = _mm_or_si128(have, take);
        }
        let mut lanes = ([0f32; 4], [0u32; 4], [0u32; 4], [0u32; 4]);
        _mm_storeu_ps(lanes.0.as_mut_ptr(), best_c);
        _mm_storeu_si128(lanes.1.as_mut_ptr().cast(), best_i);
        _mm_storeu_si128(lanes.2.as_mut_ptr().cast(), best_lc);
        _mm_storeu_si128(lanes.3.as_mut_ptr().cast(), have);
        let mut best: Option<(usize, usize, f32, u32)> = None;
        for a in 0..3 {
            let c = lanes.0[a];
            if lanes.3[a] != 0 && best.is_none_or(|b| c < b.2) {
                best = Some((a, lanes.1[a] as usize, c, lanes.2[a]));
            }
        }
        best
    }
}

/// Rows `r0`, `r1`, `r2` (the lower or upper corners of the three axes'
/// boxes) as columns: coordinate `c` of every row in vector `c`, lane 3 a
/// copy of lane 2.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn transpose3(
    r0: std::arch::x86_64::__m128,
    r1: std::arch::x86_64::__m128,
    r2: std::arch::x86_64::__m128,
) -> [std::arch::x86_64::__m128; 3] {
    use std::arch::x86_64::*;
    let xy01 = _mm_unpacklo_ps(r0, r1);
    let xy22 = _mm_unpacklo_ps(r2, r2);
    let zw01 = _mm_unpackhi_ps(r0, r1);
    let zw22 = _mm_unpackhi_ps(r2, r2);
    [
        _mm_movelh_ps(xy01, xy22),
        _mm_movehl_ps(xy22, xy01),
        _mm_movelh_ps(zw01, zw22),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aabb::Aabb;
    use crate::accel::bvh::binning::{Mapping, PrimRef, RangeInfo};
    use crate::rng::Pcg32;
    use glam::Vec3;

    /// Bins of random references: clustered, sometimes flat along an axis
    /// (zero areas), with empty bins, and now and then infinite corners
    /// (NaN and infinite costs).
    fn random_bins(rng: &mut Pcg32, nb: usize) -> (Bins, f32) {
        let n = 1 + rng.below(200) as usize;
        let flat = rng.below(4) as usize;
        let mut refs = Vec::with_capacity(n);
        for i in 0..n {
            let mut a = rng.in_box(Vec3::ZERO, Vec3::splat(10.0));
            let size = rng.range_f32(0.0, 3.0);
            let mut b = a + rng.in_box(Vec3::ZERO, Vec3::splat(size));
            if flat < 3 {
                a[flat] = 1.0;
                b[flat] = 1.0;
            }
            if rng.below(4000) == 0 {
                b[rng.below(3) as usize] = f32::INFINITY;
            }
            refs.push(PrimRef::new(&Aabb::new(a, b), i as u32));
        }
        let info = RangeInfo::of(&refs).clean();
        let mut bins = Bins::new(32);
        bins.bin(&refs, &Mapping::new(&info.centers, nb));
        (bins, info.bounds.half_area())
    }

    /// The vector sweep chooses exactly the portable sweep's split (axis,
    /// boundary, cost, left count) on random bins, for every power-of-two
    /// leaf block, bin count and traversal cost, and `best_split` gives
    /// the same boxes either way.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn vector_sweep_equals_the_portable_sweep() {
        let mut rng = Pcg32::new(2007);
        let (mut found, mut unbounded) = (0, 0);
        for round in 0..4000 {
            let nb = 2 + rng.below(31) as usize;
            let (mut bins, area) = random_bins(&mut rng, nb);
            let block = [1u32, 2, 4, 8, 16][round % 5];
            let c_trav = [1.0f32, 0.5, 0.0][rng.below(3) as usize];
            let inv = 1.0 / area.max(f32::MIN_POSITIVE);
            let want = bins.best_portable(nb, inv, c_trav, block);
            // SAFETY: x86_64 has SSE2; the bins hold 32 entries.
            let got = unsafe { bins.best_sse(nb, inv, c_trav, block.trailing_zeros()) };
            unbounded += (area.is_infinite() || area.is_nan()) as usize;
            match (got, want) {
                (Some(g), Some(w)) => {
                    assert_eq!((g.0, g.1, g.3), (w.0, w.1, w.3), "round {round}");
                    assert_eq!(g.2, w.2, "round {round}");
                    found += 1;
                }
                (g, w) => assert_eq!(g.is_none(), w.is_none(), "round {round}: {g:?} {w:?}"),
            }
        }
        assert!(found > 3500, "{found} splits found");
        assert!(unbounded > 20, "{unbounded} nodes with infinite bounds");
    }

    /// The chosen split is the cheapest candidate by brute force: every
    /// boundary of every axis costed from the bins' boxes and counts
    /// directly, in f64, with the same tie rule.
    #[test]
    fn best_split_is_the_cheapest_boundary() {
        let mut rng = Pcg32::new(2014);
        for round in 0..2000 {
            let nb = 2 + rng.below(31) as usize;
            let (mut bins, area) = random_bins(&mut rng, nb);
            let block = [1u32, 3, 4][round % 3];
            let got = bins.best_split(nb, area, 1.0, block);
            let mut want: Option<(usize, usize, f64)> = None;
            for a in 0..3 {
                for i in 1..nb {
                    let side = |r: std::ops::Range<usize>| {
                        let b = r
                            .clone()
                            .fold(Box4f::EMPTY, |b, k| b.union(bins.bins[k].boxes[a]));
                        let n: u32 = r.map(|k| bins.bins[k].counts[a]).sum();
                        (b.half_area() as f64, n)
                    };
                    let ((la, ln), (ra, rn)) = (side(0..i), side(i..nb));
                    if ln == 0 || rn == 0 || !(la + ra).is_finite() {
                        continue;
                    }
                    let t = |n: u32| n.div_ceil(block) as f64;
                    let c = 1.0 + (la * t(ln) + ra * t(rn)) / area.max(f32::MIN_POSITIVE) as f64;
                    if want.is_none_or(|w| c < w.2 - 1e-9 * w.2.abs()) {
                        want = Some((a, i, c));
                    }
                }
            }
            let Some((a, i, c)) = want else {
                continue;
            };
            let got = got.expect("a finite candidate exists");
            let rel = |x: f64| (x - c).abs() / c.abs().max(1e-30);
            // Candidates within rounding of each other may be ordered
            // differently by f32 and f64: the chosen one must cost the same.
            assert!(
                rel(got.cost as f64) < 1e-5,
                "round {round}: {got:?} vs {a} {i} {c}"
            );
            let left: u32 = (0..got.bin).map(|k| bins.bins[k].counts[got.axis]).sum();
            assert_eq!(got.left_count, left as usize, "round {round}");
        }
    }
}
