//! `W` boxes in structure-of-arrays layout and their ray test, all `W` at
//! once: the box half of the Embree-style wide BVH (Wald et al. 2014), one
//! type for both widths ([`super::box4`] and [`super::box8`] add the SIMD
//! kernels of each).
//!
//! The slab test is the one of [`NodeBox::entry`], term for term, with one
//! change that costs nothing: instead of `min`/`max` of the two plane
//! distances per axis, the ray picks the near and far plane by the sign of
//! its reciprocal direction once (plane rows `2·axis` and `2·axis + 1`). For
//! finite distances this gives bit-identical results, since `(lo - o)·d ≤
//! (hi - o)·d` for `lo ≤ hi` and `d > 0` in rounded arithmetic too. The one
//! place where a NaN can appear, `0·∞` for an axis-parallel ray whose origin
//! lies on a slab plane, is dropped (the axis then constrains nothing), so
//! that case counts as a hit where [`NodeBox::entry`] may count a miss: the
//! test accepts a superset of [`NodeBox::entry`]'s boxes and so stays
//! conservative with respect to the triangle tests (the boxes hold their
//! triangles' tolerance bands, see [`crate::tri::TriangleTest::reach`]). The exit
//! is widened by [`NodeBox::ROBUST_EXIT`]. No fused multiply-add is used:
//! its single rounding would change the distances and void that argument.
//!
//! The scalar kernel here spells out the SSE `minps`/`maxps` semantics (the
//! second operand when either is NaN), so every kernel gives identical hit
//! masks and entry distances, which the tests of `node_width.rs` check.

use super::ray_box::RayBox;
use crate::aabb::Aabb;
use crate::accel::node_box::NodeBox;
use glam::Vec3;

/// `W` boxes, `planes[2·axis]` holding the `W` minima along `axis` and
/// `planes[2·axis + 1]` the maxima. An unused slot holds the inverted box
/// `[+∞, -∞]`, which every ray misses. Aligned for 256-bit loads of eight
/// lanes (a row of four is 16-byte aligned by the same token).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct Boxes<const W: usize> {
    pub(crate) planes: [[f32; W]; 6],
}

impl<const W: usize> Default for Boxes<W> {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// Which of the `W` boxes a ray enters, and where.
#[derive(Clone, Copy, Debug)]
pub struct Hits<const W: usize> {
    /// Bit `i` set when box `i` is entered within the interval.
    pub mask: u32,
    /// Entry distance into box `i`; meaningful only where `mask` has bit `i`.
    pub t: [f32; W],
}

#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
/// `maxps` on one lane: `b` when either operand is NaN.
#[inline(always)]
pub(super) fn max_sse(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
/// `minps` on one lane: `b` when either operand is NaN.
#[inline(always)]
pub(super) fn min_sse(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

impl<const W: usize> Boxes<W> {
    /// `W` unused slots.
    pub const EMPTY: Self = Boxes {
        planes: [
            [f32::INFINITY; W],
            [f32::NEG_INFINITY; W],
            [f32::INFINITY; W],
            [f32::NEG_INFINITY; W],
            [f32::INFINITY; W],
            [f32::NEG_INFINITY; W],
        ],
    };

    /// Store `b` (already padded) in slot `slot`.
    pub fn set(&mut self, slot: usize, b: &NodeBox) {
        for a in 0..3 {
            self.planes[2 * a][slot] = b.min[a];
            self.planes[2 * a + 1][slot] = b.max[a];
        }
    }

    /// The box in slot `slot`.
    pub fn get(&self, slot: usize) -> Aabb {
        let p = &self.planes;
        Aabb::new(
            Vec3::new(p[0][slot], p[2][slot], p[4][slot]),
            Vec3::new(p[1][slot], p[3][slot], p[5][slot]),
        )
    }

    /// The portable kernel, one box after the other.
    #[inline(always)]
    pub fn entries_scalar(&self, r: &RayBox, tnear: f32, tfar: f32) -> Hits<W> {
        let mut out = Hits {
            mask: 0,
            t: [0.0; W],
        };
        for i in 0..W {
            let mut enter = tnear;
            let mut exit = f32::INFINITY;
            // Same operand order as the SIMD kernels: z, then y, then x.
            for a in (0..3).rev() {
                let n = r.near[a];
                let tn = (self.planes[n][i] - r.origin[a]) * r.inv_dir[a];
                let tf = (self.planes[n ^ 1][i] - r.origin[a]) * r.inv_dir[a];
                enter = max_sse(tn, enter);
                exit = min_sse(tf, exit);
            }
            let exit = min_sse(exit * NodeBox::ROBUST_EXIT, tfar);
            out.t[i] = enter;
            if enter <= exit {
                out.mask |= 1 << i;
            }
        }
        out
    }

    /// The SSE test of the four boxes in slots `first..first + 4` (`first`
    /// a multiple of four below `W`): 6 subtractions, 6 multiplications,
    /// 3 max, 4 min and one compare. Writes their entry distances to
    /// `t[first..first + 4]` and returns their bits of the mask, from bit 0.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub(super) fn sse_quad(
        &self,
        first: usize,
        r: &RayBox,
        tnear: f32,
        tfar: f32,
        t: &mut [f32; W],
    ) -> u32 {
        use std::arch::x86_64::*;
        assert!(first.is_multiple_of(4) && first + 4 <= W);
        // SAFETY: SSE is part of the x86_64 baseline. Each load reads four
        // floats at offset `first` of a row of `planes`, in bounds by the
        // assertion and 16-byte aligned (`Boxes` is `align(32)`, rows of a
        // multiple of four floats, `first` a multiple of four); the store
        // writes four floats of `t` at `first` (unaligned store).
        unsafe {
            let p = &self.planes;
            let mut enter = _mm_set1_ps(tnear);
            let mut exit = _mm_set1_ps(f32::INFINITY);
            for a in (0..3).rev() {
                let n = r.near[a];
                let o = _mm_set1_ps(r.origin[a]);
                let id = _mm_set1_ps(r.inv_dir[a]);
                let lo = _mm_load_ps(p[n].as_ptr().add(first));
                let hi = _mm_load_ps(p[n ^ 1].as_ptr().add(first));
                enter = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(lo, o), id), enter);
                exit = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(hi, o), id), exit);
            }
            let exit = _mm_min_ps(
                _mm_mul_ps(exit, _mm_set1_ps(NodeBox::ROBUST_EXIT)),
                _mm_set1_ps(tfar),
            );
            _mm_storeu_ps(t.as_mut_ptr().add(first), enter);
            _mm_movemask_ps(_mm_cmple_ps(enter, exit)) as u32
        }
    }
}
