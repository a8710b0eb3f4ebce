//! The AVX2 kernels of the coherent-ray path of [`super::Bvh4`] and
//! [`super::Bvh8`] (issue 8, item 4): eight rays in structure-of-arrays
//! lanes traverse the 4- or 8-wide tree together (one kernel, generic over
//! the node width), as in Wald, Slusallek, Benthin, Wagner, "Interactive rendering
//! with coherent ray tracing" (2001) and Embree's packet kernels (Wald et
//! al. 2014).
//!
//! At an inner node each child box is tested against all active rays at
//! once (the box broadcast, one ray per lane) with exactly the arithmetic
//! of [`super::box4`] (and [`super::box8`], the same) per lane: near plane by the sign of the reciprocal
//! direction (shared by the packet, see [`super::packet`]), `z`, `y`, `x`
//! in that order, `maxps`/`minps` with the same operand order, the exit
//! widened by [`NodeBox::ROBUST_EXIT`]. So a ray enters a child here
//! exactly when its own traversal would with the same `tfar`, and culling
//! stays conservative. Entered children are visited near to far by the
//! packet's smallest entry distance (occlusion: highest slot first, as
//! single rays go, `enter.rs`); the others are pushed with their
//! per-lane entry distances (NaN in lanes that did not enter) and, when
//! popped, go on only with the lanes whose entry still lies within their
//! `tfar` (which shrinks as hits are found).
//!
//! At a leaf each triangle of the `tri4` packs is broadcast and tested
//! against the eight rays with the operations of [`super::tri4_sse`] (which
//! are [`crate::tri::Moller`]'s, in the same order, no FMA), so every lane
//! gets bit for bit the scalar test's hit, `t`, `u` and `v`. A lane out of
//! play (tail of a batch, an occluded shadow ray) has `tfar = NaN`, which
//! fails every compare of both tests.

use super::node4::Child4;
use super::node_box::NodeBox;
use super::packet::{PacketTree, View, WideNode};
use super::prefetch::prefetch_child;
use super::tri4::{Tri4, CAP};
use crate::hit::Hit;
use crate::ray::Ray;
use std::arch::x86_64::*;
use std::mem::MaybeUninit;

/// Rays per packet.
pub(crate) use super::packet::LANES;

/// Unit roundoff of `f32`, as in the scalar test.
const U: f32 = f32::EPSILON * 0.5;

/// Eight rays in structure-of-arrays layout, prepared as [`super::tri4`]'s
/// `Ray4` and [`super::box4`]'s `RayBox4` prepare one ray each (same
/// values per lane; `|d|` and `0.75 · scale` are formed in registers), plus
/// the plane rows met first, common to the packet.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(crate) struct Packet8 {
    pub origin: [[f32; LANES]; 3],
    pub dir: [[f32; LANES]; 3],
    pub inv_dir: [[f32; LANES]; 3],
    pub tnear: [f32; LANES],
    /// `tfar` per lane; NaN for a lane out of play.
    pub tfar: [f32; LANES],
    pub scale: [f32; LANES],
    /// Per axis, the row of [`super::box4::Box4::planes`] met first.
    pub near: [usize; 3],
}

/// The answers of a packet: per lane the nearest hit (`t`, `u`, `v`,
/// mesh triangle) where `hit` has the lane's bit, or whether it is
/// occluded (`hit` alone).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Hits8 {
    pub hit: u32,
    pub t: [f32; LANES],
    pub u: [f32; LANES],
    pub v: [f32; LANES],
    pub prim: [u32; LANES],
}

/// Smallest lane of `v`.
#[inline]
#[target_feature(enable = "avx2")]
fn hmin(v: __m256) -> f32 {
    let x = _mm256_min_ps(v, _mm256_permute2f128_ps::<1>(v, v));
    let x = _mm256_min_ps(x, _mm256_shuffle_ps::<0b01_00_11_10>(x, x));
    let x = _mm256_min_ps(x, _mm256_shuffle_ps::<0b10_11_00_01>(x, x));
    _mm256_cvtss_f32(x)
}

/// Load a row of eight lanes.
#[inline]
#[target_feature(enable = "avx2")]
fn ld(row: &[f32; LANES]) -> __m256 {
    // SAFETY: `row` is eight readable floats; the load is unaligned.
    unsafe { _mm256_loadu_ps(row.as_ptr()) }
}

/// Most children of any node (the arrays below are sized for it).
const MAX_WIDTH: usize = 8;

