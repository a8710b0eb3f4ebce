//! The inner loops of the binned SAH build: primitive references as two 4-float
//! corners, one binning pass for all three axes, and the in-place partition
//! (the SAH sweep over the bins is [`super::sah_sweep`]).
//!
//! This is the layout of Wald 2007 ("On fast construction of SAH-based
//! bounding volume hierarchies") as Embree's builders use it (Wald et al.
//! 2014): a reference is 32 bytes (lower corner with the triangle index in
//! its fourth lane, upper corner), the centroid is never stored (the sum of
//! the corners, twice the centroid, is used instead), the bin of every axis
//! is `k = (c - min) * scale` with the scale computed once per node, and a
//! bin keeps its bounds as lower and upper 4-float corners, so that one pass
//! over the references bins all three axes. The partition also gathers the
//! two sides' centroid bounds, so the children start knowing their bounds
//! and no node walks its references more than twice (bin, partition).

use crate::aabb::Aabb;
use glam::Vec3;

/// Four floats; the corners of boxes with the fourth lane unused (or the
/// triangle index in a [`PrimRef`]'s lower corner).
pub(crate) type V4 = [f32; 4];

/// Lane-wise minimum (the compare form, which compiles to `minps`).
#[inline(always)]
pub(crate) fn vmin(a: V4, b: V4) -> V4 {
    std::array::from_fn(|i| if a[i] < b[i] { a[i] } else { b[i] })
}

/// Lane-wise maximum (the compare form, which compiles to `maxps`).
#[inline(always)]
pub(crate) fn vmax(a: V4, b: V4) -> V4 {
    std::array::from_fn(|i| if a[i] > b[i] { a[i] } else { b[i] })
}

/// A box as two 4-float corners; the empty box has `lo = +inf`,
/// `hi = -inf`. Laid out as the two corners in order (the AVX binning
/// pass reads a box as one 8-float vector).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub(crate) struct Box4f {
    pub lo: V4,
    pub hi: V4,
}

impl Box4f {
    pub const EMPTY: Box4f = Box4f {
        lo: [f32::INFINITY; 4],
        hi: [f32::NEG_INFINITY; 4],
    };

    #[inline(always)]
    pub fn union(self, o: Box4f) -> Box4f {
        Box4f {
            lo: vmin(self.lo, o.lo),
            hi: vmax(self.hi, o.hi),
        }
    }

    #[inline(always)]
    pub fn grow(&mut self, p: V4) {
        self.lo = vmin(self.lo, p);
        self.hi = vmax(self.hi, p);
    }

    /// Half the surface area (the SAH only needs ratios); 0 when empty.
    #[inline(always)]
    pub fn half_area(&self) -> f32 {
        let d: [f32; 3] = std::array::from_fn(|i| (self.hi[i] - self.lo[i]).max(0.0));
        d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
    }

    /// As an [`Aabb`] (first three lanes).
    pub fn aabb(&self) -> Aabb {
        Aabb::new(
            Vec3::new(self.lo[0], self.lo[1], self.lo[2]),
            Vec3::new(self.hi[0], self.hi[1], self.hi[2]),
        )
    }
}

/// One triangle as the builder sees it: its bounds, with the mesh triangle
/// index stored in the fourth lane of the lower corner (32 bytes, Embree's
/// `PrimRef`, Wald et al. 2014).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(crate) struct PrimRef {
    pub lo: V4,
    pub hi: V4,
}

impl PrimRef {
    /// The reference of triangle `prim` with bounds `b`.
    pub fn new(b: &Aabb, prim: u32) -> PrimRef {
        PrimRef {
            lo: [b.min.x, b.min.y, b.min.z, f32::from_bits(prim)],
            hi: [b.max.x, b.max.y, b.max.z, 0.0],
        }
    }

    /// Mesh triangle index.
    #[inline(always)]
    pub fn prim(&self) -> u32 {
        self.lo[3].to_bits()
    }

    /// Twice the centroid (the corners' sum; lane 3 is meaningless).
    #[inline(always)]
    pub fn center2(&self) -> V4 {
        std::array::from_fn(|i| self.lo[i] + self.hi[i])
    }

    /// The bounds as a [`Box4f`] (lane 3 cleared).
    #[inline(always)]
    pub fn bounds(&self) -> Box4f {
        Box4f {
            lo: [self.lo[0], self.lo[1], self.lo[2], 0.0],
            hi: [self.hi[0], self.hi[1], self.hi[2], 0.0],
        }
    }
}

