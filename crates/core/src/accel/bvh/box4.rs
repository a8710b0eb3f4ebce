//! Four boxes in structure-of-arrays layout and their ray test, all four at
//! once: with SSE on x86_64 (baseline there, so no run-time detection is
//! needed), with a scalar loop elsewhere. This is the box half of the
//! Embree-style 4-wide BVH ([`super::Bvh4`]).
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
//! conservative with respect to the triangle tests (the boxes are padded the
//! same way, see [`NodeBox`]).
//!
//! The scalar fallback spells out the SSE `minps`/`maxps` semantics (the
//! second operand when either is NaN), so both give identical hit masks and
//! entry distances, which the unit tests check.

use crate::aabb::Aabb;
use crate::accel::node_box::NodeBox;
use crate::ray::Ray;
use glam::Vec3;

/// Four boxes, `planes[2·axis]` holding the four minima along `axis` and
/// `planes[2·axis + 1]` the maxima. An unused slot holds the inverted box
/// `[+∞, -∞]`, which every ray misses.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub(crate) struct Box4 {
    pub planes: [[f32; 4]; 6],
}

impl Default for Box4 {
    fn default() -> Self {
        Box4::EMPTY
    }
}

/// Which of the four boxes a ray enters, and where.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Hits4 {
    /// Bit `i` set when box `i` is entered within the interval.
    pub mask: u32,
    /// Entry distance into box `i`; meaningful only where `mask` has bit `i`.
    pub t: [f32; 4],
}

/// A ray prepared for [`Box4`] tests: origin, reciprocal direction and, per
/// axis, the plane row met first.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayBox4 {
    origin: [f32; 3],
    inv_dir: [f32; 3],
    near: [usize; 3],
}

impl RayBox4 {
    /// Prepare `ray`: a negative reciprocal direction (including `-∞` from
    /// `-0`) meets the maximum plane first.
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        let id = ray.inv_dir.to_array();
        RayBox4 {
            origin: ray.origin.to_array(),
            inv_dir: id,
            // Spelled out, as `RayBox8::new`.
            near: [
                id[0].is_sign_negative() as usize,
                2 + id[1].is_sign_negative() as usize,
                4 + id[2].is_sign_negative() as usize,
            ],
        }
    }
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

impl Box4 {
    /// Four unused slots.
    pub const EMPTY: Box4 = Box4 {
        planes: [
            [f32::INFINITY; 4],
            [f32::NEG_INFINITY; 4],
            [f32::INFINITY; 4],
            [f32::NEG_INFINITY; 4],
            [f32::INFINITY; 4],
            [f32::NEG_INFINITY; 4],
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

    /// Test all four boxes against the ray over `[tnear, tfar]`.
    #[inline(always)]
    pub fn entries(&self, r: &RayBox4, tnear: f32, tfar: f32) -> Hits4 {
        #[cfg(target_arch = "x86_64")]
        {
            self.entries_sse(r, tnear, tfar)
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            self.entries_scalar(r, tnear, tfar)
        }
    }

    /// The portable version of [`Box4::entries`], one box after the other
    /// (on x86_64 only the unit tests use it).
    #[cfg_attr(target_arch = "x86_64", allow(dead_code))]
    #[inline(always)]
    pub fn entries_scalar(&self, r: &RayBox4, tnear: f32, tfar: f32) -> Hits4 {
        let mut out = Hits4 {
            mask: 0,
            t: [0.0; 4],
        };
        for i in 0..4 {
            let mut enter = tnear;
            let mut exit = f32::INFINITY;
            // Same operand order as the SSE version: z, then y, then x.
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

    /// [`Box4::entries`] with SSE: 6 subtractions, 6 multiplications, 3 max,
    /// 4 min and one compare for all four boxes.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub fn entries_sse(&self, r: &RayBox4, tnear: f32, tfar: f32) -> Hits4 {
        use std::arch::x86_64::*;
        let mut t = [0f32; 4];
        // SAFETY: SSE is part of the x86_64 baseline, so every intrinsic
        // here is available on any x86_64 CPU; the loads read `[f32; 4]` rows
        // of `self.planes`, 16-byte aligned because `Box4` is `align(16)` and
        // each row is 16 bytes, and the store writes the local `[f32; 4]` `t`
        // (unaligned store).
        let mask = unsafe {
            let p = &self.planes;
            let mut enter = _mm_set1_ps(tnear);
            let mut exit = _mm_set1_ps(f32::INFINITY);
            for a in (0..3).rev() {
                let n = r.near[a];
                let o = _mm_set1_ps(r.origin[a]);
                let id = _mm_set1_ps(r.inv_dir[a]);
                let tn = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(p[n].as_ptr()), o), id);
                let tf = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(p[n ^ 1].as_ptr()), o), id);
                enter = _mm_max_ps(tn, enter);
                exit = _mm_min_ps(tf, exit);
            }
            let exit = _mm_min_ps(
                _mm_mul_ps(exit, _mm_set1_ps(NodeBox::ROBUST_EXIT)),
                _mm_set1_ps(tfar),
            );
            _mm_storeu_ps(t.as_mut_ptr(), enter);
            _mm_movemask_ps(_mm_cmple_ps(enter, exit)) as u32
        };
        Hits4 { mask, t }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    /// Replace a direction component, now and then, by exactly ±0 (infinite
    /// reciprocal) or by a tiny value.
    fn component(rng: &mut Pcg32, d: f32) -> f32 {
        match rng.below(8) {
            0 => 0.0,
            1 => -0.0,
            2 => rng.range_f32(-1e-30, 1e-30),
            _ => d,
        }
    }

