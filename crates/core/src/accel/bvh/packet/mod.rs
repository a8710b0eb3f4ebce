//! The coherent-ray path of [`super::Bvh4`] and [`super::Bvh8`] over Möller
//! (Wald et al. 2001): `intersect_batch` and `occluded_batch` cut the batch
//! into packets of
//! consecutive rays and trace each coherent packet together through the
//! tree (Wald et al. 2001 coherent ray packets; Embree's packet kernels,
//! Wald et al. 2014) with the kernel of [`kernel`]: sixteen
//! rays with AVX-512 where the CPU has it, as Embree's packets on such
//! machines, else eight with AVX2. The traversal is generic over the node width
//! ([`WideNode`]: 4 or 8 children, boxes in structure-of-arrays layout) and
//! over the tree ([`PacketTree`], which supplies the hand-over to its own
//! single-ray traversal, Benthin et al. 2012).
//!
//! A packet is traced together when its rays share the signs of their
//! reciprocal directions (one octant): the box test then uses the same near
//! planes for every lane, which is what makes each lane's box test the
//! single-ray one. A full packet must also start or end within a small
//! part of the scene ([`spread`]): rays of one octant from scattered
//! points part at the root. Other packets, batches without AVX2 (detected
//! once per batch, with the width) and trees with other leaves take the
//! single-ray path, one ray after the other. Incoherent batches (random
//! directions) almost never form a packet, so they pay only the check.
//!
//! Every ray gets the single-ray traversal's answer: the same nearest `t`
//! bit for bit (the box tests are the same per lane and conservative, the
//! triangle tests the same), `u`, `v` and triangle of the same hit (another
//! triangle only at exactly the same `t`, a tie the traversal order
//! decides), and the same occlusion answer.

#[cfg(target_arch = "x86_64")]
mod gather;
#[cfg(target_arch = "x86_64")]
pub(crate) mod kernel;
mod spread;
#[cfg(test)]
pub(super) use spread::close_together;

use super::node4::Node4;
use super::node8::Node8;
use super::prefetch::prefetch_lines;
use super::tri4::Tri4Leaves;
use super::wide_node::Child4;
use crate::accel::{Accel, BATCH_GRAIN};
use crate::hit::Hit;
use crate::ray::Ray;
use crate::tri::{Moller, TriangleTest};
use rayon::prelude::*;

#[cfg(target_arch = "x86_64")]
use super::frustum::Frustum;
#[cfg(target_arch = "x86_64")]
use super::lanes::{L16, L8};
#[cfg(target_arch = "x86_64")]
pub(super) use kernel::{Packet, PacketHits, Width};

/// An inner node the packet traversal reads: up to [`WideNode::WIDTH`] children
/// (4 for [`Node4`], 8 for [`Node8`]), their boxes in structure-of-arrays plane
/// rows (`2·axis` minima, `2·axis + 1` maxima) and their references, unused
/// slots last.
pub trait WideNode: Copy + Sync {
    /// Child slots per node (at most 8).
    const WIDTH: usize;
    /// Whether the packet kernel bounds its packets and tests only the
    /// slots within the bounds ([`WideNode::slots_within`]); the
    /// others test every slot, unrolled.
    const BUNDLED: bool = false;
    /// Plane row `row` of the box in slot `slot`.
    fn plane(&self, row: usize, slot: usize) -> f32;
    /// The child in slot `slot`.
    fn child(&self, slot: usize) -> Child4;
    /// The slots that some ray within `f` may enter (a bit mask, see
    /// [`Frustum`]); every slot where the node is not
    /// [`WideNode::BUNDLED`].
    ///
    /// # Safety
    /// The CPU must have AVX (the packet kernels' widths all have it).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn slots_within(&self, f: &Frustum, near: [usize; 3]) -> u32 {
        let _ = (f, near);
        (1 << Self::WIDTH) - 1
    }
}

impl WideNode for Node4 {
    const WIDTH: usize = 4;
    #[inline(always)]
    fn plane(&self, row: usize, slot: usize) -> f32 {
        self.boxes.planes[row][slot]
    }
    #[inline(always)]
    fn child(&self, slot: usize) -> Child4 {
        self.child[slot]
    }
}

