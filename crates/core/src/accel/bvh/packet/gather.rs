//! The rays of a packet moved from the batch's ray array into the packet's
//! structure-of-arrays rows with AVX shuffles, eight rays at a time (for
//! the coherent path of [`super::packet`]).
//!
//! Eight rays are eight 44-byte [`Ray`]s one after the other. Each is read as
//! three overlapping 16-byte pieces (origin and `dir.x`; `dir.y`, `dir.z`,
//! `tnear`, `tfar`; `tfar` and `inv_dir`), rays `i` and `i + 4` into the two
//! halves of one 256-bit register, and every set of four registers is
//! transposed within its 128-bit halves (the 4×4 transpose of Intel's
//! optimization manual). That is 12 loads, 12 inserts and 24 shuffles for 8
//! rays, where copying the 88 floats one by one took about 50 instructions per
//! ray, 11% of all instructions of terrain primaries (callgrind,
//! BENCHMARKS.md). The values are moved, not computed: each row holds exactly
//! the rays' floats.

use crate::ray::Ray;
use std::arch::x86_64::*;

/// Floats in a [`Ray`] (`repr(C)`: origin, dir, tnear, tfar, inv_dir).
const RAY_FLOATS: usize = 11;
const _: () = assert!(std::mem::size_of::<Ray>() == 4 * RAY_FLOATS);

/// The rows of eight rays: `origin`, `dir` and `inv_dir` per axis, `tnear`,
/// `tfar`, lane `l` from `rays[l]`.
pub(crate) struct Rows8 {
    pub origin: [__m256; 3],
    pub dir: [__m256; 3],
    pub inv_dir: [__m256; 3],
    pub tnear: __m256,
    pub tfar: __m256,
}

/// Transpose four registers within their 128-bit halves: lane `j` of half
/// `h` of output `i` is lane `i` of half `h` of input `j`.
///
/// # Safety
/// The CPU must support AVX.
#[target_feature(enable = "avx")]
#[inline]
unsafe fn transpose4(r: [__m256; 4]) -> [__m256; 4] {
    let t0 = _mm256_unpacklo_ps(r[0], r[1]);
    let t1 = _mm256_unpackhi_ps(r[0], r[1]);
    let t2 = _mm256_unpacklo_ps(r[2], r[3]);
    let t3 = _mm256_unpackhi_ps(r[2], r[3]);
    [
        _mm256_shuffle_ps::<0x44>(t0, t2),
        _mm256_shuffle_ps::<0xEE>(t0, t2),
        _mm256_shuffle_ps::<0x44>(t1, t3),
        _mm256_shuffle_ps::<0xEE>(t1, t3),
    ]
}

/// Rays `i` and `i + 4` of the eight at `p`, four floats from float
/// `offset` of each, in the low and high half of one register.
///
/// # Safety
/// AVX; `p` points to eight readable rays and `offset + 4 <= RAY_FLOATS`.
#[target_feature(enable = "avx")]
#[inline]
unsafe fn pieces(p: *const f32, offset: usize) -> [__m256; 4] {
    let mut out = [_mm256_setzero_ps(); 4];
    for (i, o) in out.iter_mut().enumerate() {
        // SAFETY: the caller's eight rays; `offset + 4 <= RAY_FLOATS`
        // keeps both reads inside rays `i` and `i + 4`.
        unsafe {
            let lo = _mm_loadu_ps(p.add(i * RAY_FLOATS + offset));
            let hi = _mm_loadu_ps(p.add((i + 4) * RAY_FLOATS + offset));
            *o = _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(lo), hi);
        }
    }
    out
}

/// The rows of `rays` (see the module docs).
///
/// # Safety
/// The CPU must support AVX.
#[target_feature(enable = "avx")]
#[inline]
pub(crate) unsafe fn rows8(rays: &[Ray; 8]) -> Rows8 {
    let p = rays.as_ptr() as *const f32;
    // SAFETY: AVX (the caller); `rays` holds eight rays, and the offsets
    // 0, 4 and 7 read floats 0..4, 4..8 and 7..11 of each.
    unsafe {
        let [ox, oy, oz, dx] = transpose4(pieces(p, 0));
        let [dy, dz, tnear, tfar] = transpose4(pieces(p, 4));
        let [_, ix, iy, iz] = transpose4(pieces(p, 7));
        Rows8 {
            origin: [ox, oy, oz],
            dir: [dx, dy, dz],
            inv_dir: [ix, iy, iz],
            tnear,
            tfar,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;
    use glam::Vec3;

    fn lanes(v: __m256) -> [f32; 8] {
        let mut a = [0f32; 8];
        // SAFETY: only called after the test found AVX; an unaligned
        // store into a local array.
        unsafe { _mm256_storeu_ps(a.as_mut_ptr(), v) };
        a
    }

    /// Every row holds exactly the rays' floats, bit for bit, at any
    /// alignment of the rays in memory.
    #[test]
    fn rows_hold_each_rays_fields() {
        if !is_x86_feature_detected!("avx") {
            eprintln!("skipped: this CPU has no AVX (rows8 needs it)");
            return;
        }
        let mut rng = Pcg32::new(5);
        let mut v = || {
            Vec3::new(
                rng.range_f32(-9.0, 9.0),
                rng.range_f32(-9.0, 9.0),
                rng.range_f32(-9.0, 9.0),
            )
        };
        let rays: Vec<Ray> = (0..13)
            .map(|_| Ray::segment(v(), v(), v().x.abs(), 10.0 + v().y))
            .collect();
        for start in 0..=rays.len() - 8 {
            let eight: &[Ray; 8] = rays[start..start + 8].try_into().unwrap();
            // SAFETY: AVX checked above.
            let r = unsafe { rows8(eight) };
            for (l, ray) in eight.iter().enumerate() {
                for a in 0..3 {
                    assert_eq!(lanes(r.origin[a])[l].to_bits(), ray.origin[a].to_bits());
                    assert_eq!(lanes(r.dir[a])[l].to_bits(), ray.dir[a].to_bits());
                    assert_eq!(lanes(r.inv_dir[a])[l].to_bits(), ray.inv_dir[a].to_bits());
                }
                assert_eq!(lanes(r.tnear)[l].to_bits(), ray.tnear.to_bits());
                assert_eq!(lanes(r.tfar)[l].to_bits(), ray.tfar.to_bits());
            }
        }
    }
}
