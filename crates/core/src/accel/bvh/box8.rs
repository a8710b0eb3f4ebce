//! Eight boxes in structure-of-arrays layout and their ray test, all eight
//! at once: the box half of the 8-wide BVH ([`super::Bvh8`]),
//! as Embree's BVH8 nodes on AVX machines (Wald et al. 2014, "Embree: a
//! kernel framework for efficient CPU ray tracing").
//!
//! Three kernels give identical hit masks and entry distances, chosen once
//! per structure by run-time detection ([`BoxPath::detect`]):
//! - AVX: one 256-bit pass (6 subtractions, 6 multiplications, 3 max, 4 min,
//!   one compare for all eight boxes);
//! - SSE (the x86_64 baseline): two 128-bit halves;
//! - scalar: one box after the other, spelling out the `minps`/`maxps`
//!   semantics (the second operand when either is NaN).
//!
//! On CPUs with AVX-512 the AVX kernel runs inside a traversal compiled for
//! AVX-512 as well ([`BoxPath::Avx512`]): the same instructions' results,
//! with twice the vector registers and compares into mask registers.
//!
//! The slab test is [`super::box4`]'s, term for term (see its docs for why
//! it is conservative with respect to the triangle tests: the boxes are
//! padded as [`NodeBox`]'s, the exit is widened by [`NodeBox::ROBUST_EXIT`],
//! and a NaN from `0·∞` drops out). No fused multiply-add is used: FMA's
//! single rounding would change the distances, and the argument that they
//! never cull a box whose triangle the triangle test reports hit.

#[cfg_attr(target_arch = "x86_64", allow(unused_imports))]
use super::box4::{max_sse, min_sse};
use crate::aabb::Aabb;
use crate::accel::node_box::NodeBox;
use crate::ray::Ray;
use glam::Vec3;

/// Eight boxes, `planes[2·axis]` holding the eight minima along `axis` and
/// `planes[2·axis + 1]` the maxima. An unused slot holds the inverted box
/// `[+∞, -∞]`, which every ray misses.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct Box8 {
    pub planes: [[f32; 8]; 6],
}

impl Default for Box8 {
    fn default() -> Self {
        Box8::EMPTY
    }
}

/// Which of the eight boxes a ray enters, and where.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Hits8 {
    /// Bit `i` set when box `i` is entered within the interval.
    pub mask: u32,
    /// Entry distance into box `i`; meaningful only where `mask` has bit `i`.
    pub t: [f32; 8],
}

/// A ray prepared for [`Box8`] tests: origin, reciprocal direction and, per
/// axis, the plane row met first.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayBox8 {
    origin: [f32; 3],
    inv_dir: [f32; 3],
    near: [usize; 3],
}

impl RayBox8 {
    /// Prepare `ray`: a negative reciprocal direction (including `-∞` from
    /// `-0`) meets the maximum plane first.
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        let id = ray.inv_dir.to_array();
        RayBox8 {
            origin: ray.origin.to_array(),
            inv_dir: id,
            // Spelled out: `array::map`'s closure became a call inside
            // the traversals compiled for AVX2 (BENCHMARKS.md).
            near: [
                id[0].is_sign_negative() as usize,
                2 + id[1].is_sign_negative() as usize,
                4 + id[2].is_sign_negative() as usize,
            ],
        }
    }
}

/// The box kernel a structure uses, detected once when it is built
/// (run-time detection, not per node).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum BoxPath {
    /// 256-bit AVX (with AVX2 and FMA present, as the traversal is compiled
    /// for them).
    Avx2,
    /// The AVX kernel, the traversal around it compiled for AVX-512 (F, VL, BW,
    /// DQ) besides: the same 256-bit arithmetic, bit for bit, with 32 vector
    /// registers and compares into mask registers, as Embree runs its AVX-512
    /// kernels on such CPUs (single incoherent rays 1.09x faster on the
    /// scatter).
    Avx512,
    /// Two 128-bit SSE halves.
    Sse,
    /// One box after the other (off x86_64; on it, only in tests).
    #[cfg_attr(target_arch = "x86_64", allow(dead_code))]
    Scalar,
}

