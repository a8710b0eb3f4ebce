//! The compressed wide BVH of Ylitie, Karras and Laine (2017, "Efficient
//! incoherent ray traversal on GPUs through compressed wide BVHs"), made
//! from raykit's own 8-wide BVH ([`raykit_core::accel::Bvh8`], handed over
//! as [`FlatBvh8`]) and traversed by `shaders/cwbvh.wgsl`.
//!
//! A node is 80 bytes (20 words):
//!
//! | words | content |
//! |---|---|
//! | 0-2 | origin `p`: the lower corner of the union of the children's boxes |
//! | 3 | biased exponents `e_x`, `e_y`, `e_z` (bytes 0-2; scale `2^(e-127)`), `imask` (byte 3: slots holding inner nodes) |
//! | 4 | index of the first inner child (inner children are consecutive, in slot order) |
//! | 5 | index of the first triangle record (leaf triangles are consecutive, in slot order) |
//! | 6-7 | `meta` per slot (byte `s` of the 8): 0 unused; inner `0b001_11sss` (24 + slot); leaf: the count in unary in the top 3 bits, the first triangle's offset from word 5 in the low 5 |
//! | 8-19 | quantized child boxes, one byte per slot: `lo_x`, `lo_y`, `lo_z`, `hi_x`, `hi_y`, `hi_z` (two words of eight bytes each) |
//!
//! A child's box decodes as `p + q · 2^e` in `f32` (one rounding: `q · 2^e`
//! is exact), and the quantization rounds outward against exactly that
//! decoding, so every decoded box contains the child's padded box and the
//! kernel, testing the decoded box as the CPU tests the exact one, can
//! never lose a hit the CPU finds; it may enter a few more boxes.
//!
//! Children are put in slots by the paper's greedy octant assignment: slot
//! `s` takes the child whose centre lies furthest back along the
//! direction of ray octant `s`, so the kernel visits children in order of
//! `slot XOR octant` and reaches the near ones first without sorting.
//!
//! The paper's leaves hold at most three triangles (the unary count), so
//! the tree is built with leaves of at most [`MAX_LEAF`] triangles
//! ([`cwbvh_build_options`]).

use crate::error::{GpuError, GpuResult};
use raykit_core::accel::{BuildOptions, FlatBvh8, FlatChild, FlatNode8};

/// Words per node.
pub const NODE_WORDS: usize = 20;

/// Most triangles per leaf (three unary bits of `meta`).
pub const MAX_LEAF: usize = 3;

/// Most node groups on the kernel's per-thread stack (`CW_STACK` in
/// `shaders/cwbvh.wgsl`): one per level below the root, so trees up to
/// this depth are traversed.
pub const MAX_DEPTH: usize = 32;

/// The build options of the 8-wide BVH the compressed tree is made from:
/// the caller's, with leaves of at most [`MAX_LEAF`] triangles.
pub fn cwbvh_build_options(options: &BuildOptions) -> BuildOptions {
    BuildOptions {
        max_leaf_size: options.max_leaf_size.min(MAX_LEAF),
        packed_leaf_size: options.packed_leaf_size.min(MAX_LEAF),
        ..options.clone()
    }
}

/// A compressed wide BVH ready for upload.
#[derive(Clone, Debug)]
pub struct Cwbvh {
    /// [`NODE_WORDS`] words per node, the root first.
    pub nodes: Vec<u32>,
    /// Mesh triangle index of each triangle record, in the kernel's order.
    pub prims: Vec<u32>,
    /// Levels of nodes (1 for a root alone).
    pub depth: usize,
}

impl Cwbvh {
    /// Nodes.
    pub fn len(&self) -> usize {
        self.nodes.len() / NODE_WORDS
    }

    /// True for a tree without triangles.
    pub fn is_empty(&self) -> bool {
        self.prims.is_empty()
    }
}

