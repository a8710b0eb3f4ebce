//! The SSE kernel of [`Tri4::hits`]: [`crate::tri::Moller`]'s test on four
//! triangles at once, as in Embree's `triangle4` leaves (Wald et al. 2014,
//! "Embree: a kernel framework for efficient CPU ray tracing").
//!
//! Every lane repeats the scalar test (`tri/moller.rs`, `test::<true>`)
//! operation for operation: the same products and sums in the same order
//! (glam's `dot` adds `x + y` first, then `z`; `cross` is `a.y·b.z - b.y·a.z`
//! and so on), plain multiplies and adds (no FMA, whose single rounding
//! would change the bits), IEEE division for `1 / det`. So a lane's `t`, `u`
//! and `v` equal the scalar test's bit for bit, and so does hit or miss:
//!
//! - the parallel test is the scalar one's cheap bound, then, only when some
//!   used lane does not clear it, the tight bound for all four (the scalar
//!   test takes it lane by lane; a lane that clears the cheap bound is
//!   cleared either way);
//! - for nearest-hit queries, lanes that certainly miss are found before
//!   the division from the undivided barycentrics (`early_miss`, with
//!   margins proved to reject only lanes the full test rejects); a pack
//!   whose used lanes all miss returns there, as most packs do;
//! - `minps(x, cap)` returns `cap` when `x` is NaN, as `f32::min` does;
//! - `maxps` differs from `f32::max` only for NaN operands, which arise in
//!   `max |s_i|` only when `s = o - v0` is not finite; then `u` or `v` is NaN
//!   or infinite and both tests miss whatever the tolerance (it is at most
//!   the cap).
//!
//! The unit tests of [`super::tri4`] check all of this on random, degenerate,
//! parallel, shared-edge and non-finite inputs.

use super::{Ray4, Tri4, TriHits4, CAP};
use std::arch::x86_64::*;

/// Unit roundoff of `f32`, as in the scalar test.
const U: f32 = f32::EPSILON * 0.5;

