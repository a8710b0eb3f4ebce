//! The SIMD kernel of four boxes ([`Box4`], the box half of the 4-wide
//! BVH [`super::Bvh4`]): SSE on x86_64, the baseline there, so no run-time
//! detection is needed; the scalar kernel of [`super::boxes`] elsewhere.

use super::box_path::BoxPath;
use super::boxes::{Boxes, Hits};
use super::ray_box::RayBox;

/// Four boxes in structure-of-arrays layout.
pub type Box4 = Boxes<4>;

/// Which of four boxes a ray enters, and where.
pub type Hits4 = Hits<4>;

impl Boxes<4> {
    /// Test all four boxes against the ray over `[tnear, tfar]`: SSE
    /// whatever wider kernel `path` names, the scalar kernel for
    /// [`BoxPath::Scalar`] and off x86_64.
    #[inline(always)]
    pub fn entries(&self, path: BoxPath, r: &RayBox, tnear: f32, tfar: f32) -> Hits4 {
        match path {
            #[cfg(target_arch = "x86_64")]
            BoxPath::Avx512 | BoxPath::Avx2 | BoxPath::Sse => self.entries_sse(r, tnear, tfar),
            _ => self.entries_scalar(r, tnear, tfar),
        }
    }

    /// [`Box4::entries`] with SSE: 6 subtractions, 6 multiplications, 3 max,
    /// 4 min and one compare for all four boxes.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub fn entries_sse(&self, r: &RayBox, tnear: f32, tfar: f32) -> Hits4 {
        let mut t = [0f32; 4];
        let mask = self.sse_quad(0, r, tnear, tfar, &mut t);
        Hits4 { mask, t }
    }
}