/// A child box quantized to 8 bits per plane against a node's origin and
/// exponents, rounded outward so that [`decode`] contains `(lo, hi)`.
fn quantize(p: [f32; 3], e: [u8; 3], lo: [f32; 3], hi: [f32; 3]) -> Option<([u8; 3], [u8; 3])> {
    let mut ql = [0u8; 3];
    let mut qh = [0u8; 3];
    for a in 0..3 {
        let s = scale(e[a]);
        let mut l = (((lo[a] as f64) - (p[a] as f64)) / s as f64)
            .floor()
            .max(0.0) as i32;
        while l > 0 && p[a] + l as f32 * s > lo[a] {
            l -= 1;
        }
        let mut h = (((hi[a] as f64) - (p[a] as f64)) / s as f64)
            .ceil()
            .clamp(0.0, 255.0) as i32;
        while h <= 255 && p[a] + h as f32 * s < hi[a] {
            h += 1;
        }
        if h > 255 || p[a] + l as f32 * s > lo[a] {
            return None;
        }
        ql[a] = l as u8;
        qh[a] = h as u8;
    }
    Some((ql, qh))
}

/// The scale `2^(e - 127)` of a biased exponent byte (1..=254).
fn scale(e: u8) -> f32 {
    f32::from_bits((e as u32) << 23)
}

/// The box a slot decodes to, in `f32`, as the kernel computes it.
pub fn decode(node: &[u32], slot: usize) -> ([f32; 3], [f32; 3]) {
    let p = [0, 1, 2].map(|a| f32::from_bits(node[a]));
    let byte = |w: usize| ((node[w + slot / 4] >> (8 * (slot % 4))) & 0xff) as f32;
    let e = [0, 1, 2].map(|a| scale(((node[3] >> (8 * a)) & 0xff) as u8));
    let lo = [0, 1, 2].map(|a| p[a] + byte(8 + 2 * a) * e[a]);
    let hi = [0, 1, 2].map(|a| p[a] + byte(14 + 2 * a) * e[a]);
    (lo, hi)
}

/// The smallest biased exponent for which every child box on axis `a`
/// quantizes within 0..=255.
fn exponent(p: [f32; 3], a: usize, boxes: &[([f32; 3], [f32; 3])]) -> GpuResult<u8> {
    let top = boxes
        .iter()
        .map(|b| b.1[a] as f64 - p[a] as f64)
        .fold(0.0f64, f64::max);
    // 2^(e-127) · 255 >= top, then upwards until the rounded decoding fits.
    let start = if top > 0.0 {
        ((top / 255.0).log2().floor() as i32 + 127).clamp(1, 254)
    } else {
        1
    };
    for e in start..=254 {
        let e = e as u8;
        let mut es = [e; 3];
        es[a] = e;
        if boxes.iter().all(|&(lo, hi)| {
            let mut l = lo;
            let mut h = hi;
            // Test this axis alone: the others copy the origin.
            for b in 0..3 {
                if b != a {
                    l[b] = p[b];
                    h[b] = p[b];
                }
            }
            quantize(p, es, l, h).is_some()
        }) {
            return Ok(e);
        }
    }
    Err(GpuError::Unsupported(format!(
        "a node box of extent {top} on axis {a} from {}: beyond f32 exponents",
        p[a]
    )))
}