/// Test the lanes in `lanes` of `tri` against the ray `r` over
/// `[tnear, tfar]`; `EARLY` rejects the lanes that certainly miss before
/// the division (`early_miss`): the same answers, faster where most packs
/// miss (nearest-hit queries), slower where a hit is likely (any-hit
/// queries, whose leaves often hold the occluder, the branch then
/// mispredicting).
#[inline(always)]
pub(crate) fn hits<const EARLY: bool>(tri: &Tri4, r: &Ray4, tfar: f32, lanes: u32) -> TriHits4 {
    let mut out = TriHits4::default();
    // SAFETY: SSE and SSE2 are part of the x86_64 baseline, so every
    // intrinsic here is available on any x86_64 CPU. The aligned loads read
    // `[f32; 4]` rows of `Tri4` (`align(64)`, rows at multiples of 16 bytes)
    // and `Ray4` (`align(16)`, likewise), so each pointer is 16-byte aligned
    // and points at 16 readable bytes; the unaligned stores write the local
    // `[f32; 4]` arrays of `out`.
    unsafe {
        let ld = |row: &[f32; 4]| _mm_load_ps(row.as_ptr());
        let abs_bits = _mm_castsi128_ps(_mm_set1_epi32(0x7fff_ffff));
        let sign_bit = _mm_castsi128_ps(_mm_set1_epi32(i32::MIN));
        let abs = |x: __m128| _mm_and_ps(x, abs_bits);
        let dot = |ax, ay, az, bx, by, bz| {
            _mm_add_ps(
                _mm_add_ps(_mm_mul_ps(ax, bx), _mm_mul_ps(ay, by)),
                _mm_mul_ps(az, bz),
            )
        };

        let (e1x, e1y, e1z) = (ld(&tri.e1[0]), ld(&tri.e1[1]), ld(&tri.e1[2]));
        let (e2x, e2y, e2z) = (ld(&tri.e2[0]), ld(&tri.e2[1]), ld(&tri.e2[2]));
        let (dx, dy, dz) = (ld(&r.dir[0]), ld(&r.dir[1]), ld(&r.dir[2]));
        let (e1m, e2m) = (ld(&tri.e1_max), ld(&tri.e2_max));

        // p = d × e2, det = e1 · p.
        let px = _mm_sub_ps(_mm_mul_ps(dy, e2z), _mm_mul_ps(e2y, dz));
        let py = _mm_sub_ps(_mm_mul_ps(dz, e2x), _mm_mul_ps(e2z, dx));
        let pz = _mm_sub_ps(_mm_mul_ps(dx, e2y), _mm_mul_ps(e2x, dy));
        let det = dot(e1x, e1y, e1z, px, py, pz);
        let adet = abs(det);

        // Not parallel: |det| above the cheap bound, else the tight one.
        let cheap = _mm_mul_ps(_mm_mul_ps(ld(&r.clear_scale), e1m), e2m);
        let mut clear = _mm_cmpgt_ps(adet, cheap);
        if (_mm_movemask_ps(clear) as u32) & lanes != lanes {
            let (adx, ady, adz) = (ld(&r.dir_abs[0]), ld(&r.dir_abs[1]), ld(&r.dir_abs[2]));
            let (a2x, a2y, a2z) = (abs(e2x), abs(e2y), abs(e2z));
            let pcx = _mm_add_ps(_mm_mul_ps(ady, a2z), _mm_mul_ps(adz, a2y));
            let pcy = _mm_add_ps(_mm_mul_ps(adz, a2x), _mm_mul_ps(adx, a2z));
            let pcz = _mm_add_ps(_mm_mul_ps(adx, a2y), _mm_mul_ps(ady, a2x));
            let sum = dot(abs(e1x), abs(e1y), abs(e1z), pcx, pcy, pcz);
            let tight = _mm_mul_ps(_mm_set1_ps(8.0 * U), sum);
            clear = _mm_or_ps(clear, _mm_cmpgt_ps(adet, tight));
        }
        let sx = _mm_sub_ps(ld(&r.origin[0]), ld(&tri.v0[0]));
        let sy = _mm_sub_ps(ld(&r.origin[1]), ld(&tri.v0[1]));
        let sz = _mm_sub_ps(ld(&r.origin[2]), ld(&tri.v0[2]));
        let us = dot(sx, sy, sz, px, py, pz);
        // q = s × e1.
        let qx = _mm_sub_ps(_mm_mul_ps(sy, e1z), _mm_mul_ps(e1y, sz));
        let qy = _mm_sub_ps(_mm_mul_ps(sz, e1x), _mm_mul_ps(e1z, sx));
        let qz = _mm_sub_ps(_mm_mul_ps(sx, e1y), _mm_mul_ps(e1x, sy));
        let vs = dot(dx, dy, dz, qx, qy, qz);

        // With `EARLY`, lanes that certainly miss, before the division (see
        // `early_miss`).
        let live = match EARLY {
            true => _mm_andnot_ps(early_miss(det, adet, us, vs, sign_bit), clear),
            false => clear,
        };
        if (_mm_movemask_ps(live) as u32) & lanes == 0 {
            return out;
        }

        let inv_det = _mm_div_ps(_mm_set1_ps(1.0), det);
        let u = _mm_mul_ps(us, inv_det);
        let v = _mm_mul_ps(vs, inv_det);

        // Tolerances, capped.
        let c = _mm_mul_ps(ld(&r.scale), abs(inv_det));
        let sm = _mm_max_ps(_mm_max_ps(abs(sx), abs(sy)), abs(sz));
        let cap = _mm_set1_ps(CAP);
        let eu = _mm_min_ps(_mm_mul_ps(_mm_mul_ps(c, e2m), _mm_add_ps(sm, e1m)), cap);
        let ev = _mm_min_ps(_mm_mul_ps(_mm_mul_ps(c, e1m), _mm_add_ps(sm, e2m)), cap);
        let t = _mm_mul_ps(dot(e2x, e2y, e2z, qx, qy, qz), inv_det);

        let inside = _mm_and_ps(
            _mm_and_ps(
                _mm_cmpge_ps(u, _mm_xor_ps(eu, sign_bit)),
                _mm_cmpge_ps(v, _mm_xor_ps(ev, sign_bit)),
            ),
            _mm_cmple_ps(
                _mm_add_ps(u, v),
                _mm_add_ps(_mm_set1_ps(1.0), _mm_add_ps(eu, ev)),
            ),
        );
        let in_range = _mm_and_ps(
            _mm_and_ps(
                _mm_cmpge_ps(t, ld(&r.tnear)),
                _mm_cmple_ps(t, _mm_set1_ps(tfar)),
            ),
            _mm_cmplt_ps(t, _mm_set1_ps(f32::INFINITY)),
        );
        let hit = _mm_and_ps(_mm_and_ps(inside, in_range), clear);
        out.mask = (_mm_movemask_ps(hit) as u32) & lanes;
        if out.mask != 0 {
            _mm_storeu_ps(out.t.as_mut_ptr(), t);
            _mm_storeu_ps(out.u.as_mut_ptr(), u);
            _mm_storeu_ps(out.v.as_mut_ptr(), v);
        }
    }
    out
}