    #[test]
    fn sse_and_scalar_agree_on_random_boxes_and_rays() {
        let mut rng = Pcg32::new(8);
        let mut hits = 0;
        for _ in 0..200_000 {
            let mut boxes = Box4::EMPTY;
            let used = 1 + rng.below(4) as usize;
            for s in 0..used {
                let lo = rng.in_box(Vec3::splat(-1.0), Vec3::splat(1.0));
                let size = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32())
                    * if rng.below(8) == 0 { 0.0 } else { 0.5 };
                boxes.set(s, &Aabb::new(lo, lo + size).into());
            }
            let mut origin = rng.in_box(Vec3::splat(-2.0), Vec3::splat(2.0));
            // Put the origin exactly on a slab plane now and then, which with
            // a zero direction component gives 0·∞ = NaN.
            if rng.below(4) == 0 {
                let a = rng.below(3) as usize;
                let row = 2 * a + rng.below(2) as usize;
                origin[a] = boxes.planes[row][rng.below(used as u32) as usize];
            }
            // Aim at a point of one of the boxes most of the time.
            let target = boxes.get(rng.below(used as u32) as usize);
            let aim = if rng.below(4) == 0 {
                rng.unit_vector()
            } else {
                rng.in_box(target.min, target.max) - origin
            };
            let mut dir = Vec3::new(
                component(&mut rng, aim.x),
                component(&mut rng, aim.y),
                component(&mut rng, aim.z),
            );
            if dir == Vec3::ZERO {
                dir.x = 1.0;
            }
            let (tnear, tfar) = match rng.below(3) {
                0 => (0.0, f32::INFINITY),
                1 => (rng.range_f32(0.0, 0.5), rng.range_f32(0.5, 5.0)),
                _ => (0.0, rng.range_f32(0.0, 1.5)),
            };
            let ray = Ray::segment(origin, dir, tnear, tfar);
            let r = RayBox4::new(&ray);
            let a = boxes.entries_sse(&r, tnear, tfar);
            let b = boxes.entries_scalar(&r, tnear, tfar);
            assert_eq!(a.mask, b.mask, "{ray:?} {boxes:?}");
            assert_eq!(a.mask >> used, 0, "an unused slot was hit: {ray:?}");
            for i in 0..4 {
                if a.mask & (1 << i) != 0 {
                    assert_eq!(a.t[i].to_bits(), b.t[i].to_bits(), "{ray:?} {boxes:?}");
                    hits += 1;
                }
            }
            // Conservative with respect to the single-box test of Bvh2.
            for s in 0..used {
                let nb: NodeBox = NodeBox {
                    min: boxes.get(s).min.to_array(),
                    max: boxes.get(s).max.to_array(),
                };
                let e = nb.entry(&ray, tnear, tfar);
                if e != f32::INFINITY {
                    assert!(b.mask & (1 << s) != 0, "{ray:?} {nb:?}");
                    // Equal up to the sign of zero (`f32::max` may return
                    // either zero).
                    assert_eq!(b.t[s], e, "{ray:?} {nb:?}");
                }
            }
        }
        assert!(hits > 20_000, "too few hits to be a test: {hits}");
    }
}
