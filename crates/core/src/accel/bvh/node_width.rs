//! What the generic wide BVH ([`super::WideBvh`]) asks of its node type,
//! the one thing that differs between [`super::Bvh4`] and [`super::Bvh8`]:
//! the box test of all slots at once, the traversal stack a tree of that
//! width can need, and how its rays are best batched.
//!
//! The trait is public in a private module (sealed): the two node types
//! are the only ones, and its methods use the crate's kernel types.

use super::box4::Hits4;
use super::box8::Hits8;
use super::box_path::BoxPath;
use super::boxes::Hits;
use super::node4::Node4;
use super::node8::Node8;
use super::packet::WideNode as PacketNode;
use super::ray_box::RayBox;
use super::wide_node::WideSlots;
use super::wide_parts::WideNode as PartsNode;
use super::MAX_DEPTH;
use crate::accel::AccelKind;

/// The box test's answer for one node: which slots the ray entered, and
/// where.
pub trait SlotEntries {
    /// Bit `i` set when slot `i`'s box is entered within the interval.
    fn mask(&self) -> u32;
    /// Entry distance into slot `i`'s box (meaningful where the mask has
    /// bit `i`).
    fn t(&self) -> &[f32];
}

impl<const W: usize> SlotEntries for Hits<W> {
    #[inline(always)]
    fn mask(&self) -> u32 {
        self.mask
    }
    #[inline(always)]
    fn t(&self) -> &[f32] {
        &self.t
    }
}

/// A wide node type: [`Node4`] (four slots, Embree's BVH4 on SSE) or
/// [`Node8`] (eight, Embree's BVH8 on AVX; Wald et al. 2014).
pub trait NodeWidth: WideSlots + PacketNode + PartsNode + 'static {
    /// The box test's answer.
    type Hits: SlotEntries;
    /// The structure's name in the registry and in saved files.
    const KIND: AccelKind;
    /// Traversal stack entries a tree of this width may need at most
    /// (exclusive): each node visited pushes at most `WIDTH - 1`.
    const STACK: usize;
    /// Whether batches of incoherent rays (nearest hit and occlusion) are
    /// stepped in turn (`wide_bvh/walk.rs`): with eight slots a node the
    /// interleaving made nearest hits 1.2× faster and occlusion 1.6–2×;
    /// four-wide trees keep one ray after the other.
    const INTERLEAVE: bool;
    /// Test the ray `rb` against every slot's box over `[tnear, tfar]`
    /// with the kernel `path`.
    ///
    /// # Safety
    /// `path` must be one this CPU runs ([`BoxPath::detect`]'s or a slower
    /// one).
    unsafe fn entries(&self, path: BoxPath, rb: &RayBox, tnear: f32, tfar: f32) -> Self::Hits;
}

impl NodeWidth for Node4 {
    type Hits = Hits4;
    const KIND: AccelKind = AccelKind::Bvh4;
    const STACK: usize = 3 * MAX_DEPTH + 1;
    const INTERLEAVE: bool = false;
    #[inline(always)]
    unsafe fn entries(&self, path: BoxPath, rb: &RayBox, tnear: f32, tfar: f32) -> Hits4 {
        self.boxes.entries(path, rb, tnear, tfar)
    }
}

impl NodeWidth for Node8 {
    type Hits = Hits8;
    const KIND: AccelKind = AccelKind::Bvh8;
    const STACK: usize = 7 * MAX_DEPTH + 1;
    const INTERLEAVE: bool = true;
    #[inline(always)]
    unsafe fn entries(&self, path: BoxPath, rb: &RayBox, tnear: f32, tfar: f32) -> Hits8 {
        // SAFETY: the caller's `path`.
        unsafe { self.boxes.entries(path, rb, tnear, tfar) }
    }
}

/// Traversal stack entries that a tree of any width may need (the largest
/// [`NodeWidth::STACK`]): the size of the stack a deep tree's traversal
/// allocates, one size for both widths since a const generic cannot be
/// computed from a type parameter.
pub(crate) const LARGE_STACK: usize = Node8::STACK;