impl BoxPath {
    /// The fastest kernel this CPU runs.
    pub fn detect() -> BoxPath {
        #[cfg(target_arch = "x86_64")]
        {
            if avx512() {
                BoxPath::Avx512
            } else if avx2() {
                BoxPath::Avx2
            } else {
                BoxPath::Sse
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            BoxPath::Scalar
        }
    }

    /// Every kernel this CPU runs (for tests).
    #[cfg(test)]
    pub fn available() -> Vec<BoxPath> {
        let mut v = vec![BoxPath::Scalar];
        #[cfg(target_arch = "x86_64")]
        {
            v.push(BoxPath::Sse);
            if avx2() {
                v.push(BoxPath::Avx2);
            }
            if avx512() {
                v.push(BoxPath::Avx512);
            } else {
                eprintln!("note: no AVX-512 on this CPU: the Avx512 traversal is not tested here");
            }
        }
        v
    }
}

/// AVX2 and FMA, which [`BoxPath::Avx2`]'s traversal is compiled for.
#[cfg(target_arch = "x86_64")]
fn avx2() -> bool {
    is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")
}

/// Every feature [`BoxPath::Avx512`]'s traversal is compiled for (what its
/// `target_feature` attributes name).
#[cfg(target_arch = "x86_64")]
fn avx512() -> bool {
    avx2()
        && is_x86_feature_detected!("avx512f")
        && is_x86_feature_detected!("avx512vl")
        && is_x86_feature_detected!("avx512bw")
        && is_x86_feature_detected!("avx512dq")
        && is_x86_feature_detected!("bmi1")
        && is_x86_feature_detected!("bmi2")
        && is_x86_feature_detected!("lzcnt")
        && is_x86_feature_detected!("popcnt")
}

impl Box8 {
    /// Eight unused slots.
    pub const EMPTY: Box8 = Box8 {
        planes: [
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
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

    /// Test all eight boxes with the kernel `path` (see the module docs).
    ///
    /// # Safety
    /// `path` must be one of [`BoxPath::available`] on this CPU (the one
    /// [`BoxPath::detect`] returns, or a slower one).
    #[inline(always)]
    pub unsafe fn entries(&self, path: BoxPath, r: &RayBox8, tnear: f32, tfar: f32) -> Hits8 {
        match path {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the caller guarantees AVX2 (hence AVX) is present.
            BoxPath::Avx2 | BoxPath::Avx512 => unsafe { self.entries_avx(r, tnear, tfar) },
            #[cfg(target_arch = "x86_64")]
            BoxPath::Sse => self.entries_sse(r, tnear, tfar),
            _ => self.entries_scalar(r, tnear, tfar),
        }
    }

    /// The portable kernel, one box after the other.
    #[inline(always)]
    pub fn entries_scalar(&self, r: &RayBox8, tnear: f32, tfar: f32) -> Hits8 {
        let mut out = Hits8 {
            mask: 0,
            t: [0.0; 8],
        };
        for i in 0..8 {
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

    /// The SSE kernel: the two halves of four boxes each.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub fn entries_sse(&self, r: &RayBox8, tnear: f32, tfar: f32) -> Hits8 {
        use std::arch::x86_64::*;
        let mut t = [0f32; 8];
        let mut mask = 0u32;
        for half in 0..2 {
            // SAFETY: SSE is part of the x86_64 baseline. Each load reads
            // four floats at offset `4·half` of a 32-byte row of `planes`
            // (`Box8` is `align(32)`, rows 32 bytes), so 16-byte aligned and
            // in bounds; the store writes four floats of the local `t`.
            unsafe {
                let p = &self.planes;
                let mut enter = _mm_set1_ps(tnear);
                let mut exit = _mm_set1_ps(f32::INFINITY);
                for a in (0..3).rev() {
                    let n = r.near[a];
                    let o = _mm_set1_ps(r.origin[a]);
                    let id = _mm_set1_ps(r.inv_dir[a]);
                    let lo = _mm_load_ps(p[n].as_ptr().add(4 * half));
                    let hi = _mm_load_ps(p[n ^ 1].as_ptr().add(4 * half));
                    enter = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(lo, o), id), enter);
                    exit = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(hi, o), id), exit);
                }
                let exit = _mm_min_ps(
                    _mm_mul_ps(exit, _mm_set1_ps(NodeBox::ROBUST_EXIT)),
                    _mm_set1_ps(tfar),
                );
                _mm_storeu_ps(t.as_mut_ptr().add(4 * half), enter);
                mask |= (_mm_movemask_ps(_mm_cmple_ps(enter, exit)) as u32) << (4 * half);
            }
        }
        Hits8 { mask, t }
    }