/// Bounds of a range of references and of their (doubled) centroids.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RangeInfo {
    pub bounds: Box4f,
    pub centers: Box4f,
}

impl RangeInfo {
    pub const EMPTY: RangeInfo = RangeInfo {
        bounds: Box4f::EMPTY,
        centers: Box4f::EMPTY,
    };

    /// The bounds of `refs`.
    pub fn of(refs: &[PrimRef]) -> RangeInfo {
        let mut r = RangeInfo::EMPTY;
        for p in refs {
            r.add(p);
        }
        r
    }

    #[inline(always)]
    pub fn add(&mut self, p: &PrimRef) {
        self.bounds.lo = vmin(self.bounds.lo, p.lo);
        self.bounds.hi = vmax(self.bounds.hi, p.hi);
        self.centers.grow(p.center2());
    }

    pub fn merge(self, o: RangeInfo) -> RangeInfo {
        RangeInfo {
            bounds: self.bounds.union(o.bounds),
            centers: self.centers.union(o.centers),
        }
    }

    /// Node bounds with lane 3 cleared (the lower corner's lane 3 carries
    /// triangle indices while accumulating).
    pub fn clean(mut self) -> RangeInfo {
        self.bounds.lo[3] = 0.0;
        self.bounds.hi[3] = 0.0;
        self.centers.lo[3] = 0.0;
        self.centers.hi[3] = 0.0;
        self
    }
}

/// The binning transform of a node: `bin = (c2 - lo) * scale` per axis,
/// clamped to the last bin; an axis whose centroids coincide has scale 0
/// (everything in bin 0, so it offers no split).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Mapping {
    lo: V4,
    scale: V4,
    last: usize,
}

impl Mapping {
    pub fn new(centers: &Box4f, bins: usize) -> Mapping {
        let scale = std::array::from_fn(|i| {
            let extent = centers.hi[i] - centers.lo[i];
            // 0.99999 keeps the largest centroid inside the last bin in most
            // cases; the clamp catches the rest.
            if i < 3 && extent > 0.0 && extent.is_finite() {
                bins as f32 * 0.99999 / extent
            } else {
                0.0
            }
        });
        Mapping {
            lo: centers.lo,
            scale,
            last: bins - 1,
        }
    }

    /// Bin of every axis of a reference.
    #[inline(always)]
    pub fn bins(&self, p: &PrimRef) -> [usize; 3] {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: SSE2 is part of x86_64; the loads read the 16-byte
            // arrays they are given.
            unsafe { self.bins_sse(p) }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            // The arithmetic of `index`, four lanes wide (lane 3 is clamped
            // like the others).
            let c = p.center2();
            let v: V4 = std::array::from_fn(|i| (c[i] - self.lo[i]) * self.scale[i]);
            let v = vmax(v, [0.0; 4]);
            let v = vmin(v, [self.last as f32; 4]);
            // SAFETY: every lane is finite and within `[0, last]` (NaN
            // became 0 in `vmax`, which keeps its second operand then),
            // `last < 256`.
            let k: [u32; 4] = std::array::from_fn(|i| unsafe { v[i].to_int_unchecked::<u32>() });
            [k[0] as usize, k[1] as usize, k[2] as usize]
        }
    }

    /// [`Mapping::bins`] in SSE intrinsics: the arithmetic of `index`, four
    /// lanes at once (`maxps` keeps its second operand, 0, for NaN, as
    /// `index` does; `minps` its second, `last`, at equality). Written out
    /// because the portable form compiled to a compare and a branch for the
    /// clamp and to sign extensions for the indices, and binning took 1.1x
    /// longer.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn bins_sse(&self, p: &PrimRef) -> [usize; 3] {
        use std::arch::x86_64::*;
        let k = self.bin_lanes(p);
        let lane = |k: __m128i| _mm_cvtsi128_si32(k) as u32 as usize;
        [
            lane(k),
            lane(_mm_shuffle_epi32::<0b01_01_01_01>(k)),
            lane(_mm_shuffle_epi32::<0b10_10_10_10>(k)),
        ]
    }

    /// The bins of `p` along the three axes in lanes 0–2 of a vector
    /// (lane 3 within `[0, last]` too): [`Mapping::bins`] before the
    /// indices leave the vector.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub(super) unsafe fn bin_lanes(&self, p: &PrimRef) -> std::arch::x86_64::__m128i {
        use std::arch::x86_64::*;
        let c = _mm_add_ps(_mm_loadu_ps(p.lo.as_ptr()), _mm_loadu_ps(p.hi.as_ptr()));
        let v = _mm_mul_ps(
            _mm_sub_ps(c, _mm_loadu_ps(self.lo.as_ptr())),
            _mm_loadu_ps(self.scale.as_ptr()),
        );
        let v = _mm_max_ps(v, _mm_setzero_ps());
        let v = _mm_min_ps(v, _mm_set1_ps(self.last as f32));
        _mm_cvttps_epi32(v)
    }

    /// Bin of a reference along one axis (the same arithmetic as
    /// [`Mapping::bins`], so binning and partition agree).
    #[inline(always)]
    pub fn bin(&self, p: &PrimRef, axis: usize) -> usize {
        self.index(p.lo[axis] + p.hi[axis], axis)
    }

    /// `(c - lo) * scale` clamped to `[0, last]` in floats (NaN gives 0),
    /// then truncated: no saturating conversion on the hot path.
    #[inline(always)]
    fn index(&self, c: f32, axis: usize) -> usize {
        let v = (c - self.lo[axis]) * self.scale[axis];
        let v = if v > 0.0 { v } else { 0.0 };
        let last = self.last as f32;
        let v = if v < last { v } else { last };
        // SAFETY: `v` is finite and within `[0, last]`, `last < 256`, so it
        // fits a u32 after truncation.
        unsafe { v.to_int_unchecked::<u32>() as usize }
    }

    pub fn num_bins(&self) -> usize {
        self.last + 1
    }
}

