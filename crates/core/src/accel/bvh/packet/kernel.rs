//! The kernel of the coherent-ray path of [`super::Bvh4`] and
//! [`super::Bvh8`]: a packet of rays in structure-of-arrays
//! lanes traverses the 4- or 8-wide tree together (one kernel, generic over
//! the node width and over the packet width: eight rays with AVX2, sixteen
//! with AVX-512, [`super::super::lanes`]), as in Wald, Slusallek, Benthin, Wagner,
//! "Interactive rendering with coherent ray tracing" (2001) and Embree's
//! packet kernels (Wald et al. 2014).
//!
//! At an 8-wide node the children that no ray of the packet can enter are
//! found first, all eight in one AVX pass over interval bounds of the
//! packet's rays ([`super::super::frustum`], formed once per packet:
//! shadow rays 1.03–1.15× and primaries 1.12–1.23× faster; 4-wide nodes
//! test every slot). Each other child box is tested against all active rays at
//! once (the box broadcast, one ray per lane) with exactly the arithmetic
//! of [`super::super::box4`] (and [`super::super::box8`], the same) per lane: near plane by the sign of the reciprocal
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
//! against the packet's rays with the operations of `tri4::sse` (which
//! are [`crate::tri::Moller`]'s, in the same order, no FMA), so every lane
//! gets bit for bit the scalar test's hit, `t`, `u` and `v`. A lane out of
//! play (tail of a batch, an occluded shadow ray) has `tfar = NaN`, which
//! fails every compare of both tests.

use super::super::frustum::Frustum;
use super::super::lanes::{Lanes, L16, L8};
use super::super::prefetch::prefetch_child;
use super::super::tri4::{Tri4, CAP};
use super::super::wide_node::Child4;
use super::{PacketTree, View, WideNode};
use crate::accel::node_box::NodeBox;
use crate::hit::Hit;
use crate::ray::Ray;
use std::mem::MaybeUninit;

/// Unit roundoff of `f32`, as in the scalar test.
const U: f32 = f32::EPSILON * 0.5;

/// `L` rays in structure-of-arrays layout, prepared as [`super::super::tri4`]'s
/// `Ray4` and [`super::super::ray_box`]'s `RayBox` prepare one ray each (same
/// values per lane; `|d|` and `0.75 · scale` are formed in registers), plus
/// the plane rows met first, common to the packet.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct Packet<const L: usize> {
    pub origin: [[f32; L]; 3],
    pub dir: [[f32; L]; 3],
    pub inv_dir: [[f32; L]; 3],
    pub tnear: [f32; L],
    /// `tfar` per lane; NaN for a lane out of play.
    pub tfar: [f32; L],
    pub scale: [f32; L],
    /// Per axis, the row of [`super::super::box4::Box4::planes`] met first.
    pub near: [usize; 3],
}

/// The answers of a packet of `L` rays: per lane the nearest hit (`t`,
/// `u`, `v`, mesh triangle) where `hit` has the lane's bit, or whether it
/// is occluded (`hit` alone).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PacketHits<const L: usize> {
    pub hit: u32,
    pub t: [f32; L],
    pub u: [f32; L],
    pub v: [f32; L],
    pub prim: [u32; L],
}

impl<const L: usize> Default for PacketHits<L> {
    fn default() -> Self {
        PacketHits {
            hit: 0,
            t: [0.0; L],
            u: [0.0; L],
            v: [0.0; L],
            prim: [0; L],
        }
    }
}

/// Most children of any node (the arrays below are sized for it).
const MAX_WIDTH: usize = 8;

/// A packet width the kernel runs at, with its entry point compiled for
/// the width's instructions.
pub(crate) trait Width<const L: usize>: Lanes<L> {
    /// [`traverse`] at this width.
    ///
    /// # Safety
    /// The CPU must have the width's features ([`L8`]: AVX2; [`L16`]:
    /// AVX-512 F, VL, BW, DQ besides).
    unsafe fn traverse<const ANY: bool, B: PacketTree, const STACK: usize>(
        bvh: &B,
        view: &View<'_, B::Node>,
        rays: &[Ray],
        p: &Packet<L>,
        switch: u32,
        out: &mut PacketHits<L>,
    );
}

impl Width<8> for L8 {
    #[target_feature(enable = "avx2")]
    unsafe fn traverse<const ANY: bool, B: PacketTree, const STACK: usize>(
        bvh: &B,
        view: &View<'_, B::Node>,
        rays: &[Ray],
        p: &Packet<8>,
        switch: u32,
        out: &mut PacketHits<8>,
    ) {
        traverse::<ANY, 8, L8, B, STACK>(bvh, view, rays, p, switch, out)
    }
}