impl WideNode for Node8 {
    const WIDTH: usize = 8;
    // Four slots a node were too few for the bounds to pay (BENCHMARKS.md), eight
    // are not.
    const BUNDLED: bool = true;
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn slots_within(&self, f: &Frustum, near: [usize; 3]) -> u32 {
        // SAFETY: the caller's AVX.
        unsafe { f.slots8(&self.boxes.planes, near) }
    }
    #[inline(always)]
    fn plane(&self, row: usize, slot: usize) -> f32 {
        self.boxes.planes[row][slot]
    }
    #[inline(always)]
    fn child(&self, slot: usize) -> Child4 {
        self.child[slot]
    }
}

/// A wide BVH that traces coherent packets of rays (Wald et al.
/// 2001): [`super::Bvh4`] and [`super::Bvh8`] over `tri4`
/// leaves.
pub(crate) trait PacketTree: Accel + Sync {
    /// The inner node.
    type Node: WideNode;
    /// What the packet traversal reads: `None` unless the leaves are `tri4`
    /// packs and the tree holds triangles.
    fn packet_view(&self) -> Option<View<'_, Self::Node>>;
    /// Traverse the subtree `start` with one ray exactly as the tree's own
    /// single-ray traversal does from the root, from the ray's current
    /// `tfar` and nearest hit `best` (the hybrid hand-over of Benthin,
    /// Wald, Woop, Ernst, Mark 2012). Returns true for an any-hit query's
    /// hit (`ANY`).
    fn single_subtree<const ANY: bool>(
        &self,
        view: &View<'_, Self::Node>,
        start: Child4,
        ray: &Ray,
        tfar: &mut f32,
        best: &mut Option<Hit>,
    ) -> bool;
    /// Trace `rays` from the root one by one (those that formed no packet):
    /// `done(i, any, best)` receives ray `i`'s any-hit answer (`ANY`) or
    /// nearest hit, exactly the single-ray traversal's. A tree may
    /// interleave the rays ([`super::Bvh8`] steps two in turn).
    #[inline(always)]
    fn singles<const ANY: bool>(
        &self,
        rays: &[Ray],
        mut done: impl FnMut(usize, bool, Option<Hit>),
    ) {
        for (i, ray) in rays.iter().enumerate() {
            if ANY {
                done(i, self.occluded(ray), None);
            } else {
                done(i, false, self.intersect(ray));
            }
        }
    }
    /// [`Width::traverse`] with this tree's stack size.
    ///
    /// # Safety
    /// The CPU must have the width's features (see [`Width::traverse`]).
    #[cfg(target_arch = "x86_64")]
    unsafe fn traverse_packet<const ANY: bool, const L: usize, W: Width<L>>(
        &self,
        view: &View<'_, Self::Node>,
        rays: &[Ray],
        p: &Packet<L>,
        switch: u32,
        out: &mut PacketHits<L>,
    );
}

/// Active rays at or below which a packet hands its rays over to the
/// single-ray traversal (Benthin et al. 2012's hybrid), for nearest-hit
/// queries and for occlusion. With packets of eight, 2 measured best for
/// shadow rays (full dragon, AMD host); with packets of sixteen on an
/// Intel host (whole 1024² batches through `bvh8`, 1 thread), 1
/// beat 2 on primaries by 2.5–3.3% (terrain, dragon) and 0.5–1.5%
/// (scatter), and 2 stayed best for shadow rays (terrain +3–4% over 1).
pub(super) const SWITCH: [u32; 2] = [1, 2];

/// How a batch is traced: one ray at a time, or in packets of `lanes`
/// rays (8 or 16) that hand over to single rays at `switch[0]` active rays
/// for nearest hits, `switch[1]` for occlusion.
#[derive(Clone, Copy, Debug)]
pub(super) struct Mode {
    pub(super) lanes: usize,
    pub(super) switch: [u32; 2],
}

impl Mode {
    pub(super) const SINGLES: Mode = Mode {
        lanes: 0,
        switch: [0; 2],
    };
}

