//! The fast, lower-quality BVH build for dynamic scenes:
//! a linear BVH after Karras 2012 ("Maximizing parallelism in the
//! construction of BVHs, octrees, and k-d trees", HPG 2012; the LBVH idea
//! is Lauterbach et al. 2009).
//!
//! Each triangle's centroid is quantised to 10 bits per axis inside the
//! centroid bounds and its bits interleaved into a 30-bit Morton code; the
//! references are sorted by code with a stable least-significant-digit
//! radix sort (three passes of 10 bits), so equal codes keep the mesh order
//! (Karras's tie-break by index). A node over a sorted range splits where
//! the highest bit in which the range's first and last codes differ turns
//! from 0 to 1 (found by binary search: the codes are sorted), which gives
//! exactly Karras's radix tree; a range of equal codes splits at its middle.
//! Ranges of at most `max_leaf_size` triangles become one leaf when the SAH
//! (with [`super::BuildOptions::leaf_block`]) says the leaf costs no more
//! than the best subtree of them, as in the leaf collapse of Karras & Aila
//! 2013. Subtrees above the parallel threshold are built with `rayon::join`
//! and the codes are computed in parallel; the tree does not depend on the
//! number of threads.

use super::super::binning::{Box4f, PrimRef};
use super::{blocks, prim_refs, BuildNode, BuildOptions, BuildTree};
use crate::aabb::Aabb;
use crate::mesh::TriangleMesh;
use rayon::prelude::*;

/// Bits per axis of the Morton codes.
const BITS: u32 = 10;

/// Spread the low 10 bits of `v` to every third bit (bit `i` to `3 i`).
#[inline]
pub fn spread_bits(v: u32) -> u32 {
    let mut x = v & 0x3ff;
    x = (x | (x << 16)) & 0x0300_00ff;
    x = (x | (x << 8)) & 0x0300_f00f;
    x = (x | (x << 4)) & 0x030c_30c3;
    x = (x | (x << 2)) & 0x0924_9249;
    x
}

/// The 30-bit Morton code of a point quantised to `q = [x, y, z]` (10 bits
/// each): x in bits 3i+2, y in 3i+1, z in 3i (Karras 2012).
#[inline]
pub fn morton3(q: [u32; 3]) -> u32 {
    (spread_bits(q[0]) << 2) | (spread_bits(q[1]) << 1) | spread_bits(q[2])
}

/// The axis a Morton code bit belongs to.
#[inline]
fn bit_axis(bit: u32) -> u8 {
    match bit % 3 {
        2 => 0,
        1 => 1,
        _ => 2,
    }
}

/// Stable LSD radix sort of `(code, item)` pairs by 30-bit code, three
/// passes of 10 bits.
fn radix_sort(pairs: &mut Vec<(u32, u32)>) {
    let mut tmp = vec![(0u32, 0u32); pairs.len()];
    for pass in 0..3 {
        let shift = pass * BITS;
        let mut count = [0usize; 1 << BITS];
        for &(c, _) in pairs.iter() {
            count[((c >> shift) & 0x3ff) as usize] += 1;
        }
        let mut sum = 0;
        for c in count.iter_mut() {
            let k = *c;
            *c = sum;
            sum += k;
        }
        for &p in pairs.iter() {
            let d = ((p.0 >> shift) & 0x3ff) as usize;
            tmp[count[d]] = p;
            count[d] += 1;
        }
        std::mem::swap(pairs, &mut tmp);
    }
}

/// Build a linear BVH over the triangles of `mesh` (see the module
/// documentation; Karras 2012). Called by [`super::build`] for
/// [`super::BuildQuality::Fast`], with clamped options.
pub fn build(mesh: &TriangleMesh, opts: &BuildOptions) -> BuildTree {
    let (refs, info) = prim_refs(mesh);
    let n = refs.len();
    if n == 0 {
        return BuildTree {
            root: BuildNode::Leaf {
                bounds: Aabb::EMPTY,
                first: 0,
                count: 0,
            },
            order: Vec::new(),
        };
    }
    let c = info.centers;
    let scale: [f32; 3] = std::array::from_fn(|a| {
        let e = c.hi[a] - c.lo[a];
        if e > 0.0 && e.is_finite() {
            1024.0 * 0.99999 / e
        } else {
            0.0
        }
    });
    let mut pairs: Vec<(u32, u32)> = refs
        .par_iter()
        .with_min_len(4096)
        .enumerate()
        .map(|(i, r)| {
            let p = r.center2();
            let q = std::array::from_fn(|a| (((p[a] - c.lo[a]) * scale[a]) as u32).min(1023));
            (morton3(q), i as u32)
        })
        .collect();
    radix_sort(&mut pairs);
    let sorted: Vec<PrimRef> = pairs
        .par_iter()
        .with_min_len(4096)
        .map(|&(_, i)| refs[i as usize])
        .collect();
    drop(refs);
    let codes: Vec<u32> = pairs.iter().map(|p| p.0).collect();
    drop(pairs);
    let ctx = Ctx {
        refs: &sorted,
        codes: &codes,
        opts,
    };
    let (root, _) = ctx.node(0, n);
    BuildTree {
        root,
        order: sorted.iter().map(|r| r.prim()).collect(),
    }
}