/// One bin of a node: its box along each axis and the counts of the three
/// axes, the fourth lane 0 (so that the sweep loads them as one vector).
/// 112 bytes, the boxes first (the AVX binning pass addresses a bin's box
/// and count of one axis from one offset).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub(crate) struct Bin {
    pub boxes: [Box4f; 3],
    pub counts: [u32; 4],
}

impl Bin {
    pub const EMPTY: Bin = Bin {
        boxes: [Box4f::EMPTY; 3],
        counts: [0; 4],
    };
}

/// The bins of a node (bounds and counts of the three axes per bin).
#[derive(Clone, Debug)]
pub(crate) struct Bins {
    pub(super) bins: Vec<Bin>,
    /// A second set of bins for every other reference while binning, merged
    /// into the first at the end: consecutive references often fall in the
    /// same bin (a partitioned range is spatially sorted), and two sets halve
    /// the chain of dependent read-modify-writes through memory.
    pub(super) odd: Vec<Bin>,
    /// Sweep scratch (see [`super::sah_sweep`]).
    pub(super) scratch: Vec<SweepBin>,
}

/// The best split found by the sweep.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Split {
    pub axis: usize,
    /// References whose bin along `axis` is below this go left.
    pub bin: usize,
    /// SAH cost in units of one leaf test, relative to this node's area.
    pub cost: f32,
    pub left_count: usize,
    pub left: Box4f,
    pub right: Box4f,
}

impl Bins {
    pub fn new(n: usize) -> Bins {
        Bins {
            bins: vec![Bin::EMPTY; n],
            odd: vec![Bin::EMPTY; n],
            scratch: vec![SweepBin::default(); n],
        }
    }

    /// Add `other`'s first `nb` bins to this one's (exact: min, max, sums).
    pub fn merge(&mut self, other: &Bins, nb: usize) {
        for (b, o) in self.bins[..nb].iter_mut().zip(&other.bins[..nb]) {
            for a in 0..3 {
                b.boxes[a] = b.boxes[a].union(o.boxes[a]);
                b.counts[a] += o.counts[a];
            }
        }
    }
}

/// References ahead of the one being classified that [`partition`]'s
/// blocks ask the cache for, in the direction each end moves (4 KiB; 64,
/// 128, 192 and 256 tried).
const PARTITION_AHEAD: usize = 128;

/// Ask the cache for the reference `ahead` places after `p` (before it
/// when negative); a hint, which never faults.
#[inline(always)]
pub(super) fn prefetch_ref(p: &PrimRef, ahead: isize) {
    let at = (p as *const PrimRef).wrapping_offset(ahead);
    super::prefetch::prefetch_lines(at as *const u8, 1);
}