/// Nearest hits of `rays` through `bvh`: coherent packets together (Wald
/// et al. 2001), the rest one by one; in parallel over the rayon pool.
pub(crate) fn intersect_batch<B: PacketTree>(bvh: &B, rays: &[Ray], hits: &mut [Option<Hit>]) {
    intersect_batch_with(bvh, rays, hits, mode(bvh));
}

/// [`intersect_batch`] in the mode `mode` (the caller has checked that the
/// CPU has the packet width's features).
pub(super) fn intersect_batch_with<B: PacketTree>(
    bvh: &B,
    rays: &[Ray],
    hits: &mut [Option<Hit>],
    mode: Mode,
) {
    assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
    #[cfg(target_arch = "x86_64")]
    match mode.lanes {
        16 => return intersect_packets::<16, L16, B>(bvh, rays, hits, mode.switch[0]),
        8 => return intersect_packets::<8, L8, B>(bvh, rays, hits, mode.switch[0]),
        _ => {}
    }
    let _ = mode;
    in_groups::<false, 1, _, _>(bvh, rays, hits, |_, _| false, |h, _, best| *h = best);
}

/// [`intersect_batch_with`] in packets of `L` rays.
#[cfg(target_arch = "x86_64")]
fn intersect_packets<const L: usize, W: Width<L>, B: PacketTree>(
    bvh: &B,
    rays: &[Ray],
    hits: &mut [Option<Hit>],
    switch: u32,
) {
    in_groups::<false, L, _, _>(
        bvh,
        rays,
        hits,
        |r, h| packet_intersect::<L, W, B>(bvh, r, h, switch),
        |h, _, best| *h = best,
    );
}

/// Occlusion of `rays` through `bvh`, packets as in [`intersect_batch`].
pub(crate) fn occluded_batch<B: PacketTree>(bvh: &B, rays: &[Ray], occluded: &mut [bool]) {
    occluded_batch_with(bvh, rays, occluded, mode(bvh));
}

/// [`occluded_batch`] in the mode `mode` (see [`intersect_batch_with`]).
pub(super) fn occluded_batch_with<B: PacketTree>(
    bvh: &B,
    rays: &[Ray],
    occluded: &mut [bool],
    mode: Mode,
) {
    assert_eq!(rays.len(), occluded.len(), "one result per ray");
    #[cfg(target_arch = "x86_64")]
    match mode.lanes {
        16 => return occluded_packets::<16, L16, B>(bvh, rays, occluded, mode.switch[1]),
        8 => return occluded_packets::<8, L8, B>(bvh, rays, occluded, mode.switch[1]),
        _ => {}
    }
    let _ = mode;
    in_groups::<true, 1, _, _>(bvh, rays, occluded, |_, _| false, |o, any, _| *o = any);
}

/// [`occluded_batch_with`] in packets of `L` rays.
#[cfg(target_arch = "x86_64")]
fn occluded_packets<const L: usize, W: Width<L>, B: PacketTree>(
    bvh: &B,
    rays: &[Ray],
    occluded: &mut [bool],
    switch: u32,
) {
    in_groups::<true, L, _, _>(
        bvh,
        rays,
        occluded,
        |r, o| packet_occluded::<L, W, B>(bvh, r, o, switch),
        |o, any, _| *o = any,
    );
}

/// Cache lines that `n` consecutive values of `T` may touch (one more
/// than their size, as they need not start on a line).
const fn lines<T>(n: usize) -> usize {
    (n * std::mem::size_of::<T>()).div_ceil(64) + 1
}