/// Traverse `view` of `bvh` with the packet `p` of `rays` (nearest hits for
/// `ANY = false`, occlusion for `ANY = true`), answers in `out`; at a node
/// or leaf with `switch` or fewer active rays, they go on one by one with
/// the tree's own single-ray traversal ([`PacketTree::single_subtree`]).
/// `STACK` entries must hold the tree's deepest stack (each node pushes at
/// most its width less one).
///
/// # Safety
/// The CPU must support AVX2 (checked by the caller with
/// `is_x86_feature_detected!`).
#[target_feature(enable = "avx2")]
pub(crate) fn traverse<const ANY: bool, B: PacketTree, const STACK: usize>(
    bvh: &B,
    view: &View<'_, B::Node>,
    rays: &[Ray],
    p: &Packet8,
    switch: u32,
    out: &mut Hits8,
) {
    let mut tfar = ld(&p.tfar);
    let nan = _mm256_set1_ps(f32::NAN);
    let inf = _mm256_set1_ps(f32::INFINITY);
    let mut u = _mm256_setzero_ps();
    let mut v = _mm256_setzero_ps();
    let mut prim = _mm256_set1_epi32(-1);
    let mut has = _mm256_setzero_ps();
    let mut occluded = 0u32;
    // Lanes in play: tfar not NaN.
    let mut act = _mm256_cmp_ps::<_CMP_ORD_Q>(tfar, tfar);
    let mut cur = view.root;
    let mut stack_t = [const { MaybeUninit::<[f32; LANES]>::uninit() }; STACK];
    let mut stack_c = [const { MaybeUninit::<Child4>::uninit() }; STACK];
    let mut sp = 0usize;
    let lanes = RayLanes::load(p);
    'walk: loop {
        let am = _mm256_movemask_ps(act) as u32;
        if am.count_ones() <= switch {
            // Few rays left in this subtree: one at a time (hybrid
            // traversal, Benthin et al. 2012).
            let mut tf = [0f32; LANES];
            // SAFETY: `tf` is eight floats; unaligned store.
            unsafe { _mm256_storeu_ps(tf.as_mut_ptr(), tfar) };
            if ANY {
                for l in Lanes(am) {
                    if bvh.single_subtree::<true>(view, cur, &rays[l], &mut tf[l], &mut None) {
                        tf[l] = f32::NAN;
                        occluded |= 1 << l;
                    }
                }
                tfar = ld(&tf);
                if _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_ORD_Q>(tfar, tfar)) == 0 {
                    break 'walk;
                }
            } else {
                let mut spill = Hits8::default();
                // SAFETY: each destination is an array of eight lanes of
                // four bytes; unaligned stores.
                unsafe {
                    _mm256_storeu_ps(spill.u.as_mut_ptr(), u);
                    _mm256_storeu_ps(spill.v.as_mut_ptr(), v);
                    _mm256_storeu_si256(spill.prim.as_mut_ptr() as *mut __m256i, prim);
                }
                let mut hm = _mm256_movemask_ps(has) as u32;
                for l in Lanes(am) {
                    let mut best = (hm & (1 << l) != 0).then(|| Hit {
                        t: tf[l],
                        u: spill.u[l],
                        v: spill.v[l],
                        prim: spill.prim[l],
                    });
                    bvh.single_subtree::<false>(view, cur, &rays[l], &mut tf[l], &mut best);
                    if let Some(h) = best {
                        tf[l] = h.t;
                        spill.u[l] = h.u;
                        spill.v[l] = h.v;
                        spill.prim[l] = h.prim;
                        hm |= 1 << l;
                    }
                }
                tfar = ld(&tf);
                u = ld(&spill.u);
                v = ld(&spill.v);
                // SAFETY: `spill.prim` is eight lanes of four bytes.
                prim = unsafe { _mm256_loadu_si256(spill.prim.as_ptr() as *const __m256i) };
                let bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
                let set = _mm256_and_si256(_mm256_set1_epi32(hm as i32), bit);
                has = _mm256_castsi256_ps(_mm256_cmpeq_epi32(set, bit));
            }
        } else if cur.count > 0 {
            let (first, count) = (cur.index as usize, cur.count as usize);
            let mut left = count;
            for pack in &view.leaves.packs()[first..first + count.div_ceil(4)] {
                for k in 0..left.min(4) {
                    let h = tri_hits(pack, k, &lanes, tfar, act);
                    let Some((mask, t, tu, tv)) = h else { continue };
                    if ANY {
                        occluded |= _mm256_movemask_ps(mask) as u32;
                        tfar = _mm256_blendv_ps(tfar, nan, mask);
                        act = _mm256_andnot_ps(mask, act);
                    } else {
                        // The earlier triangle keeps a tie, as in the
                        // scalar leaf loop.
                        let nearer = _mm256_or_ps(
                            _mm256_cmp_ps::<_CMP_LT_OQ>(t, tfar),
                            _mm256_xor_ps(has, _mm256_castsi256_ps(_mm256_set1_epi32(-1))),
                        );
                        let upd = _mm256_and_ps(mask, nearer);
                        tfar = _mm256_blendv_ps(tfar, t, upd);
                        u = _mm256_blendv_ps(u, tu, upd);
                        v = _mm256_blendv_ps(v, tv, upd);
                        prim = _mm256_castps_si256(_mm256_blendv_ps(
                            _mm256_castsi256_ps(prim),
                            _mm256_castsi256_ps(_mm256_set1_epi32(pack.prim[k] as i32)),
                            upd,
                        ));
                        has = _mm256_or_ps(has, upd);
                    }
                }
                left = left.saturating_sub(4);
            }
            if ANY && _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_ORD_Q>(tfar, tfar)) == 0 {
                break 'walk;
            }
        } else {
            let node = &view.nodes[cur.index as usize];
            let mut ent = [nan; MAX_WIDTH];
            let mut near = [inf; MAX_WIDTH];
            let mut slots = 0u32;
            for s in 0..B::Node::WIDTH {
                if node.child(s) == Child4::EMPTY {
                    break;
                }
                let (enter, m) = box_hits(node, s, &lanes, p, tfar, act);
                slots |= ((_mm256_movemask_ps(m) != 0) as u32) << s;
                ent[s] = _mm256_blendv_ps(nan, enter, m);
                near[s] = _mm256_blendv_ps(inf, enter, m);
            }
            if slots != 0 {
                let first = slots.trailing_zeros() as usize;
                if slots & (slots - 1) == 0 {
                    // One child entered: no ordering.
                    cur = node.child(first);
                    act = _mm256_cmp_ps::<_CMP_LE_OQ>(ent[first], tfar);
                    continue;
                }
                // Entered children, farthest first by the packet's nearest
                // entry; for occlusion in slot order, so the highest slot
                // is visited first, as by single rays (`enter.rs`): on the
                // scatter's shadow rays 1.2x faster than near to far (no
                // reductions, no sort; BENCHMARKS.md, step 3u).
                let mut tmin = [0f32; MAX_WIDTH];
                let mut order = [0usize; MAX_WIDTH];
                let mut n = 0;
                while slots != 0 {
                    let s = slots.trailing_zeros() as usize;
                    slots &= slots - 1;
                    if ANY {
                        order[n] = s;
                        n += 1;
                        continue;
                    }
                    tmin[s] = hmin(near[s]);
                    let mut j = n;
                    while j > 0 && tmin[order[j - 1]] < tmin[s] {
                        order[j] = order[j - 1];
                        j -= 1;
                    }
                    order[j] = s;
                    n += 1;
                }
                for &s in &order[..n - 1] {
                    // SAFETY: `ent[s]` is eight floats and the slot is a
                    // local array entry of eight floats; unaligned store.
                    unsafe {
                        _mm256_storeu_ps(stack_t[sp].as_mut_ptr() as *mut f32, ent[s]);
                    }
                    stack_c[sp].write(node.child(s));
                    sp += 1;
                    // Fetched now, visited later (`prefetch.rs`).
                    prefetch_child(view.nodes, view.leaves.packs(), node.child(s));
                }
                let s = order[n - 1];
                cur = node.child(s);
                act = _mm256_cmp_ps::<_CMP_LE_OQ>(ent[s], tfar);
                continue;
            }
        }
        // Pop, with the lanes whose entry still lies within their tfar.
        loop {
            if sp == 0 {
                break 'walk;
            }
            sp -= 1;
            // SAFETY: entries below the stack pointer were written by the
            // pushes above (`sp` grows only right after both writes).
            let t = unsafe { stack_t[sp].assume_init_ref() };
            let a = _mm256_cmp_ps::<_CMP_LE_OQ>(ld(t), tfar);
            if _mm256_movemask_ps(a) != 0 {
                // SAFETY: as above.
                cur = unsafe { stack_c[sp].assume_init() };
                act = a;
                break;
            }
        }
    }
    if ANY {
        out.hit = occluded;
    } else {
        out.hit = _mm256_movemask_ps(has) as u32;
        // SAFETY: each destination is an array of eight lanes of four
        // bytes; unaligned stores.
        unsafe {
            _mm256_storeu_ps(out.t.as_mut_ptr(), tfar);
            _mm256_storeu_ps(out.u.as_mut_ptr(), u);
            _mm256_storeu_ps(out.v.as_mut_ptr(), v);
            _mm256_storeu_si256(out.prim.as_mut_ptr() as *mut __m256i, prim);
        }
    }
}