impl Width<16> for L16 {
    #[target_feature(enable = "avx2,fma,avx512f,avx512vl,avx512bw,avx512dq,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn traverse<const ANY: bool, B: PacketTree, const STACK: usize>(
        bvh: &B,
        view: &View<'_, B::Node>,
        rays: &[Ray],
        p: &Packet<16>,
        switch: u32,
        out: &mut PacketHits<16>,
    ) {
        traverse::<ANY, 16, L16, B, STACK>(bvh, view, rays, p, switch, out)
    }
}

/// Traverse `view` of `bvh` with the packet `p` of `rays` (nearest hits for
/// `ANY = false`, occlusion for `ANY = true`), answers in `out`; at a node
/// or leaf with `switch` or fewer active rays, they go on one by one with
/// the tree's own single-ray traversal ([`PacketTree::single_subtree`]).
/// `STACK` entries must hold the tree's deepest stack (each node pushes at
/// most its width less one). Inlined into [`Width::traverse`], which is
/// compiled for the lanes' instructions.
#[inline(always)]
fn traverse<const ANY: bool, const L: usize, V: Lanes<L>, B: PacketTree, const STACK: usize>(
    bvh: &B,
    view: &View<'_, B::Node>,
    rays: &[Ray],
    p: &Packet<L>,
    switch: u32,
    out: &mut PacketHits<L>,
) {
    let mut tfar = V::load(&p.tfar);
    let nan = V::splat(f32::NAN);
    let inf = V::splat(f32::INFINITY);
    let mut u = V::splat(0.0);
    let mut v = V::splat(0.0);
    let mut prim = V::splat_int(-1);
    let mut has = V::mask(0);
    let mut occluded = 0u32;
    // Lanes in play: tfar not NaN.
    let mut act = tfar.ordered();
    let mut cur = view.root;
    let mut stack_t = [const { MaybeUninit::<[f32; L]>::uninit() }; STACK];
    let mut stack_c = [const { MaybeUninit::<Child4>::uninit() }; STACK];
    let mut sp = 0usize;
    let lanes = RayLanes::<L, V>::load(p);
    // The packet's bounds, for nodes that use them (see the node test).
    let bundle = if B::Node::BUNDLED {
        Some(Frustum::of::<L, V>(
            &lanes.o,
            &lanes.inv,
            lanes.tnear,
            tfar,
            act,
            p.near,
        ))
    } else {
        None
    };
    'walk: loop {
        let am = V::bits(act);
        if am.count_ones() <= switch {
            // Few rays left in this subtree: one at a time (hybrid
            // traversal, Benthin et al. 2012).
            let mut tf = [0f32; L];
            tfar.store(&mut tf);
            if ANY {
                for l in SetLanes(am) {
                    if bvh.single_subtree::<true>(view, cur, &rays[l], &mut tf[l], &mut None) {
                        tf[l] = f32::NAN;
                        occluded |= 1 << l;
                    }
                }
                tfar = V::load(&tf);
                if V::bits(tfar.ordered()) == 0 {
                    break 'walk;
                }
            } else {
                let mut spill = PacketHits::<L>::default();
                u.store(&mut spill.u);
                v.store(&mut spill.v);
                V::store_int(prim, &mut spill.prim);
                let mut hm = V::bits(has);
                for l in SetLanes(am) {
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
                tfar = V::load(&tf);
                u = V::load(&spill.u);
                v = V::load(&spill.v);
                prim = V::load_int(&spill.prim);
                has = V::mask(hm);
            }
        } else if cur.count > 0 {
            let (first, count) = (cur.index as usize, cur.count as usize);
            let mut left = count;
            for pack in &view.leaves.packs()[first..first + count.div_ceil(4)] {
                for k in 0..left.min(4) {
                    let h = tri_hits::<L, V>(pack, k, &lanes, tfar, act);
                    let Some((mask, t, tu, tv)) = h else { continue };
                    if ANY {
                        occluded |= V::bits(mask);
                        tfar = tfar.blend(nan, mask);
                        act = V::andnot(mask, act);
                    } else {
                        // The earlier triangle keeps a tie, as in the
                        // scalar leaf loop.
                        let nearer = V::or(t.lt(tfar), V::andnot(has, V::mask(u32::MAX)));
                        let upd = V::and(mask, nearer);
                        tfar = tfar.blend(t, upd);
                        u = u.blend(tu, upd);
                        v = v.blend(tv, upd);
                        prim = V::blend_int(prim, V::splat_int(pack.prim[k] as i32), upd);
                        has = V::or(has, upd);
                    }
                }
                left = left.saturating_sub(4);
            }
            if ANY && V::bits(tfar.ordered()) == 0 {
                break 'walk;
            }
        } else {
            let node = &view.nodes[cur.index as usize];
            // No check for the first unused slot: no lane enters its
            // inverted box (and the bundle's test drops it). One blend per
            // slot (the `near` copy went: 1M terrain
            // primaries took 4% fewer instructions, BENCHMARKS.md).
            let mut ent = [nan; MAX_WIDTH];
            let mut slots = 0u32;
            // The lanes out of this subtree get a NaN limit, which fails
            // every lane's box test as a NaN `tfar` does (one blend per
            // node instead of a mask operation per box).
            let limit = nan.blend(tfar, act);
            if let Some(bundle) = &bundle {
                // Only the slots the packet's bundle may enter are tested
                // lane by lane (`frustum.rs`); the others would enter no
                // lane, unused slots among them.
                // SAFETY: the widths that run this kernel all have AVX.
                let mut maybe = unsafe { node.slots_within(bundle, p.near) };
                while maybe != 0 {
                    let s = maybe.trailing_zeros() as usize;
                    maybe &= maybe - 1;
                    let (enter, m) = box_hits::<L, V>(node, s, &lanes, p, limit);
                    slots |= ((V::bits(m) != 0) as u32) << s;
                    ent[s] = nan.blend(enter, m);
                }
            } else {
                // Not bundled (`bvh4`): every slot tested, unrolled (a
                // loop over set bits was 1% slower on `bvh4`, and bounds
                // for four boxes were not faster).
                for (s, e) in ent.iter_mut().enumerate().take(B::Node::WIDTH) {
                    let (enter, m) = box_hits::<L, V>(node, s, &lanes, p, limit);
                    slots |= ((V::bits(m) != 0) as u32) << s;
                    *e = nan.blend(enter, m);
                }
            }
            if slots != 0 {
                let first = slots.trailing_zeros() as usize;
                if slots & (slots - 1) == 0 {
                    // One child entered: no ordering.
                    cur = node.child(first);
                    act = ent[first].le(tfar);
                    continue;
                }
                // Entered children, farthest first by the packet's nearest
                // entry; for occlusion in slot order, so the highest slot
                // is visited first, as by single rays (`enter.rs`): on the
                // scatter's shadow rays 1.2x faster than near to far (no
                // reductions, no sort; BENCHMARKS.md).
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
                    // The lanes that entered are those with an entry (an
                    // entry that is NaN enters no box).
                    tmin[s] = inf.blend(ent[s], ent[s].ordered()).hmin();
                    let mut j = n;
                    while j > 0 && tmin[order[j - 1]] < tmin[s] {
                        order[j] = order[j - 1];
                        j -= 1;
                    }
                    order[j] = s;
                    n += 1;
                }
                for &s in &order[..n - 1] {
                    let mut row = [0f32; L];
                    ent[s].store(&mut row);
                    stack_t[sp].write(row);
                    stack_c[sp].write(node.child(s));
                    sp += 1;
                    // Fetched now, visited later (`prefetch.rs`).
                    prefetch_child(view.nodes, view.leaves.packs(), node.child(s));
                }
                let s = order[n - 1];
                cur = node.child(s);
                act = ent[s].le(tfar);
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
            let a = V::load(t).le(tfar);
            if V::bits(a) != 0 {
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
        out.hit = V::bits(has);
        tfar.store(&mut out.t);
        u.store(&mut out.u);
        v.store(&mut out.v);
        V::store_int(prim, &mut out.prim);
    }
}

/// The set bits of a lane mask, lowest first.
struct SetLanes(u32);

impl Iterator for SetLanes {
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
struct RayLanes<const L: usize, V: Lanes<L>> {
    o: [V; 3],
    d: [V; 3],
    d_abs: [V; 3],
    inv: [V; 3],
    tnear: V,
    scale: V,
    clear_scale: V,
}

impl<const L: usize, V: Lanes<L>> RayLanes<L, V> {
    #[inline(always)]
    fn load(p: &Packet<L>) -> Self {
        // Spelled out: `array::map`'s closures were not inlined into the
        // kernel compiled for the lanes' features (a call per packet).
        let rows = |r: &[[f32; L]; 3]| [V::load(&r[0]), V::load(&r[1]), V::load(&r[2])];
        let d = rows(&p.dir);
        let scale = V::load(&p.scale);
        RayLanes {
            o: rows(&p.origin),
            d,
            d_abs: [d[0].abs(), d[1].abs(), d[2].abs()],
            inv: rows(&p.inv_dir),
            tnear: V::load(&p.tnear),
            scale,
            // As `Ray4::new`: the scalar test's `0.75 * scale * ...`
            // multiplies left to right, so this first product is the same.
            clear_scale: V::splat(0.75).mul(scale),
        }
    }
}

/// Box `s` of a node against the lanes: entry distances and the mask of
/// lanes that enter within `[tnear, tfar]`, per lane exactly
/// [`super::super::box4::Box4::entries`] (none where `tfar` is NaN).
#[inline(always)]
fn box_hits<const L: usize, V: Lanes<L>>(
    node: &impl WideNode,
    s: usize,
    r: &RayLanes<L, V>,
    p: &Packet<L>,
    tfar: V,
) -> (V, V::Mask) {
    let mut enter = r.tnear;
    let mut exit = V::splat(f32::INFINITY);
    for a in (0..3).rev() {
        let n = p.near[a];
        let lo = V::splat(node.plane(n, s));
        let hi = V::splat(node.plane(n ^ 1, s));
        let tn = lo.sub(r.o[a]).mul(r.inv[a]);
        let tf = hi.sub(r.o[a]).mul(r.inv[a]);
        enter = tn.max(enter);
        exit = tf.min(exit);
    }
    let exit = exit.mul(V::splat(NodeBox::ROBUST_EXIT)).min(tfar);
    (enter, enter.le(exit))
}

/// Triangle `k` of `tri` against the lanes in `act` over `[tnear, tfar]`:
/// `None` when no lane hits, else the hit mask and `t`, `u`, `v` (per lane
/// exactly [`crate::tri::Moller`]'s test, see `tri4::sse`).
#[inline(always)]
fn tri_hits<const L: usize, V: Lanes<L>>(
    tri: &Tri4,
    k: usize,
    r: &RayLanes<L, V>,
    tfar: V,
    act: V::Mask,
) -> Option<(V::Mask, V, V, V)> {
    let dot = |ax: V, ay: V, az: V, bx: V, by: V, bz: V| ax.mul(bx).add(ay.mul(by)).add(az.mul(bz));
    let b = |x: f32| V::splat(x);
    let (e1x, e1y, e1z) = (b(tri.e1[0][k]), b(tri.e1[1][k]), b(tri.e1[2][k]));
    let (e2x, e2y, e2z) = (b(tri.e2[0][k]), b(tri.e2[1][k]), b(tri.e2[2][k]));
    let [dx, dy, dz] = r.d;
    let (e1m, e2m) = (b(tri.e1_max[k]), b(tri.e2_max[k]));

    // p = d × e2, det = e1 · p.
    let px = dy.mul(e2z).sub(e2y.mul(dz));
    let py = dz.mul(e2x).sub(e2z.mul(dx));
    let pz = dx.mul(e2y).sub(e2x.mul(dy));
    let det = dot(e1x, e1y, e1z, px, py, pz);
    let adet = det.abs();

    // Not parallel: |det| above the cheap bound, else the tight one.
    let cheap = r.clear_scale.mul(e1m).mul(e2m);
    let mut clear = adet.gt(cheap);
    let want = V::bits(act);
    if V::bits(clear) & want != want {
        let [adx, ady, adz] = r.d_abs;
        let (a2x, a2y, a2z) = (e2x.abs(), e2y.abs(), e2z.abs());
        let pcx = ady.mul(a2z).add(adz.mul(a2y));
        let pcy = adz.mul(a2x).add(adx.mul(a2z));
        let pcz = adx.mul(a2y).add(ady.mul(a2x));
        let sum = dot(e1x.abs(), e1y.abs(), e1z.abs(), pcx, pcy, pcz);
        let tight = b(8.0 * U).mul(sum);
        clear = V::or(clear, adet.gt(tight));
    }
    let clear = V::and(clear, act);
    if V::bits(clear) == 0 {
        return None;
    }

    let inv_det = b(1.0).div(det);
    let sx = r.o[0].sub(b(tri.v0[0][k]));
    let sy = r.o[1].sub(b(tri.v0[1][k]));
    let sz = r.o[2].sub(b(tri.v0[2][k]));
    let u = dot(sx, sy, sz, px, py, pz).mul(inv_det);
    // q = s × e1.
    let qx = sy.mul(e1z).sub(e1y.mul(sz));
    let qy = sz.mul(e1x).sub(e1z.mul(sx));
    let qz = sx.mul(e1y).sub(e1x.mul(sy));
    let v = dot(dx, dy, dz, qx, qy, qz).mul(inv_det);

    // Tolerances, capped.
    let c = r.scale.mul(inv_det.abs());
    let sm = sx.abs().max(sy.abs()).max(sz.abs());
    let cap = b(CAP);
    let eu = c.mul(e2m).mul(sm.add(e1m)).min(cap);
    let ev = c.mul(e1m).mul(sm.add(e2m)).min(cap);
    let t = dot(e2x, e2y, e2z, qx, qy, qz).mul(inv_det);

    let inside = V::and(
        V::and(u.ge(eu.neg()), v.ge(ev.neg())),
        u.add(v).le(b(1.0).add(eu.add(ev))),
    );
    let in_range = V::and(V::and(t.ge(r.tnear), t.le(tfar)), t.lt(b(f32::INFINITY)));
    let hit = V::and(V::and(inside, in_range), clear);
    if V::bits(hit) == 0 {
        return None;
    }
    Some((hit, t, u, v))
}
