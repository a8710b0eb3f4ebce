//! The SIMD lanes the coherent-ray packet kernel runs on:
//! eight rays in a 256-bit AVX register ([`L8`]) or sixteen in a 512-bit
//! AVX-512 register ([`L16`]), as Embree's packet and stream kernels use
//! packets of the machine's vector width (Wald et al. 2014).
//!
//! The kernel (`packet/kernel.rs`) is written once against [`Lanes`]. The
//! methods are thin `#[inline(always)]` wrappers of single instructions;
//! they inline into the kernel's entry points, which are compiled for the
//! features each width needs, so every operation is the one instruction
//! it names. Each lane computes with exactly the instruction the scalar
//! and single-ray kernels use (`minps`/`maxps` semantics included: the
//! second operand when either is NaN), so a lane's answer is the same bit
//! for bit at either width.

use std::arch::x86_64::*;

/// A vector of `L` single-precision lanes, a mask of `L` lanes and a vector
/// of `L` 32-bit integers.
///
/// # Safety
/// Every method runs instructions of the width's feature set (AVX2 for
/// [`L8`], AVX-512 F/VL/BW/DQ for [`L16`]): call them only from code
/// compiled for those features, on a CPU that has them.
pub(crate) trait Lanes<const L: usize>: Copy {
    /// A lane mask.
    type Mask: Copy;
    /// Lanes of `i32`.
    type Int: Copy;
    /// Every lane `x`.
    fn splat(x: f32) -> Self;
    /// Load `L` lanes.
    fn load(row: &[f32; L]) -> Self;
    /// Store `L` lanes.
    fn store(self, row: &mut [f32; L]);
    fn add(self, b: Self) -> Self;
    fn sub(self, b: Self) -> Self;
    fn mul(self, b: Self) -> Self;
    fn div(self, b: Self) -> Self;
    /// `minps`: `b` where either lane is NaN.
    fn min(self, b: Self) -> Self;
    /// `maxps`: `b` where either lane is NaN.
    fn max(self, b: Self) -> Self;
    /// `|self|`, by clearing the sign bit.
    fn abs(self) -> Self;
    /// `-self`, by flipping the sign bit.
    fn neg(self) -> Self;
    /// Ordered `self <= b` (false with a NaN).
    fn le(self, b: Self) -> Self::Mask;
    /// Ordered `self < b`.
    fn lt(self, b: Self) -> Self::Mask;
    /// Ordered `self >= b`.
    fn ge(self, b: Self) -> Self::Mask;
    /// Ordered `self > b`.
    fn gt(self, b: Self) -> Self::Mask;
    /// Lanes that are not NaN.
    fn ordered(self) -> Self::Mask;
    /// `b` where `m` is set, else `self`.
    fn blend(self, b: Self, m: Self::Mask) -> Self;
    /// The smallest lane (no lane may be NaN: `minps` passes a NaN on
    /// depending on its position).
    fn hmin(self) -> f32;
    /// The mask's lanes as bits, lane 0 lowest.
    fn bits(m: Self::Mask) -> u32;
    /// The mask with the lanes of `bits`.
    fn mask(bits: u32) -> Self::Mask;
    /// `a & b`.
    fn and(a: Self::Mask, b: Self::Mask) -> Self::Mask;
    /// `a | b`.
    fn or(a: Self::Mask, b: Self::Mask) -> Self::Mask;
    /// `!a & b`.
    fn andnot(a: Self::Mask, b: Self::Mask) -> Self::Mask;
    /// Every integer lane `x`.
    fn splat_int(x: i32) -> Self::Int;
    /// Integer `b` where `m` is set, else `a`.
    fn blend_int(a: Self::Int, b: Self::Int, m: Self::Mask) -> Self::Int;
    /// Load `L` integer lanes.
    fn load_int(row: &[u32; L]) -> Self::Int;
    /// Store `L` integer lanes.
    fn store_int(v: Self::Int, row: &mut [u32; L]);
}

/// Eight lanes in an AVX register; masks are all-ones lanes.
#[derive(Clone, Copy)]
pub(crate) struct L8(__m256);

/// Sixteen lanes in an AVX-512 register; masks are `k` registers
/// (Embree's packets of sixteen on AVX-512 machines).
#[derive(Clone, Copy)]
pub(crate) struct L16(__m512);