/// Trace `rays` in parallel, [`BATCH_GRAIN`] rays per task: within a task
/// every `L` consecutive rays are offered to `packet` (which traces them
/// and returns true when they form a packet), and the rays of the chunks
/// that form none are then traced together by the tree's
/// [`PacketTree::singles`], their answers given to `set`.
///
/// Together, because [`super::Bvh8`]'s singles step several rays in turn
/// (`wide_bvh/walk.rs`): handed a chunk of sixteen, its walks ran dry at the
/// end of every chunk and started over (with six walks, about a third of
/// the rays traced with fewer in flight, and the walks' set-up each time;
/// BENCHMARKS.md). Over a whole task of incoherent rays, the walks
/// stay full until its last rays. Without packets (`L` = 1, `packet`
/// always false) every task goes to the singles whole.
///
/// While a chunk is traced, the next chunk's rays and answer slots are
/// requested ([`prefetch_lines`]): the batch streams through memory once,
/// and a packet's trace takes long enough that the hardware prefetcher
/// fell behind, leaving the first read of every chunk (the octant check)
/// waiting on memory. Terrain and dragon primaries went 1.03–1.07×
/// faster, the scatter's within the noise (BENCHMARKS.md).
fn in_groups<const ANY: bool, const L: usize, B: PacketTree, R: Send>(
    bvh: &B,
    rays: &[Ray],
    out: &mut [R],
    packet: impl Fn(&[Ray], &mut [R]) -> bool + Sync,
    set: impl Fn(&mut R, bool, Option<Hit>) + Sync,
) {
    rays.par_chunks(BATCH_GRAIN)
        .zip(out.par_chunks_mut(BATCH_GRAIN))
        .for_each(|(r, o)| {
            // The chunks that formed no packet, by their first ray.
            let mut left = Vec::new();
            let answers = o.as_ptr();
            for (k, (rc, oc)) in r.chunks(L).zip(o.chunks_mut(L)).enumerate() {
                if L > 1 {
                    // The next chunk's rays and answers, requested while
                    // this one is traced (past the task's end too: the
                    // next task's rays usually follow on this thread).
                    let next = (k + 1) * L;
                    prefetch_lines(r.as_ptr().wrapping_add(next) as *const u8, lines::<Ray>(L));
                    prefetch_lines(answers.wrapping_add(next) as *const u8, lines::<R>(L));
                }
                if !packet(rc, oc) {
                    left.push(k * L);
                }
            }
            if left.len() == r.len().div_ceil(L) {
                // None formed a packet (incoherent rays): no copy.
                bvh.singles::<ANY>(r, |i, any, best| set(&mut o[i], any, best));
            } else if !left.is_empty() {
                let index: Vec<usize> = left
                    .iter()
                    .flat_map(|&first| first..(first + L).min(r.len()))
                    .collect();
                let rest: Vec<Ray> = index.iter().map(|&i| r[i]).collect();
                bvh.singles::<ANY>(&rest, |i, any, best| set(&mut o[index[i]], any, best));
            }
        });
}

/// The batch mode for `bvh` on this CPU: packets need packed leaves and
/// AVX2; sixteen lanes where the CPU has AVX-512 (the features of
/// `BoxPath::Avx512`), else eight. The environment variable
/// `RAYKIT_PACKETS` (read once) chooses otherwise, for measuring the paths
/// in one binary: `0` for single rays only, `8` for packets of eight.
fn mode<B: PacketTree>(bvh: &B) -> Mode {
    if bvh.packet_view().is_none() {
        return Mode::SINGLES;
    }
    let widths = widths();
    let want = PACKETS.get_or_init(|| std::env::var("RAYKIT_PACKETS").ok());
    let lanes = match want.as_deref() {
        Some("0") => 0,
        Some("8") => widths.iter().copied().find(|&w| w == 8).unwrap_or(0),
        _ => widths.first().copied().unwrap_or(0),
    };
    Mode {
        lanes,
        switch: SWITCH,
    }
}

static PACKETS: std::sync::OnceLock<Option<String>> = std::sync::OnceLock::new();