    /// The AVX kernel: all eight boxes in one 256-bit pass.
    ///
    /// # Safety
    /// The CPU must support AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    #[inline]
    pub unsafe fn entries_avx(&self, r: &RayBox8, tnear: f32, tfar: f32) -> Hits8 {
        use std::arch::x86_64::*;
        let mut t = [0f32; 8];
        // SAFETY: the caller guarantees AVX. The aligned loads read 32-byte
        // rows of `planes` (`Box8` is `align(32)`, each row 32 bytes); the
        // store writes the local `[f32; 8]` `t` (unaligned store).
        let mask = unsafe {
            let p = &self.planes;
            let mut enter = _mm256_set1_ps(tnear);
            let mut exit = _mm256_set1_ps(f32::INFINITY);
            for a in (0..3).rev() {
                let n = r.near[a];
                let o = _mm256_set1_ps(r.origin[a]);
                let id = _mm256_set1_ps(r.inv_dir[a]);
                let lo = _mm256_load_ps(p[n].as_ptr());
                let hi = _mm256_load_ps(p[n ^ 1].as_ptr());
                enter = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(lo, o), id), enter);
                exit = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(hi, o), id), exit);
            }
            let exit = _mm256_min_ps(
                _mm256_mul_ps(exit, _mm256_set1_ps(NodeBox::ROBUST_EXIT)),
                _mm256_set1_ps(tfar),
            );
            _mm256_storeu_ps(t.as_mut_ptr(), enter);
            _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(enter, exit)) as u32
        };
        Hits8 { mask, t }
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

    /// Every available kernel gives the scalar kernel's mask and entry
    /// distances bit for bit, and the scalar kernel accepts every box the
    /// single-box test of Bvh2 accepts, at the same distance.
    #[test]
    fn simd_and_scalar_agree_on_random_boxes_and_rays() {
        let mut rng = Pcg32::new(88);
        let paths = BoxPath::available();
        let mut hits = 0;
        for _ in 0..100_000 {
            let mut boxes = Box8::EMPTY;
            let used = 1 + rng.below(8) as usize;
            for s in 0..used {
                let lo = rng.in_box(Vec3::splat(-1.0), Vec3::splat(1.0));
                let size = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32())
                    * if rng.below(8) == 0 { 0.0 } else { 0.5 };
                boxes.set(s, &Aabb::new(lo, lo + size).into());
            }
            let mut origin = rng.in_box(Vec3::splat(-2.0), Vec3::splat(2.0));
            // The origin exactly on a slab plane now and then (0·∞ = NaN
            // with a zero direction component).
            if rng.below(4) == 0 {
                let a = rng.below(3) as usize;
                let row = 2 * a + rng.below(2) as usize;
                origin[a] = boxes.planes[row][rng.below(used as u32) as usize];
            }
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
            let r = RayBox8::new(&ray);
            let want = boxes.entries_scalar(&r, tnear, tfar);
            assert_eq!(want.mask >> used, 0, "an unused slot was hit: {ray:?}");
            for &path in &paths {
                // SAFETY: `path` is one this CPU runs.
                let got = unsafe { boxes.entries(path, &r, tnear, tfar) };
                assert_eq!(got.mask, want.mask, "{path:?} {ray:?} {boxes:?}");
                for i in 0..8 {
                    if want.mask & (1 << i) != 0 {
                        assert_eq!(got.t[i].to_bits(), want.t[i].to_bits(), "{path:?} {ray:?}");
                    }
                }
            }
            for s in 0..used {
                let b = boxes.get(s);
                let nb = NodeBox {
                    min: b.min.to_array(),
                    max: b.max.to_array(),
                };
                let e = nb.entry(&ray, tnear, tfar);
                if e != f32::INFINITY {
                    assert!(want.mask & (1 << s) != 0, "{ray:?} {nb:?}");
                    assert_eq!(want.t[s], e, "{ray:?} {nb:?}");
                    hits += 1;
                }
            }
        }
        assert!(hits > 10_000, "too few hits to be a test: {hits}");
    }
}
