//! The SIMD kernels of eight boxes ([`Box8`]): the box half of the 8-wide BVH ([`super::Bvh8`]),
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
//! The slab test is [`super::boxes`]'s, term for term (see its docs for why
//! it is conservative with respect to the triangle tests).

use super::box_path::BoxPath;
use super::boxes::{Boxes, Hits};
use super::ray_box::RayBox;
use crate::accel::node_box::NodeBox;

/// Eight boxes in structure-of-arrays layout.
pub type Box8 = Boxes<8>;

/// Which of eight boxes a ray enters, and where.
pub type Hits8 = Hits<8>;

impl Boxes<8> {
    /// Test all eight boxes with the kernel `path` (see the module docs).
    ///
    /// # Safety
    /// `path` must be one of [`BoxPath::available`] on this CPU (the one
    /// [`BoxPath::detect`] returns, or a slower one).
    #[inline(always)]
    pub unsafe fn entries(&self, path: BoxPath, r: &RayBox, tnear: f32, tfar: f32) -> Hits8 {
        match path {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the caller guarantees AVX2 (hence AVX) is present.
            BoxPath::Avx2 | BoxPath::Avx512 => unsafe { self.entries_avx(r, tnear, tfar) },
            #[cfg(target_arch = "x86_64")]
            BoxPath::Sse => self.entries_sse(r, tnear, tfar),
            _ => self.entries_scalar(r, tnear, tfar),
        }
    }

    /// The SSE kernel: the two halves of four boxes each.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub fn entries_sse(&self, r: &RayBox, tnear: f32, tfar: f32) -> Hits8 {
        let mut t = [0f32; 8];
        let mask = self.sse_quad(0, r, tnear, tfar, &mut t)
            | self.sse_quad(4, r, tnear, tfar, &mut t) << 4;
        Hits8 { mask, t }
    }

    /// The AVX kernel: all eight boxes in one 256-bit pass.
    ///
    /// # Safety
    /// The CPU must support AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    #[inline]
    pub unsafe fn entries_avx(&self, r: &RayBox, tnear: f32, tfar: f32) -> Hits8 {
        use std::arch::x86_64::*;
        let mut t = [0f32; 8];
        // SAFETY: the caller guarantees AVX. The aligned loads read 32-byte
        // rows of `planes` (`Boxes` is `align(32)`, each row 32 bytes); the
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