/// The stack of trees that need no more than this (most do; a smaller stack
/// is cheaper to set up per ray).
pub(crate) const SMALL_STACK: usize = 64;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aabb::Aabb;
    use crate::accel::bvh::wide_node::Child4;
    use crate::accel::node_box::NodeBox;
    use crate::ray::Ray;
    use crate::rng::Pcg32;
    use glam::Vec3;

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

    /// Every kernel this CPU runs gives the scalar kernel's mask and entry
    /// distances bit for bit, and the scalar kernel accepts every box the
    /// single-box test of Bvh2 ([`NodeBox::entry`]) accepts, at the same
    /// distance; random boxes (some flat) and rays (some axis-parallel,
    /// some starting on a slab plane: `0·∞`).
    fn kernels_agree_on_random_boxes_and_rays<N: NodeWidth>(seed: u64) {
        let mut rng = Pcg32::new(seed);
        let paths = BoxPath::available();
        let mut hits = 0;
        for _ in 0..100_000 {
            let mut node = N::EMPTY;
            let used = 1 + rng.below(<N as WideSlots>::WIDTH as u32) as usize;
            for s in 0..used {
                let lo = rng.in_box(Vec3::splat(-1.0), Vec3::splat(1.0));
                let size = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32())
                    * if rng.below(8) == 0 { 0.0 } else { 0.5 };
                node.set_slot(s, &Aabb::new(lo, lo + size).into(), Child4::EMPTY);
            }
            let mut origin = rng.in_box(Vec3::splat(-2.0), Vec3::splat(2.0));
            // The origin exactly on a slab plane now and then (0·∞ = NaN
            // with a zero direction component).
            if rng.below(4) == 0 {
                let a = rng.below(3) as usize;
                let b = node.slot_box(rng.below(used as u32) as usize);
                origin[a] = if rng.below(2) == 0 {
                    b.min[a]
                } else {
                    b.max[a]
                };
            }
            let target = node.slot_box(rng.below(used as u32) as usize);
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
            let r = RayBox::new(&ray);
            // SAFETY: every CPU runs the scalar kernel.
            let want = unsafe { node.entries(BoxPath::Scalar, &r, tnear, tfar) };
            assert_eq!(want.mask() >> used, 0, "an unused slot was hit: {ray:?}");
            for &path in &paths {
                // SAFETY: `path` is one this CPU runs.
                let got = unsafe { node.entries(path, &r, tnear, tfar) };
                assert_eq!(got.mask(), want.mask(), "{path:?} {ray:?}");
                for i in 0..<N as WideSlots>::WIDTH {
                    if want.mask() & (1 << i) != 0 {
                        assert_eq!(
                            got.t()[i].to_bits(),
                            want.t()[i].to_bits(),
                            "{path:?} {ray:?}"
                        );
                    }
                }
            }
            for s in 0..used {
                let b = node.slot_box(s);
                let nb = NodeBox {
                    min: b.min.to_array(),
                    max: b.max.to_array(),
                };
                let e = nb.entry(&ray, tnear, tfar);
                if e != f32::INFINITY {
                    assert!(want.mask() & (1 << s) != 0, "{ray:?} {nb:?}");
                    // Equal up to the sign of zero (`f32::max` may return
                    // either zero).
                    assert_eq!(want.t()[s], e, "{ray:?} {nb:?}");
                    hits += 1;
                }
            }
        }
        assert!(hits > 10_000, "too few hits to be a test: {hits}");
    }

    #[test]
    fn kernels_agree_on_random_boxes_and_rays_4() {
        kernels_agree_on_random_boxes_and_rays::<Node4>(8);
    }

    #[test]
    fn kernels_agree_on_random_boxes_and_rays_8() {
        kernels_agree_on_random_boxes_and_rays::<Node8>(88);
    }
}