/// The set bits of a lane mask, lowest first.
struct Lanes(u32);

impl Iterator for Lanes {
    type Item = usize;

    #[inline(always)]
    fn next(&mut self) -> Option<usize> {
        (self.0 != 0).then(|| {
            let l = self.0.trailing_zeros() as usize;
            self.0 &= self.0 - 1;
            l
        })
    }
}

/// The packet's rows in registers' reach.
struct RayLanes {
    o: [__m256; 3],
    d: [__m256; 3],
    d_abs: [__m256; 3],
    inv: [__m256; 3],
    tnear: __m256,
    scale: __m256,
    clear_scale: __m256,
}

impl RayLanes {
    #[inline]
    #[target_feature(enable = "avx2")]
    fn load(p: &Packet8) -> Self {
        let d = [ld(&p.dir[0]), ld(&p.dir[1]), ld(&p.dir[2])];
        let abs_bits = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fff_ffff));
        let abs = |x: __m256| _mm256_and_ps(x, abs_bits);
        let scale = ld(&p.scale);
        RayLanes {
            o: [ld(&p.origin[0]), ld(&p.origin[1]), ld(&p.origin[2])],
            d,
            d_abs: [abs(d[0]), abs(d[1]), abs(d[2])],
            inv: [ld(&p.inv_dir[0]), ld(&p.inv_dir[1]), ld(&p.inv_dir[2])],
            tnear: ld(&p.tnear),
            scale,
            // As `Ray4::new`: the scalar test's `0.75 * scale * ...`
            // multiplies left to right, so this first product is the same.
            clear_scale: _mm256_mul_ps(_mm256_set1_ps(0.75), scale),
        }
    }
}