/// Move the references whose bin along the split's axis is below the
/// split's bin to the front, and return the two sides' centroid bounds.
/// The front then holds exactly `split.left_count` references (the sweep
/// counted them with the same mapping).
///
/// Branch-free: blocks of references from both ends are classified
/// without branches and only the misplaced ones are swapped (see
/// `partition_on`); the centroid bounds grow through masks. Which side a
/// reference goes to is a coin toss for the branch predictor near the top
/// of the tree: with the two-ended version's branches (and the axis a
/// variable) the full dragon's build took 15% longer on one thread.
///
/// Kept out of line, as `Bins::best_split`: inlined into the build's node
/// step, which happened when an unrelated module changed how the crate's
/// code was split into codegen units, the scatter's build took 7% longer
/// (one thread).
#[inline(never)]
pub(crate) fn partition(refs: &mut [PrimRef], map: &Mapping, split: &Split) -> (Box4f, Box4f) {
    // One loop per axis, so that the axis is a constant inside it.
    match split.axis {
        0 => partition_on::<0>(refs, map, split),
        1 => partition_on::<1>(refs, map, split),
        _ => partition_on::<2>(refs, map, split),
    }
}

#[inline(always)]
fn partition_on<const AXIS: usize>(
    refs: &mut [PrimRef],
    map: &Mapping,
    split: &Split,
) -> (Box4f, Box4f) {
    let mut sides = SideCentroids::new();
    // Whether `r` goes left; its centroid into its side's bounds, without
    // a branch.
    let mut classify = |r: &PrimRef| {
        let left = map.bin(r, AXIS) < split.bin;
        sides.add(r, left);
        left
    };
    // Block partition (Edelkamp & Weiß 2016, "BlockQuicksort"): a block of
    // `BLOCK` references from each end is classified without branches,
    // the offsets of those on the wrong side recorded, and as many pairs
    // swapped as both blocks have. Every reference is read once to be
    // classified, and only misplaced ones move: Lomuto's scheme wrote every
    // reference twice.
    const BLOCK: usize = 64;
    let mut off_l = [0u8; BLOCK];
    let mut off_r = [0u8; BLOCK];
    let (mut start_l, mut num_l, mut start_r, mut num_r) = (0, 0, 0, 0);
    // `refs[..l]` hold left references but the unswapped offsets of the
    // block at `l`; `refs[r..]` right ones but those of the block ending
    // at `r`.
    let (mut l, mut r) = (0, refs.len());
    while r - l >= 2 * BLOCK {
        if num_l == 0 {
            start_l = 0;
            num_l = scan(
                refs[l..l + BLOCK].iter(),
                true,
                PARTITION_AHEAD as isize,
                &mut off_l,
                &mut classify,
            );
        }
        if num_r == 0 {
            start_r = 0;
            num_r = scan(
                refs[r - BLOCK..r].iter().rev(),
                false,
                -(PARTITION_AHEAD as isize),
                &mut off_r,
                &mut classify,
            );
        }
        let m = num_l.min(num_r);
        for k in 0..m {
            let a = l + off_l[start_l + k] as usize;
            let b = r - 1 - off_r[start_r + k] as usize;
            refs.swap(a, b);
        }
        (num_l, num_r) = (num_l - m, num_r - m);
        (start_l, start_r) = (start_l + m, start_r + m);
        if num_l == 0 {
            l += BLOCK;
        }
        if num_r == 0 {
            r -= BLOCK;
        }
    }
    // The rest (under two blocks, pending offsets included) by Lomuto's
    // scheme; growing the bounds again by a reference already counted
    // changes nothing (min and max).
    let mut j = l;
    for i in l..r {
        let p = refs[i];
        let left = classify(&p);
        refs[i] = refs[j];
        refs[j] = p;
        j += left as usize;
    }
    debug_assert_eq!(j, split.left_count);
    sides.bounds()
}

/// The (doubled) centroid bounds of a partition's two sides, grown one
/// reference at a time without a branch: the side's box is picked by
/// index (`v[1]` left, `v[0]` right) and grown in memory. Picking the
/// centroid or the empty box's corners for both sides by mask, in
/// registers, took about 20 instructions per reference where this takes
/// 9.
struct SideCentroids {
    v: [Box4f; 2],
}

impl SideCentroids {
    #[inline(always)]
    fn new() -> SideCentroids {
        SideCentroids {
            v: [Box4f::EMPTY; 2],
        }
    }