/// The greedy octant assignment of Ylitie et al. (2017), section 3.1:
/// `slots[s]` is the child (index into `kids`) put in slot `s`. The cost of
/// child `c` in slot `s` is the dot product of the child's centre, relative
/// to the node's, with the direction of octant `s` (bit `k` of `s` set:
/// negative along axis `k`); the cheapest pair is taken first.
fn assign_slots(kids: &[([f32; 3], [f32; 3])]) -> [Option<usize>; 8] {
    let centre = |b: &([f32; 3], [f32; 3])| [0, 1, 2].map(|a| 0.5 * (b.0[a] + b.1[a]));
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for b in kids {
        for a in 0..3 {
            lo[a] = lo[a].min(b.0[a]);
            hi[a] = hi[a].max(b.1[a]);
        }
    }
    let node = centre(&(lo, hi));
    let mut cost = [[0.0f32; 8]; 8];
    for (c, b) in kids.iter().enumerate() {
        let m = centre(b);
        for (s, row) in cost[c].iter_mut().enumerate().take(8) {
            *row = (0..3)
                .map(|a| {
                    let sign = if s >> a & 1 == 1 { -1.0 } else { 1.0 };
                    (m[a] - node[a]) * sign
                })
                .sum();
        }
    }
    let mut slots = [None; 8];
    let mut placed = [false; 8];
    for _ in 0..kids.len() {
        let mut best: Option<(f32, usize, usize)> = None;
        for (c, row) in cost.iter().enumerate().take(kids.len()) {
            if placed[c] {
                continue;
            }
            for (s, &k) in row.iter().enumerate() {
                if slots[s].is_none() && best.is_none_or(|b| k < b.0) {
                    best = Some((k, c, s));
                }
            }
        }
        let (_, c, s) = best.expect("a free slot for each child");
        slots[s] = Some(c);
        placed[c] = true;
    }
    slots
}