/// Box `s` of a node against the lanes in `act`: entry distances and the
/// mask of lanes that enter within `[tnear, tfar]`, per lane exactly
/// [`super::box4::Box4::entries`].
#[inline]
#[target_feature(enable = "avx2")]
fn box_hits(
    node: &impl WideNode,
    s: usize,
    r: &RayLanes,
    p: &Packet8,
    tfar: __m256,
    act: __m256,
) -> (__m256, __m256) {
    let mut enter = r.tnear;
    let mut exit = _mm256_set1_ps(f32::INFINITY);
    for a in (0..3).rev() {
        let n = p.near[a];
        let lo = _mm256_set1_ps(node.plane(n, s));
        let hi = _mm256_set1_ps(node.plane(n ^ 1, s));
        let tn = _mm256_mul_ps(_mm256_sub_ps(lo, r.o[a]), r.inv[a]);
        let tf = _mm256_mul_ps(_mm256_sub_ps(hi, r.o[a]), r.inv[a]);
        enter = _mm256_max_ps(tn, enter);
        exit = _mm256_min_ps(tf, exit);
    }
    let exit = _mm256_min_ps(
        _mm256_mul_ps(exit, _mm256_set1_ps(NodeBox::ROBUST_EXIT)),
        tfar,
    );
    let m = _mm256_and_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(enter, exit), act);
    (enter, m)
}