/// `1/256 + 1/65536`: the edge tolerance cap with a margin of `2^-8`.
const EDGE_MARGIN: f32 = CAP * (1.0 + 1.0 / 256.0);
/// `(1 + 2·cap)·(1 + 2^-8)`: the bound on `u + v` with the same margin.
const SUM_MARGIN: f32 = (1.0 + 2.0 * CAP) * (1.0 + 1.0 / 256.0);

/// The lanes that the full test would certainly reject, found from the
/// undivided barycentrics `us = s·p` and `vs = d·q` (the very values the
/// full test multiplies by `1/det`), so that a pack whose four triangles
/// all miss skips the division, the tolerances and `t` (Embree's
/// `triangle4` test likewise compares undivided values first; Wald et al.
/// 2014). Never a lane the full test accepts, so every answer stays the
/// scalar test's bit for bit:
///
/// - the tolerances are capped, `eu, ev ≤ CAP`, so `u < -CAP` is a miss;
///   with `σ` the sign of `det`, `σ·us < -CAP·(1 + 2^-8)·|det|` gives
///   `us/det < -CAP·(1 + 2^-8)·(1 - u)`, and `u = fl(us · fl(1/det))` is
///   `us/det` within a relative `2^-21` (two roundings, or `fl(1/det)`
///   subnormal with at least 21 bits when `|det|` nears `f32::MAX`), far
///   inside the margin: `u < -CAP ≤ -eu`. The same for `v`;
/// - `u + v ≤ 1 + (eu + ev)` needs `fl(u + v) ≤ 1 + 2·CAP`; a lane not
///   rejected above has `u, v ≥ -CAP`-ish, so the rounding of `u`, `v` and
///   their sum is again a relative few `2^-23` of `|u| + |v|`, inside the
///   `2^-8` margin of `SUM_MARGIN`;
/// - thresholds below the smallest normal are raised to it (a larger
///   threshold rejects less); where `|det| < 2^-128`, `1/det` overflows and
///   the full test's `u` or `v` is infinite or NaN for every lane rejected
///   here, a miss too; NaN comparisons reject nothing, and an infinite
///   `det` gives infinite thresholds, rejecting nothing.
#[inline(always)]
fn early_miss(det: __m128, adet: __m128, us: __m128, vs: __m128, sign_bit: __m128) -> __m128 {
    // SAFETY: SSE is part of the x86_64 baseline.
    unsafe {
        let sign = _mm_and_ps(det, sign_bit);
        let (su, sv) = (_mm_xor_ps(us, sign), _mm_xor_ps(vs, sign));
        let floor = _mm_set1_ps(f32::MIN_POSITIVE);
        let edge = _mm_max_ps(_mm_mul_ps(adet, _mm_set1_ps(EDGE_MARGIN)), floor);
        let sum = _mm_max_ps(_mm_mul_ps(adet, _mm_set1_ps(SUM_MARGIN)), floor);
        let neg_edge = _mm_xor_ps(edge, sign_bit);
        _mm_or_ps(
            _mm_or_ps(_mm_cmplt_ps(su, neg_edge), _mm_cmplt_ps(sv, neg_edge)),
            _mm_cmpgt_ps(_mm_add_ps(su, sv), sum),
        )
    }
}