// SAFETY (every `unsafe` block in the two impls): the trait's contract, the
// caller runs on a CPU with the width's features; loads and stores read or
// write exactly the `L` lanes of the array given (unaligned forms).
impl Lanes<8> for L8 {
    type Mask = __m256;
    type Int = __m256i;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        L8(unsafe { _mm256_set1_ps(x) })
    }
    #[inline(always)]
    fn load(row: &[f32; 8]) -> Self {
        L8(unsafe { _mm256_loadu_ps(row.as_ptr()) })
    }
    #[inline(always)]
    fn store(self, row: &mut [f32; 8]) {
        unsafe { _mm256_storeu_ps(row.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn add(self, b: Self) -> Self {
        L8(unsafe { _mm256_add_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn sub(self, b: Self) -> Self {
        L8(unsafe { _mm256_sub_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn mul(self, b: Self) -> Self {
        L8(unsafe { _mm256_mul_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn div(self, b: Self) -> Self {
        L8(unsafe { _mm256_div_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn min(self, b: Self) -> Self {
        L8(unsafe { _mm256_min_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn max(self, b: Self) -> Self {
        L8(unsafe { _mm256_max_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn abs(self) -> Self {
        L8(unsafe { _mm256_and_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(i32::MAX))) })
    }
    #[inline(always)]
    fn neg(self) -> Self {
        L8(unsafe { _mm256_xor_ps(self.0, _mm256_castsi256_ps(_mm256_set1_epi32(i32::MIN))) })
    }
    #[inline(always)]
    fn le(self, b: Self) -> __m256 {
        unsafe { _mm256_cmp_ps::<_CMP_LE_OQ>(self.0, b.0) }
    }
    #[inline(always)]
    fn lt(self, b: Self) -> __m256 {
        unsafe { _mm256_cmp_ps::<_CMP_LT_OQ>(self.0, b.0) }
    }
    #[inline(always)]
    fn ge(self, b: Self) -> __m256 {
        unsafe { _mm256_cmp_ps::<_CMP_GE_OQ>(self.0, b.0) }
    }
    #[inline(always)]
    fn gt(self, b: Self) -> __m256 {
        unsafe { _mm256_cmp_ps::<_CMP_GT_OQ>(self.0, b.0) }
    }
    #[inline(always)]
    fn ordered(self) -> __m256 {
        unsafe { _mm256_cmp_ps::<_CMP_ORD_Q>(self.0, self.0) }
    }
    #[inline(always)]
    fn blend(self, b: Self, m: __m256) -> Self {
        L8(unsafe { _mm256_blendv_ps(self.0, b.0, m) })
    }
    #[inline(always)]
    fn hmin(self) -> f32 {
        unsafe {
            let v = self.0;
            let x = _mm256_min_ps(v, _mm256_permute2f128_ps::<1>(v, v));
            let x = _mm256_min_ps(x, _mm256_shuffle_ps::<0b01_00_11_10>(x, x));
            let x = _mm256_min_ps(x, _mm256_shuffle_ps::<0b10_11_00_01>(x, x));
            _mm256_cvtss_f32(x)
        }
    }
    #[inline(always)]
    fn bits(m: __m256) -> u32 {
        unsafe { _mm256_movemask_ps(m) as u32 }
    }
    #[inline(always)]
    fn mask(bits: u32) -> __m256 {
        unsafe {
            let bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
            let set = _mm256_and_si256(_mm256_set1_epi32(bits as i32), bit);
            _mm256_castsi256_ps(_mm256_cmpeq_epi32(set, bit))
        }
    }
    #[inline(always)]
    fn and(a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_and_ps(a, b) }
    }
    #[inline(always)]
    fn or(a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_or_ps(a, b) }
    }
    #[inline(always)]
    fn andnot(a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_andnot_ps(a, b) }
    }
    #[inline(always)]
    fn splat_int(x: i32) -> __m256i {
        unsafe { _mm256_set1_epi32(x) }
    }
    #[inline(always)]
    fn blend_int(a: __m256i, b: __m256i, m: __m256) -> __m256i {
        unsafe {
            _mm256_castps_si256(_mm256_blendv_ps(
                _mm256_castsi256_ps(a),
                _mm256_castsi256_ps(b),
                m,
            ))
        }
    }
    #[inline(always)]
    fn load_int(row: &[u32; 8]) -> __m256i {
        unsafe { _mm256_loadu_si256(row.as_ptr() as *const __m256i) }
    }
    #[inline(always)]
    fn store_int(v: __m256i, row: &mut [u32; 8]) {
        unsafe { _mm256_storeu_si256(row.as_mut_ptr() as *mut __m256i, v) }
    }
}

impl Lanes<16> for L16 {
    type Mask = __mmask16;
    type Int = __m512i;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        L16(unsafe { _mm512_set1_ps(x) })
    }
    #[inline(always)]
    fn load(row: &[f32; 16]) -> Self {
        L16(unsafe { _mm512_loadu_ps(row.as_ptr()) })
    }
    #[inline(always)]
    fn store(self, row: &mut [f32; 16]) {
        unsafe { _mm512_storeu_ps(row.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn add(self, b: Self) -> Self {
        L16(unsafe { _mm512_add_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn sub(self, b: Self) -> Self {
        L16(unsafe { _mm512_sub_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn mul(self, b: Self) -> Self {
        L16(unsafe { _mm512_mul_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn div(self, b: Self) -> Self {
        L16(unsafe { _mm512_div_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn min(self, b: Self) -> Self {
        L16(unsafe { _mm512_min_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn max(self, b: Self) -> Self {
        L16(unsafe { _mm512_max_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn abs(self) -> Self {
        L16(unsafe { _mm512_abs_ps(self.0) })
    }
    #[inline(always)]
    fn neg(self) -> Self {
        L16(unsafe {
            _mm512_castsi512_ps(_mm512_xor_si512(
                _mm512_castps_si512(self.0),
                _mm512_set1_epi32(i32::MIN),
            ))
        })
    }
    #[inline(always)]
    fn le(self, b: Self) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_LE_OQ>(self.0, b.0) }
    }
    #[inline(always)]
    fn lt(self, b: Self) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(self.0, b.0) }
    }
    #[inline(always)]
    fn ge(self, b: Self) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_GE_OQ>(self.0, b.0) }
    }
    #[inline(always)]
    fn gt(self, b: Self) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_GT_OQ>(self.0, b.0) }
    }
    #[inline(always)]
    fn ordered(self) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_ORD_Q>(self.0, self.0) }
    }
    #[inline(always)]
    fn blend(self, b: Self, m: __mmask16) -> Self {
        L16(unsafe { _mm512_mask_blend_ps(m, self.0, b.0) })
    }
    #[inline(always)]
    fn hmin(self) -> f32 {
        unsafe {
            let v = self.0;
            let lo = _mm512_castps512_ps256(v);
            let hi = _mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(_mm512_castps_pd(v)));
            L8(_mm256_min_ps(lo, hi)).hmin()
        }
    }
    #[inline(always)]
    fn bits(m: __mmask16) -> u32 {
        m as u32
    }
    #[inline(always)]
    fn mask(bits: u32) -> __mmask16 {
        bits as __mmask16
    }
    #[inline(always)]
    fn and(a: __mmask16, b: __mmask16) -> __mmask16 {
        a & b
    }
    #[inline(always)]
    fn or(a: __mmask16, b: __mmask16) -> __mmask16 {
        a | b
    }
    #[inline(always)]
    fn andnot(a: __mmask16, b: __mmask16) -> __mmask16 {
        !a & b
    }
    #[inline(always)]
    fn splat_int(x: i32) -> __m512i {
        unsafe { _mm512_set1_epi32(x) }
    }
    #[inline(always)]
    fn blend_int(a: __m512i, b: __m512i, m: __mmask16) -> __m512i {
        unsafe { _mm512_mask_blend_epi32(m, a, b) }
    }
    #[inline(always)]
    fn load_int(row: &[u32; 16]) -> __m512i {
        unsafe { _mm512_loadu_si512(row.as_ptr() as *const _) }
    }
    #[inline(always)]
    fn store_int(v: __m512i, row: &mut [u32; 16]) {
        unsafe { _mm512_storeu_si512(row.as_mut_ptr() as *mut _, v) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::boxes::{max_sse, min_sse};
    use crate::rng::Pcg32;

    /// Awkward and ordinary values: NaN, infinities, signed zeros,
    /// subnormals and random magnitudes of both signs.
    fn values(rng: &mut Pcg32, n: usize) -> Vec<f32> {
        let special = [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            0.0,
            -0.0,
            f32::MIN_POSITIVE / 4.0,
            -1.0,
            1.0,
        ];
        (0..n)
            .map(|i| match i % 3 {
                0 => special[rng.below(special.len() as u32) as usize],
                _ => rng.range_f32(-4.0, 4.0) * 10f32.powi(rng.below(9) as i32 - 4),
            })
            .collect()
    }

    /// Every operation of both widths, lane by lane, against the scalar
    /// semantics it names (`minps`/`maxps`: the second operand where either
    /// is NaN; ordered compares; blends by mask; bit-exact results).
    fn check<const L: usize, V: Lanes<L>>() {
        let mut rng = Pcg32::new(16);
        let same = |a: f32, b: f32| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        for _ in 0..200 {
            let xs: [f32; L] = values(&mut rng, L).try_into().unwrap();
            let ys: [f32; L] = values(&mut rng, L).try_into().unwrap();
            let (x, y) = (V::load(&xs), V::load(&ys));
            let lanes = |v: V| {
                let mut out = [0f32; L];
                v.store(&mut out);
                out
            };
            type Op = (&'static str, fn(f32, f32) -> f32);
            let ops: [(Op, [f32; L]); 8] = [
                (("add", |a, b| a + b), lanes(x.add(y))),
                (("sub", |a, b| a - b), lanes(x.sub(y))),
                (("mul", |a, b| a * b), lanes(x.mul(y))),
                (("div", |a, b| a / b), lanes(x.div(y))),
                (("min", min_sse), lanes(x.min(y))),
                (("max", max_sse), lanes(x.max(y))),
                (
                    ("abs", |a, _| f32::from_bits(a.to_bits() & 0x7fff_ffff)),
                    lanes(x.abs()),
                ),
                (
                    ("neg", |a, _| f32::from_bits(a.to_bits() ^ 0x8000_0000)),
                    lanes(x.neg()),
                ),
            ];
            for ((name, f), got) in ops {
                for l in 0..L {
                    let want = f(xs[l], ys[l]);
                    assert!(same(got[l], want), "{name} lane {l}: {} {}", xs[l], ys[l]);
                }
            }
            type Cmp = (&'static str, fn(f32, f32) -> bool);
            let cmps: [(Cmp, V::Mask); 5] = [
                (("le", |a, b| a <= b), x.le(y)),
                (("lt", |a, b| a < b), x.lt(y)),
                (("ge", |a, b| a >= b), x.ge(y)),
                (("gt", |a, b| a > b), x.gt(y)),
                (("ordered", |a, _| !a.is_nan()), x.ordered()),
            ];
            for ((name, f), m) in cmps {
                let bits = V::bits(m);
                for l in 0..L {
                    assert_eq!(bits >> l & 1 == 1, f(xs[l], ys[l]), "{name} lane {l}");
                }
            }
            let pick = rng.next_u32() & ((1u64 << L) - 1) as u32;
            let other = rng.next_u32() & ((1u64 << L) - 1) as u32;
            let m = V::mask(pick);
            assert_eq!(V::bits(m), pick);
            assert_eq!(V::bits(V::and(m, V::mask(other))), pick & other);
            assert_eq!(V::bits(V::or(m, V::mask(other))), pick | other);
            assert_eq!(V::bits(V::andnot(m, V::mask(other))), !pick & other);
            let blended = lanes(x.blend(y, m));
            let ints: [u32; L] = std::array::from_fn(|l| xs[l].to_bits());
            let mut int_out = [0u32; L];
            V::store_int(
                V::blend_int(V::load_int(&ints), V::splat_int(-7), m),
                &mut int_out,
            );
            for l in 0..L {
                let on = pick >> l & 1 == 1;
                assert!(
                    same(blended[l], if on { ys[l] } else { xs[l] }),
                    "blend {l}"
                );
                assert_eq!(
                    int_out[l],
                    if on { -7i32 as u32 } else { ints[l] },
                    "blend_int {l}"
                );
            }
            let finite: [f32; L] =
                std::array::from_fn(|l| if xs[l].is_nan() { 9.0 } else { xs[l] });
            let want = finite.iter().copied().fold(f32::INFINITY, f32::min);
            assert_eq!(V::load(&finite).hmin(), want, "hmin {finite:?}");
            assert!(lanes(V::splat(2.5)).iter().all(|&a| a == 2.5));
        }
    }

    /// Both widths where this CPU has their features (a note otherwise).
    #[test]
    fn every_operation_matches_its_scalar_semantics() {
        use super::super::box_path::BoxPath;
        let paths = BoxPath::available();
        if paths.contains(&BoxPath::Avx2) {
            check::<8, L8>();
        } else {
            eprintln!("note: no AVX2 on this CPU: L8 is not tested here");
        }
        if paths.contains(&BoxPath::Avx512) {
            check::<16, L16>();
        } else {
            eprintln!("note: no AVX-512 on this CPU: L16 is not tested here");
        }
    }
}