/// Triangle `k` of `tri` against the lanes in `act` over `[tnear, tfar]`:
/// `None` when no lane hits, else the hit mask and `t`, `u`, `v` (per lane
/// exactly [`crate::tri::Moller`]'s test, see [`super::tri4_sse`]).
#[inline]
#[target_feature(enable = "avx2")]
fn tri_hits(
    tri: &Tri4,
    k: usize,
    r: &RayLanes,
    tfar: __m256,
    act: __m256,
) -> Option<(__m256, __m256, __m256, __m256)> {
    let abs_bits = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fff_ffff));
    let sign_bit = _mm256_castsi256_ps(_mm256_set1_epi32(i32::MIN));
    let abs = |x: __m256| _mm256_and_ps(x, abs_bits);
    let dot = |ax, ay, az, bx, by, bz| {
        _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(ax, bx), _mm256_mul_ps(ay, by)),
            _mm256_mul_ps(az, bz),
        )
    };
    let b = |x: f32| _mm256_set1_ps(x);
    let (e1x, e1y, e1z) = (b(tri.e1[0][k]), b(tri.e1[1][k]), b(tri.e1[2][k]));
    let (e2x, e2y, e2z) = (b(tri.e2[0][k]), b(tri.e2[1][k]), b(tri.e2[2][k]));
    let [dx, dy, dz] = r.d;
    let (e1m, e2m) = (b(tri.e1_max[k]), b(tri.e2_max[k]));

    // p = d × e2, det = e1 · p.
    let px = _mm256_sub_ps(_mm256_mul_ps(dy, e2z), _mm256_mul_ps(e2y, dz));
    let py = _mm256_sub_ps(_mm256_mul_ps(dz, e2x), _mm256_mul_ps(e2z, dx));
    let pz = _mm256_sub_ps(_mm256_mul_ps(dx, e2y), _mm256_mul_ps(e2x, dy));
    let det = dot(e1x, e1y, e1z, px, py, pz);
    let adet = abs(det);

    // Not parallel: |det| above the cheap bound, else the tight one.
    let cheap = _mm256_mul_ps(_mm256_mul_ps(r.clear_scale, e1m), e2m);
    let mut clear = _mm256_cmp_ps::<_CMP_GT_OQ>(adet, cheap);
    let want = _mm256_movemask_ps(act);
    if _mm256_movemask_ps(clear) & want != want {
        let [adx, ady, adz] = r.d_abs;
        let (a2x, a2y, a2z) = (abs(e2x), abs(e2y), abs(e2z));
        let pcx = _mm256_add_ps(_mm256_mul_ps(ady, a2z), _mm256_mul_ps(adz, a2y));
        let pcy = _mm256_add_ps(_mm256_mul_ps(adz, a2x), _mm256_mul_ps(adx, a2z));
        let pcz = _mm256_add_ps(_mm256_mul_ps(adx, a2y), _mm256_mul_ps(ady, a2x));
        let sum = dot(abs(e1x), abs(e1y), abs(e1z), pcx, pcy, pcz);
        let tight = _mm256_mul_ps(b(8.0 * U), sum);
        clear = _mm256_or_ps(clear, _mm256_cmp_ps::<_CMP_GT_OQ>(adet, tight));
    }
    let clear = _mm256_and_ps(clear, act);
    if _mm256_movemask_ps(clear) == 0 {
        return None;
    }

    let inv_det = _mm256_div_ps(b(1.0), det);
    let sx = _mm256_sub_ps(r.o[0], b(tri.v0[0][k]));
    let sy = _mm256_sub_ps(r.o[1], b(tri.v0[1][k]));
    let sz = _mm256_sub_ps(r.o[2], b(tri.v0[2][k]));
    let u = _mm256_mul_ps(dot(sx, sy, sz, px, py, pz), inv_det);
    // q = s × e1.
    let qx = _mm256_sub_ps(_mm256_mul_ps(sy, e1z), _mm256_mul_ps(e1y, sz));
    let qy = _mm256_sub_ps(_mm256_mul_ps(sz, e1x), _mm256_mul_ps(e1z, sx));
    let qz = _mm256_sub_ps(_mm256_mul_ps(sx, e1y), _mm256_mul_ps(e1x, sy));
    let v = _mm256_mul_ps(dot(dx, dy, dz, qx, qy, qz), inv_det);

    // Tolerances, capped.
    let c = _mm256_mul_ps(r.scale, abs(inv_det));
    let sm = _mm256_max_ps(_mm256_max_ps(abs(sx), abs(sy)), abs(sz));
    let cap = b(CAP);
    let eu = _mm256_min_ps(
        _mm256_mul_ps(_mm256_mul_ps(c, e2m), _mm256_add_ps(sm, e1m)),
        cap,
    );
    let ev = _mm256_min_ps(
        _mm256_mul_ps(_mm256_mul_ps(c, e1m), _mm256_add_ps(sm, e2m)),
        cap,
    );
    let t = _mm256_mul_ps(dot(e2x, e2y, e2z, qx, qy, qz), inv_det);

    let inside = _mm256_and_ps(
        _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GE_OQ>(u, _mm256_xor_ps(eu, sign_bit)),
            _mm256_cmp_ps::<_CMP_GE_OQ>(v, _mm256_xor_ps(ev, sign_bit)),
        ),
        _mm256_cmp_ps::<_CMP_LE_OQ>(
            _mm256_add_ps(u, v),
            _mm256_add_ps(b(1.0), _mm256_add_ps(eu, ev)),
        ),
    );
    let in_range = _mm256_and_ps(
        _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GE_OQ>(t, r.tnear),
            _mm256_cmp_ps::<_CMP_LE_OQ>(t, tfar),
        ),
        _mm256_cmp_ps::<_CMP_LT_OQ>(t, b(f32::INFINITY)),
    );
    let hit = _mm256_and_ps(_mm256_and_ps(inside, in_range), clear);
    if _mm256_movemask_ps(hit) == 0 {
        return None;
    }
    Some((hit, t, u, v))
}