/// The packet widths this CPU runs, widest first.
pub(super) fn widths() -> Vec<usize> {
    #[cfg(target_arch = "x86_64")]
    {
        use super::box_path::BoxPath;
        match BoxPath::detect() {
            BoxPath::Avx512 => vec![16, 8],
            BoxPath::Avx2 => vec![8],
            _ => vec![],
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        vec![]
    }
}

/// The octant of a ray: the sign bits of its reciprocal direction.
#[inline(always)]
fn octant(ray: &Ray) -> u32 {
    let id = ray.inv_dir;
    (id.x.is_sign_negative() as u32)
        | (id.y.is_sign_negative() as u32) << 1
        | (id.z.is_sign_negative() as u32) << 2
}

/// The packet of `rays` (one to `L`, all of octant `oct`); lanes past the
/// end are out of play.
#[cfg(target_arch = "x86_64")]
pub(super) fn packet<const L: usize>(rays: &[Ray], oct: u32) -> Packet<L> {
    let mut p = Packet {
        origin: [[0.0; L]; 3],
        dir: [[1.0; L]; 3],
        inv_dir: [[1.0; L]; 3],
        tnear: [0.0; L],
        tfar: [f32::NAN; L],
        scale: [0.0; L],
        near: [0, 1, 2].map(|a| 2 * a + ((oct >> a) & 1) as usize),
    };
    for (l, ray) in rays.iter().enumerate() {
        let (o, d, id) = (ray.origin, ray.dir, ray.inv_dir);
        p.origin[0][l] = o.x;
        p.origin[1][l] = o.y;
        p.origin[2][l] = o.z;
        p.dir[0][l] = d.x;
        p.dir[1][l] = d.y;
        p.dir[2][l] = d.z;
        p.inv_dir[0][l] = id.x;
        p.inv_dir[1][l] = id.y;
        p.inv_dir[2][l] = id.z;
        p.scale[l] = Moller::prepare(ray);
        p.tnear[l] = ray.tnear;
        p.tfar[l] = ray.traversal_tfar();
    }
    p
}

/// The octant shared by all of `rays`, if they share one.
#[inline(always)]
pub(super) fn coherent(rays: &[Ray]) -> Option<u32> {
    let oct = octant(&rays[0]);
    rays[1..].iter().all(|r| octant(r) == oct).then_some(oct)
}

/// The packet of `rays` (one to `L`) if they share an octant: a full
/// packet through [`gathered`], a batch's tail through [`packet`].
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn coherent_packet<const L: usize>(rays: &[Ray]) -> Option<Packet<L>> {
    if rays.len() == L && L.is_multiple_of(8) {
        // SAFETY: the caller's AVX.
        unsafe { gathered::<L>(rays) }
    } else {
        coherent(rays).map(|oct| packet::<L>(rays, oct))
    }
}

/// [`packet`] of `L` rays (a multiple of eight), moved into the rows eight
/// at a time with vector shuffles (`gather`), the octants
/// compared by the rows' sign bits and the Möller scale formed eight at a
/// time: the same packet, bit for bit (`max` of magnitudes is exact in any
/// order; a NaN direction fails every triangle test whatever its scale).
/// `None` when the rays do not share an octant.
///
/// # Safety
/// The CPU must support AVX; `rays.len() == L`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
pub(super) unsafe fn gathered<const L: usize>(rays: &[Ray]) -> Option<Packet<L>> {
    use std::arch::x86_64::*;
    let mut p = std::mem::MaybeUninit::<Packet<L>>::uninit();
    let q = p.as_mut_ptr();
    let mut signs = [0u32; 3];
    let factor = _mm256_set1_ps(crate::tri::moller::PREPARE_FACTOR);
    let magnitude = _mm256_castsi256_ps(_mm256_set1_epi32(i32::MAX));
    for h in 0..L / 8 {
        let eight: &[Ray; 8] = rays[8 * h..8 * h + 8].try_into().expect("eight rays");
        // SAFETY: the caller's AVX. The stores write eight floats at
        // offset `8·h < L` of rows of `L` floats inside `p`.
        unsafe {
            let r = gather::rows8(eight);
            macro_rules! row {
                ($x:expr) => {
                    (&raw mut $x as *mut f32).add(8 * h)
                };
            }
            for (a, sign) in signs.iter_mut().enumerate() {
                _mm256_storeu_ps(row!((*q).origin[a]), r.origin[a]);
                _mm256_storeu_ps(row!((*q).dir[a]), r.dir[a]);
                _mm256_storeu_ps(row!((*q).inv_dir[a]), r.inv_dir[a]);
                *sign |= (_mm256_movemask_ps(r.inv_dir[a]) as u32) << (8 * h);
            }
            _mm256_storeu_ps(row!((*q).tnear), r.tnear);
            // `Ray::traversal_tfar` in lanes: NaN where the origin or
            // direction is not finite (`x - x` is 0 only for finite `x`).
            let zero = _mm256_setzero_ps();
            let mut finite = _mm256_cmp_ps::<_CMP_EQ_OQ>(zero, zero);
            for x in [
                r.origin[0],
                r.origin[1],
                r.origin[2],
                r.dir[0],
                r.dir[1],
                r.dir[2],
            ] {
                let ok = _mm256_cmp_ps::<_CMP_EQ_OQ>(_mm256_sub_ps(x, x), zero);
                finite = _mm256_and_ps(finite, ok);
            }
            let tfar = _mm256_blendv_ps(_mm256_set1_ps(f32::NAN), r.tfar, finite);
            _mm256_storeu_ps(row!((*q).tfar), tfar);
            let ax = _mm256_and_ps(r.dir[0], magnitude);
            let ay = _mm256_and_ps(r.dir[1], magnitude);
            let az = _mm256_and_ps(r.dir[2], magnitude);
            let scale = _mm256_mul_ps(factor, _mm256_max_ps(_mm256_max_ps(ax, ay), az));
            _mm256_storeu_ps(row!((*q).scale), scale);
        }
    }
    let all = if L >= 32 { u32::MAX } else { (1u32 << L) - 1 };
    if signs.iter().any(|&s| s != 0 && s != all) {
        return None;
    }
    let oct = (0..3).fold(0, |o, a| o | ((signs[a] & 1) << a));
    // SAFETY: every row was written above (`L / 8` full stores each).
    unsafe {
        (*q).near = [0, 1, 2].map(|a| 2 * a + ((oct >> a) & 1) as usize);
        Some(p.assume_init())
    }
}

/// Trace `rays` (at most `L`) as one packet if coherent; false when not
/// (nothing written).
#[cfg(target_arch = "x86_64")]
fn packet_intersect<const L: usize, W: Width<L>, B: PacketTree>(
    bvh: &B,
    rays: &[Ray],
    hits: &mut [Option<Hit>],
    switch: u32,
) -> bool {
    let Some(view) = bvh.packet_view() else {
        return false;
    };
    if rays.len() == L && !spread::close_together(rays, view.extent) {
        return false;
    }
    // SAFETY: the width is one of `widths()`, whose features (AVX among
    // them) this CPU has.
    let Some(p) = (unsafe { coherent_packet::<L>(rays) }) else {
        return false;
    };
    let mut out = PacketHits::<L>::default();
    // SAFETY: as above.
    unsafe { bvh.traverse_packet::<false, L, W>(&view, rays, &p, switch, &mut out) };
    for (l, h) in hits.iter_mut().enumerate() {
        *h = (out.hit & (1 << l) != 0).then_some(Hit {
            t: out.t[l],
            u: out.u[l],
            v: out.v[l],
            prim: out.prim[l],
        });
    }
    true
}

/// As [`packet_intersect`], for occlusion.
#[cfg(target_arch = "x86_64")]
fn packet_occluded<const L: usize, W: Width<L>, B: PacketTree>(
    bvh: &B,
    rays: &[Ray],
    occluded: &mut [bool],
    switch: u32,
) -> bool {
    let Some(view) = bvh.packet_view() else {
        return false;
    };
    if rays.len() == L && !spread::close_together(rays, view.extent) {
        return false;
    }
    // SAFETY: as in `packet_intersect`.
    let Some(p) = (unsafe { coherent_packet::<L>(rays) }) else {
        return false;
    };
    let mut out = PacketHits::<L>::default();
    // SAFETY: as in `packet_intersect`.
    unsafe { bvh.traverse_packet::<true, L, W>(&view, rays, &p, switch, &mut out) };
    for (l, o) in occluded.iter_mut().enumerate() {
        *o = out.hit & (1 << l) != 0;
    }
    true
}

/// What the packet traversal reads of a wide BVH over Möller: the
/// nodes, the root and the `tri4` leaves (Wald et al. 2014).
#[derive(Clone, Copy)]
pub(crate) struct View<'a, N> {
    pub nodes: &'a [N],
    pub root: Child4,
    pub leaves: &'a Tri4Leaves,
    /// The largest side of the tree's box.
    pub extent: f32,
}