struct Ctx<'a> {
    refs: &'a [PrimRef],
    codes: &'a [u32],
    opts: &'a BuildOptions,
}

impl Ctx<'_> {
    /// Where the range `lo..hi` (at least two references) splits, and the
    /// split bit's axis (`None` for a range of equal codes).
    fn split(&self, lo: usize, hi: usize) -> (usize, Option<u8>) {
        let (a, b) = (self.codes[lo], self.codes[hi - 1]);
        if a == b {
            return ((lo + hi) / 2, None);
        }
        let bit = 31 - (a ^ b).leading_zeros();
        let mask = 1 << bit;
        let mid = lo + self.codes[lo..hi].partition_point(|c| c & mask == 0);
        (mid, Some(bit_axis(bit)))
    }

    fn leaf(&self, lo: usize, hi: usize, bounds: Box4f) -> BuildNode {
        BuildNode::Leaf {
            bounds: bounds.aabb(),
            first: lo as u32,
            count: (hi - lo) as u32,
        }
    }

    /// Bounds and SAH cost (half areas × tests) of the best tree over a
    /// small range: each node either one leaf or split as the radix tree
    /// splits it.
    fn small_cost(&self, lo: usize, hi: usize) -> (Box4f, f32) {
        let n = hi - lo;
        if n == 1 {
            let b = self.refs[lo].bounds();
            return (b, b.half_area() * blocks(1, self.opts));
        }
        let (mid, _) = self.split(lo, hi);
        let (bl, cl) = self.small_cost(lo, mid);
        let (br, cr) = self.small_cost(mid, hi);
        let b = bl.union(br);
        let a = b.half_area();
        let leaf = a * blocks(n as u32, self.opts);
        (b, leaf.min(a * self.opts.traversal_cost + cl + cr))
    }

    /// The subtree over `lo..hi`, and its bounds.
    fn node(&self, lo: usize, hi: usize) -> (BuildNode, Box4f) {
        let n = hi - lo;
        if n == 1 {
            let b = self.refs[lo].bounds();
            return (self.leaf(lo, hi, b), b);
        }
        let (mid, _) = self.split(lo, hi);
        if n <= self.opts.max_leaf_size {
            let (bl, cl) = self.small_cost(lo, mid);
            let (br, cr) = self.small_cost(mid, hi);
            let b = bl.union(br);
            let a = b.half_area();
            if a * blocks(n as u32, self.opts) <= a * self.opts.traversal_cost + cl + cr {
                return (self.leaf(lo, hi, b), b);
            }
        }
        let ((l, bl), (r, br)) = if n > self.opts.parallel_threshold {
            rayon::join(|| self.node(lo, mid), || self.node(mid, hi))
        } else {
            (self.node(lo, mid), self.node(mid, hi))
        };
        let b = bl.union(br);
        let node = BuildNode::Inner {
            bounds: b.aabb(),
            children: Box::new([l, r]),
            leaf_ok: false,
        };
        (node, b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Morton code against a bit-by-bit interleave.
    #[test]
    fn morton_interleaves_bits() {
        let mut rng = crate::rng::Pcg32::new(7);
        for _ in 0..1000 {
            let q: [u32; 3] = std::array::from_fn(|_| rng.next_u32() & 0x3ff);
            let mut want = 0u32;
            for i in 0..10 {
                want |= ((q[0] >> i) & 1) << (3 * i + 2);
                want |= ((q[1] >> i) & 1) << (3 * i + 1);
                want |= ((q[2] >> i) & 1) << (3 * i);
            }
            assert_eq!(morton3(q), want, "{q:?}");
        }
    }

    /// The radix sort against the standard library's stable sort.
    #[test]
    fn radix_sort_is_stable_and_sorted() {
        let mut rng = crate::rng::Pcg32::new(3);
        for n in [0, 1, 5, 1000, 70_000] {
            // Few distinct codes, so that stability is exercised.
            let mut v: Vec<(u32, u32)> = (0..n)
                .map(|i| ((rng.next_u32() % 64) << (rng.next_u32() % 24), i))
                .collect();
            let mut want = v.clone();
            want.sort_by_key(|p| p.0);
            radix_sort(&mut v);
            assert_eq!(v, want, "n = {n}");
        }
    }

    /// Split positions: every code left of the split has the highest
    /// differing bit clear, every code right of it set.
    #[test]
    fn split_at_highest_differing_bit() {
        let codes = vec![0b0001, 0b0011, 0b0100, 0b0101, 0b1000, 0b1000];
        let refs = vec![PrimRef::new(&Aabb::new(glam::Vec3::ZERO, glam::Vec3::ONE), 0); 6];
        let opts = BuildOptions::default();
        let ctx = Ctx {
            refs: &refs,
            codes: &codes,
            opts: &opts,
        };
        assert_eq!(ctx.split(0, 6), (4, Some(bit_axis(3))));
        assert_eq!(ctx.split(0, 4), (2, Some(bit_axis(2))));
        assert_eq!(ctx.split(0, 2), (1, Some(bit_axis(1))));
        assert_eq!(ctx.split(4, 6), (5, None));
    }
}