/// The lanes in `lanes` that [`crate::tri::Moller::crossing`] might not
/// dismiss (return `None` for), found from the undivided barycentrics as
/// [`early_miss`] finds them: a lane is dropped only when its determinant
/// clears the cheap bound (so `crossing` takes it as sure) and `us`, `vs`
/// or their sum lie beyond the edges by more than `crossing`'s widening
/// (`SURE`: its error bounds `eu·|det|`, `ev·|det|`; otherwise none) with a
/// relative margin of `2^-8` for the roundings of the division, and at
/// least the smallest normal. Every lane kept is classified by `crossing`
/// itself, so its answers are unchanged.
#[inline(always)]
pub(crate) fn crossing_candidates<const SURE: bool>(tri: &Tri4, r: &Ray4, lanes: u32) -> u32 {
    // SAFETY: SSE and SSE2 are part of the x86_64 baseline; the loads are
    // the aligned rows of `hits`.
    unsafe {
        let ld = |row: &[f32; 4]| _mm_load_ps(row.as_ptr());
        let abs_bits = _mm_castsi128_ps(_mm_set1_epi32(0x7fff_ffff));
        let sign_bit = _mm_castsi128_ps(_mm_set1_epi32(i32::MIN));
        let abs = |x: __m128| _mm_and_ps(x, abs_bits);
        let dot = |ax, ay, az, bx, by, bz| {
            _mm_add_ps(
                _mm_add_ps(_mm_mul_ps(ax, bx), _mm_mul_ps(ay, by)),
                _mm_mul_ps(az, bz),
            )
        };
        let (e1x, e1y, e1z) = (ld(&tri.e1[0]), ld(&tri.e1[1]), ld(&tri.e1[2]));
        let (e2x, e2y, e2z) = (ld(&tri.e2[0]), ld(&tri.e2[1]), ld(&tri.e2[2]));
        let (dx, dy, dz) = (ld(&r.dir[0]), ld(&r.dir[1]), ld(&r.dir[2]));
        let (e1m, e2m) = (ld(&tri.e1_max), ld(&tri.e2_max));
        let px = _mm_sub_ps(_mm_mul_ps(dy, e2z), _mm_mul_ps(e2y, dz));
        let py = _mm_sub_ps(_mm_mul_ps(dz, e2x), _mm_mul_ps(e2z, dx));
        let pz = _mm_sub_ps(_mm_mul_ps(dx, e2y), _mm_mul_ps(e2x, dy));
        let det = dot(e1x, e1y, e1z, px, py, pz);
        let adet = abs(det);
        let sx = _mm_sub_ps(ld(&r.origin[0]), ld(&tri.v0[0]));
        let sy = _mm_sub_ps(ld(&r.origin[1]), ld(&tri.v0[1]));
        let sz = _mm_sub_ps(ld(&r.origin[2]), ld(&tri.v0[2]));
        let us = dot(sx, sy, sz, px, py, pz);
        let qx = _mm_sub_ps(_mm_mul_ps(sy, e1z), _mm_mul_ps(e1y, sz));
        let qy = _mm_sub_ps(_mm_mul_ps(sz, e1x), _mm_mul_ps(e1z, sx));
        let qz = _mm_sub_ps(_mm_mul_ps(sx, e1y), _mm_mul_ps(e1x, sy));
        let vs = dot(dx, dy, dz, qx, qy, qz);
        let sign = _mm_and_ps(det, sign_bit);
        let (su, sv) = (_mm_xor_ps(us, sign), _mm_xor_ps(vs, sign));
        let margin = _mm_set1_ps(1.0 + 1.0 / 256.0);
        let floor = _mm_set1_ps(f32::MIN_POSITIVE);
        let (wide_u, wide_v, clear) = if SURE {
            let scale = ld(&r.scale);
            let sm = _mm_max_ps(_mm_max_ps(abs(sx), abs(sy)), abs(sz));
            let wu = _mm_mul_ps(_mm_mul_ps(scale, e2m), _mm_add_ps(sm, e1m));
            let wv = _mm_mul_ps(_mm_mul_ps(scale, e1m), _mm_add_ps(sm, e2m));
            let cheap = _mm_mul_ps(_mm_mul_ps(ld(&r.clear_scale), e1m), e2m);
            (wu, wv, _mm_cmpgt_ps(adet, cheap))
        } else {
            let zero = _mm_setzero_ps();
            (zero, zero, _mm_cmpneq_ps(det, zero))
        };
        let edge_u = _mm_max_ps(_mm_mul_ps(wide_u, margin), floor);
        let edge_v = _mm_max_ps(_mm_mul_ps(wide_v, margin), floor);
        // A relative 2^-20 of |det| besides, for the roundings of `u`, `v`
        // and `u + v` when there is no widening.
        let slack = _mm_mul_ps(adet, _mm_set1_ps(1.0 / (1u32 << 20) as f32));
        let edge_u = _mm_add_ps(edge_u, slack);
        let edge_v = _mm_add_ps(edge_v, slack);
        let sum = _mm_add_ps(
            _mm_mul_ps(_mm_add_ps(adet, _mm_add_ps(wide_u, wide_v)), margin),
            _mm_add_ps(floor, slack),
        );
        let miss = _mm_or_ps(
            _mm_or_ps(
                _mm_cmplt_ps(su, _mm_xor_ps(edge_u, sign_bit)),
                _mm_cmplt_ps(sv, _mm_xor_ps(edge_v, sign_bit)),
            ),
            _mm_cmpgt_ps(_mm_add_ps(su, sv), sum),
        );
        let dropped = _mm_and_ps(miss, clear);
        lanes & !(_mm_movemask_ps(dropped) as u32)
    }
}