    /// Grow the left side's bounds by the centroid of `r` if `left`, else
    /// the right side's.
    #[inline(always)]
    fn add(&mut self, r: &PrimRef, left: bool) {
        let b = &mut self.v[left as usize];
        #[cfg(target_arch = "x86_64")]
        // SAFETY: SSE is part of x86_64; the loads and stores access `r`'s
        // corners and `b`'s, 16-byte arrays.
        unsafe {
            use std::arch::x86_64::*;
            let c = _mm_add_ps(_mm_loadu_ps(r.lo.as_ptr()), _mm_loadu_ps(r.hi.as_ptr()));
            _mm_storeu_ps(
                b.lo.as_mut_ptr(),
                _mm_min_ps(_mm_loadu_ps(b.lo.as_ptr()), c),
            );
            _mm_storeu_ps(
                b.hi.as_mut_ptr(),
                _mm_max_ps(_mm_loadu_ps(b.hi.as_ptr()), c),
            );
        }
        #[cfg(not(target_arch = "x86_64"))]
        b.grow(r.center2());
    }

    /// The left and right sides' bounds.
    fn bounds(self) -> (Box4f, Box4f) {
        (self.v[1], self.v[0])
    }
}

/// Classify the references of `block` (one of [`partition_on`]'s blocks,
/// in scan order) and record in `off` the offsets of those that do not
/// belong on the block's side (`left_side`); returns their number.
#[inline(always)]
fn scan<'a, const BLOCK: usize>(
    block: impl Iterator<Item = &'a PrimRef>,
    left_side: bool,
    ahead: isize,
    off: &mut [u8; BLOCK],
    classify: &mut impl FnMut(&PrimRef) -> bool,
) -> usize {
    let mut num = 0;
    for (i, p) in block.enumerate() {
        prefetch_ref(p, ahead);
        off[num] = i as u8;
        num += (classify(p) != left_side) as usize;
    }
    num
}

/// One bin of the vector sweep: its three boxes transposed (`lo[c]` holds
/// coordinate `c` of the lower corners of the axes' boxes, one axis per
/// lane), and the area and count of the bins at and above it.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(16))]
pub(crate) struct SweepBin {
    pub(super) lo: [[f32; 4]; 3],
    pub(super) hi: [[f32; 4]; 3],
    pub(super) right_area: [f32; 4],
    pub(super) right_count: [u32; 4],
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::rng::Pcg32;
    use glam::Vec3;

    /// References with random boxes; runs of equal boxes (the same bin many
    /// times in a row) and a few degenerate ones.
    pub(in crate::accel::bvh) fn refs(n: usize, seed: u64) -> Vec<PrimRef> {
        let mut rng = Pcg32::new(seed);
        let mut out = Vec::with_capacity(n);
        while out.len() < n {
            let a = rng.in_box(Vec3::ZERO, Vec3::splat(10.0));
            let size = rng.range_f32(0.0, 2.0);
            let b = a + rng.in_box(Vec3::ZERO, Vec3::splat(size));
            let run = 1 + rng.below(6) as usize;
            for _ in 0..run.min(n - out.len()) {
                out.push(PrimRef::new(&Aabb::new(a, b), out.len() as u32));
            }
        }
        out
    }

    /// The branch-free partition puts exactly the references of the lower
    /// bins first, keeps every reference once, and returns each side's
    /// centroid bounds as computed directly from the sides.
    #[test]
    fn partition_splits_by_bin_and_bounds_both_sides() {
        for (n, seed) in [
            (2usize, 1u64),
            (9, 2),
            (127, 5),
            (128, 6),
            (129, 7),
            (1000, 3),
            (5000, 4),
        ] {
            let r = refs(n, seed);
            let info = RangeInfo::of(&r);
            let nb = 16;
            let map = Mapping::new(&info.centers, nb);
            let mut bins = Bins::new(nb);
            bins.bin(&r, &map);
            let Some(split) = bins.best_split(nb, info.bounds.half_area(), 1.0, 1) else {
                continue;
            };
            let mut moved = r.clone();
            let (lc, rc) = partition(&mut moved, &map, &split);
            let (left, right) = moved.split_at(split.left_count);
            assert!(left.iter().all(|p| map.bin(p, split.axis) < split.bin));
            assert!(right.iter().all(|p| map.bin(p, split.axis) >= split.bin));
            let mut prims: Vec<u32> = moved.iter().map(|p| p.prim()).collect();
            prims.sort_unstable();
            assert_eq!(
                prims,
                (0..n as u32).collect::<Vec<_>>(),
                "every reference once"
            );
            for (side, got) in [(left, lc), (right, rc)] {
                let want = RangeInfo::of(side).centers;
                assert_eq!(got.lo[..3], want.lo[..3], "n {n}");
                assert_eq!(got.hi[..3], want.hi[..3], "n {n}");
            }
        }
    }
}