/// Compress `tree`: nodes in breadth-first order of their parents (so each
/// node's inner children are consecutive), triangles in node order.
pub fn compress(tree: &FlatBvh8) -> GpuResult<Cwbvh> {
    let root = match tree.root {
        FlatChild::Empty => {
            return Ok(Cwbvh {
                nodes: Vec::new(),
                prims: Vec::new(),
                depth: 0,
            })
        }
        FlatChild::Inner(i) => tree.nodes[i as usize],
        leaf @ FlatChild::Leaf { .. } => {
            // A root leaf becomes the only child of a root node.
            let mut n = FlatNode8 {
                min: [[f32::INFINITY; 3]; 8],
                max: [[f32::NEG_INFINITY; 3]; 8],
                child: [FlatChild::Empty; 8],
            };
            n.min[0] = tree.root_box.0;
            n.max[0] = tree.root_box.1;
            n.child[0] = leaf;
            n
        }
    };
    let mut nodes = vec![0u32; NODE_WORDS];
    let mut prims = Vec::with_capacity(tree.prims.len());
    // (source node, its index in `nodes`, its level)
    let mut queue = std::collections::VecDeque::from([(root, 0usize, 1usize)]);
    let mut depth = 0;
    while let Some((n, at, level)) = queue.pop_front() {
        depth = depth.max(level);
        let kids: Vec<usize> = (0..8).filter(|&s| n.child[s] != FlatChild::Empty).collect();
        let boxes: Vec<([f32; 3], [f32; 3])> = kids.iter().map(|&s| (n.min[s], n.max[s])).collect();
        let mut p = [f32::INFINITY; 3];
        for b in &boxes {
            for (a, pa) in p.iter_mut().enumerate() {
                *pa = pa.min(b.0[a]);
            }
        }
        let e = [
            exponent(p, 0, &boxes)?,
            exponent(p, 1, &boxes)?,
            exponent(p, 2, &boxes)?,
        ];
        let slots = assign_slots(&boxes);
        let child_base = nodes.len() / NODE_WORDS;
        let tri_base = prims.len();
        let mut w = [0u32; NODE_WORDS];
        w[0..3].copy_from_slice(&p.map(f32::to_bits));
        w[4] = child_base as u32;
        w[5] = tri_base as u32;
        let mut imask = 0u32;
        let mut inner = 0;
        for (s, k) in slots.iter().enumerate() {
            let Some(k) = *k else { continue };
            let (lo, hi) = boxes[k];
            let (ql, qh) = quantize(p, e, lo, hi).ok_or_else(|| {
                GpuError::Unsupported(format!("a child box {lo:?}..{hi:?} that does not quantize"))
            })?;
            for a in 0..3 {
                w[8 + 2 * a + s / 4] |= (ql[a] as u32) << (8 * (s % 4));
                w[14 + 2 * a + s / 4] |= (qh[a] as u32) << (8 * (s % 4));
            }
            let meta = match n.child[kids[k]] {
                FlatChild::Inner(i) => {
                    imask |= 1 << s;
                    let idx = child_base + inner;
                    inner += 1;
                    queue.push_back((tree.nodes[i as usize], idx, level + 1));
                    0b001_00000 | (24 + s as u32)
                }
                FlatChild::Leaf { first, count } => {
                    let count = count as usize;
                    let offset = prims.len() - tri_base;
                    if count == 0 || count > MAX_LEAF || offset + count > 24 {
                        return Err(GpuError::Unsupported(format!(
                            "a leaf of {count} triangles at offset {offset} of its node \
                             (the compressed wide BVH holds at most {MAX_LEAF} per leaf, 24 per node)"
                        )));
                    }
                    prims.extend_from_slice(&tree.prims[first as usize..first as usize + count]);
                    (((1u32 << count) - 1) << 5) | offset as u32
                }
                FlatChild::Empty => unreachable!("empty slots are skipped"),
            };
            w[6 + s / 4] |= meta << (8 * (s % 4));
        }
        w[3] = e[0] as u32 | (e[1] as u32) << 8 | (e[2] as u32) << 16 | imask << 24;
        nodes[at * NODE_WORDS..(at + 1) * NODE_WORDS].copy_from_slice(&w);
        nodes.resize(nodes.len() + inner * NODE_WORDS, 0);
    }
    if depth > MAX_DEPTH {
        return Err(GpuError::Unsupported(format!(
            "a compressed wide BVH {depth} levels deep (the kernel's stack holds {MAX_DEPTH})"
        )));
    }
    Ok(Cwbvh {
        nodes,
        prims,
        depth,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use raykit_core::accel::Bvh8;
    use raykit_core::tri::{Moller, Plucker, TriangleTest};
    use raykit_core::TriangleMesh;

    /// A triangle soup over several orders of magnitude of size and
    /// position, so that exponents and roundings vary.
    fn soup(n: usize, seed: u32, scale: f32, offset: f32) -> TriangleMesh {
        let mut s = seed | 1;
        let mut r = move || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s as f32 / u32::MAX as f32
        };
        let mut v = Vec::new();
        for i in 0..n {
            let size = scale * 10f32.powi(-((i % 5) as i32));
            let c = Vec3::new(r(), r(), r()) * scale + Vec3::splat(offset);
            for _ in 0..3 {
                v.push(c + (Vec3::new(r(), r(), r()) - 0.5) * size);
            }
        }
        let idx = (0..n as u32)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect();
        TriangleMesh::new(v, idx)
    }

    /// The smallest mesh triangle index under a flat child: it names the
    /// child, since each triangle lies in one leaf.
    fn flat_min(f: &FlatBvh8, c: FlatChild) -> u32 {
        match c {
            FlatChild::Empty => u32::MAX,
            FlatChild::Leaf { first, count } => f.prims[first as usize..(first + count) as usize]
                .iter()
                .copied()
                .min()
                .unwrap(),
            FlatChild::Inner(i) => f.nodes[i as usize]
                .child
                .iter()
                .map(|&k| flat_min(f, k))
                .min()
                .unwrap(),
        }
    }

    /// The compressed child in slot `s` of node `at`: its node index when
    /// inner, and the smallest mesh triangle index under it.
    fn cw_slot(cw: &Cwbvh, at: usize, s: usize) -> (Option<usize>, u32) {
        let w = &cw.nodes[at * NODE_WORDS..(at + 1) * NODE_WORDS];
        let meta = (w[6 + s / 4] >> (8 * (s % 4))) & 0xff;
        let imask = w[3] >> 24;
        if imask >> s & 1 == 1 {
            let child = w[4] as usize + (imask & ((1 << s) - 1)).count_ones() as usize;
            let m = (0..8)
                .filter(|&k| {
                    (cw.nodes[child * NODE_WORDS + 6 + k / 4] >> (8 * (k % 4))) & 0xff != 0
                })
                .map(|k| cw_slot(cw, child, k).1)
                .min()
                .unwrap();
            (Some(child), m)
        } else {
            let first = w[5] as usize + (meta & 31) as usize;
            let count = (meta >> 5).count_ones() as usize;
            (
                None,
                cw.prims[first..first + count]
                    .iter()
                    .copied()
                    .min()
                    .unwrap(),
            )
        }
    }

    /// Walk the compressed tree beside the 8-wide BVH it came from: every
    /// slot holds one of the source node's children, whose exact (padded)
    /// box its decoded box contains; each triangle is held once, but those
    /// that packed leaves leave out because no ray can hit them (stored
    /// edges with a zero cross product, computed here in `f64`), held by
    /// neither.
    fn check<T: TriangleTest>(mesh: &TriangleMesh) {
        let bvh = Bvh8::<T>::build(mesh, &cwbvh_build_options(&BuildOptions::default()));
        let flat = bvh.flat();
        let cw = compress(&flat).unwrap();
        let mut seen = vec![0u32; mesh.num_triangles()];
        for &p in &cw.prims {
            seen[p as usize] += 1;
        }
        let held = |i: usize| {
            let [a, b, c] = mesh.triangle(i).map(|v| v.as_dvec3());
            let (e1, e2) = ((b - a).as_vec3(), (c - a).as_vec3());
            let parallel = e1.as_dvec3().cross(e2.as_dvec3()) == glam::DVec3::ZERO;
            u32::from(!(T::PACKS_OF_FOUR && parallel))
        };
        assert!((0..seen.len()).all(|i| seen[i] == held(i)));
        let root = match flat.root {
            FlatChild::Inner(i) => flat.nodes[i as usize],
            _ => return, // a root leaf: checked by the GPU agreement tests
        };
        let mut todo = vec![(0usize, root)];
        let mut slots = 0;
        while let Some((at, n)) = todo.pop() {
            let w = &cw.nodes[at * NODE_WORDS..(at + 1) * NODE_WORDS];
            let used: Vec<usize> = (0..8)
                .filter(|&s| (w[6 + s / 4] >> (8 * (s % 4))) & 0xff != 0)
                .collect();
            let kids = n.child.iter().filter(|&&c| c != FlatChild::Empty).count();
            assert_eq!(used.len(), kids, "one slot per child");
            for s in used {
                let (inner, m) = cw_slot(&cw, at, s);
                let k = (0..8).find(|&k| flat_min(&flat, n.child[k]) == m).unwrap();
                let (lo, hi) = decode(w, s);
                for a in 0..3 {
                    assert!(
                        lo[a] <= n.min[k][a] && hi[a] >= n.max[k][a],
                        "slot {s} axis {a}: decoded {lo:?}..{hi:?} misses the exact {:?}..{:?}",
                        n.min[k],
                        n.max[k]
                    );
                }
                slots += 1;
                match (inner, n.child[k]) {
                    (Some(c), FlatChild::Inner(i)) => todo.push((c, flat.nodes[i as usize])),
                    (None, FlatChild::Leaf { .. }) => {}
                    other => panic!("slot {s} of node {at}: kinds differ {other:?}"),
                }
            }
        }
        assert_eq!(slots + 1, cw.len() + flat_leaves(&flat));
    }

    fn flat_leaves(f: &FlatBvh8) -> usize {
        f.nodes
            .iter()
            .flat_map(|n| n.child)
            .filter(|c| matches!(c, FlatChild::Leaf { .. }))
            .count()
    }

    #[test]
    fn every_quantized_child_box_contains_its_exact_box() {
        for (seed, scale, offset) in [(1, 10.0, 0.0), (7, 1e-3, 5e3), (9, 1e4, -3e4)] {
            let mesh = soup(4000, seed, scale, offset);
            check::<Plucker>(&mesh);
            check::<Moller>(&mesh);
        }
        // One triangle: the root is a leaf.
        check::<Plucker>(&soup(1, 3, 1.0, 0.0));
    }
}
