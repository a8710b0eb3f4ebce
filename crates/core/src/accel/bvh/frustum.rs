//! A packet's rays bounded as one bundle, to skip the children of a node that
//! no ray of the packet can enter before testing them ray by ray (the
//! interval-arithmetic culling of Wald, Boulos and Shirley 2007, "Ray tracing
//! deformable scenes using dynamic bounding volume hierarchies", and of
//! Embree's coherent packet kernels).
//!
//! Per axis the packet's origins lie in `[o_min, o_max]` and its
//! reciprocal directions in `[i_min, i_max]` (all of one sign: a packet's
//! rays share an octant). A lane's entry distance through a plane `p` is
//! `fl(fl(p - o) · i)`; rounding is monotone, so the interval bounds of
//! `(p - o) · i`, formed from the extremes with the same two operations,
//! bound every lane's value as computed (the smallest for the entry
//! planes, the largest for the exit planes). A slot where the smallest
//! entry any lane can have lies beyond the largest exit any lane can have
//! (widened as the lanes widen it, capped by the largest `tfar`) is
//! entered by no lane, and its ray-by-ray test would return an empty
//! mask: skipping it changes nothing but the work.
//!
//! Bounds are only formed where every reciprocal direction in play is
//! finite and non-zero: then no product is NaN (an unused slot's infinite
//! planes give infinite bounds and are skipped too). Otherwise every slot
//! is tested.

use super::lanes::Lanes;
use crate::accel::node_box::NodeBox;

/// The bounds of a packet's rays in play (see the module notes).
#[derive(Clone, Copy, Debug)]
pub struct Frustum {
    /// Per axis, the origin extreme that gives the smallest entry through
    /// the near plane: the largest origin where the direction is positive,
    /// the smallest where it is negative.
    pub(crate) o_near: [f32; 3],
    /// Per axis, the origin extreme that gives the largest exit through
    /// the far plane.
    pub(crate) o_far: [f32; 3],
    /// Per axis, the smallest and largest reciprocal direction.
    pub(crate) inv_min: [f32; 3],
    pub(crate) inv_max: [f32; 3],
    /// The smallest `tnear` and the largest `tfar` of the lanes in play.
    pub(crate) tnear: f32,
    pub(crate) tfar: f32,
    /// False when the bounds could not be formed (every slot is tested).
    pub(crate) usable: bool,
}

impl Frustum {
    /// The bounds of the lanes in `act` of rows `o` (origins), `inv`
    /// (reciprocal directions), `tnear` and `tfar`, whose near planes per
    /// axis are `near` (rows of [`super::box4::Box4::planes`]: even for a
    /// positive direction).
    #[inline(always)]
    pub(crate) fn of<const L: usize, V: Lanes<L>>(
        o: &[V; 3],
        inv: &[V; 3],
        tnear: V,
        tfar: V,
        act: V::Mask,
        near: [usize; 3],
    ) -> Frustum {
        let inf = V::splat(f32::INFINITY);
        let ninf = V::splat(f32::NEG_INFINITY);
        // Extremes over the lanes in play (the others read as ±infinity).
        let lo = |x: V| inf.blend(x, act).hmin();
        let hi = |x: V| -(ninf.blend(x, act).neg().hmin());
        let mut f = Frustum {
            o_near: [0.0; 3],
            o_far: [0.0; 3],
            inv_min: [0.0; 3],
            inv_max: [0.0; 3],
            tnear: lo(tnear),
            tfar: hi(tfar),
            usable: V::bits(act) != 0,
        };
        for a in 0..3 {
            let (omin, omax) = (lo(o[a]), hi(o[a]));
            let (imin, imax) = (lo(inv[a]), hi(inv[a]));
            let positive = near[a] & 1 == 0;
            (f.o_near[a], f.o_far[a]) = if positive { (omax, omin) } else { (omin, omax) };
            (f.inv_min[a], f.inv_max[a]) = (imin, imax);
            // One sign, finite, non-zero: no product below is NaN.
            let one_sign = if positive { imin > 0.0 } else { imax < 0.0 };
            f.usable &= one_sign && imin.is_finite() && imax.is_finite();
            f.usable &= omin.is_finite() && omax.is_finite();
        }
        f.usable &= f.tnear.is_finite() && !f.tfar.is_nan();
        f
    }

    /// The slots of `planes` (eight boxes in plane rows, unused slots
    /// inverted) that some lane may enter, as a bit mask; all eight where
    /// the bounds are not usable.
    ///
    /// # Safety
    /// The CPU must have AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    #[inline]
    pub(crate) unsafe fn slots8(&self, planes: &[[f32; 8]; 6], near: [usize; 3]) -> u32 {
        use std::arch::x86_64::*;
        if !self.usable {
            return 0xff;
        }
        let s = _mm256_set1_ps;
        let mut enter = s(self.tnear);
        let mut exit = s(f32::INFINITY);
        for (a, &n) in near.iter().enumerate() {
            let pn = _mm256_loadu_ps(planes[n].as_ptr());
            let pf = _mm256_loadu_ps(planes[n ^ 1].as_ptr());
            let (imin, imax) = (s(self.inv_min[a]), s(self.inv_max[a]));
            let xn = _mm256_sub_ps(pn, s(self.o_near[a]));
            let xf = _mm256_sub_ps(pf, s(self.o_far[a]));
            let tn = _mm256_min_ps(_mm256_mul_ps(xn, imin), _mm256_mul_ps(xn, imax));
            let tf = _mm256_max_ps(_mm256_mul_ps(xf, imin), _mm256_mul_ps(xf, imax));
            enter = _mm256_max_ps(enter, tn);
            exit = _mm256_min_ps(exit, tf);
        }
        let exit = _mm256_min_ps(_mm256_mul_ps(exit, s(NodeBox::ROBUST_EXIT)), s(self.tfar));
        _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(enter, exit)) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::box8::Box8;
    use crate::accel::bvh::lanes::L8;
    use crate::accel::bvh::ray_box::RayBox;
    use crate::ray::Ray;
    use crate::rng::Pcg32;
    use glam::Vec3;

    /// Eight rays of one octant towards `target`: a shared origin (camera) or origins
    /// spread over a patch (shadow rays), directions around a common one,
    /// some components tiny, some rays bounded, some lanes out of play.
    fn packet(rng: &mut Pcg32, target: Vec3) -> (Vec<Ray>, u32) {
        let shared = rng.below(2) == 0;
        let centre = rng.in_box(Vec3::splat(-4.0), Vec3::splat(4.0));
        // Towards `target`, in the octant of that direction.
        let base = target - centre;
        let sign = Vec3::select(base.cmplt(Vec3::ZERO), Vec3::splat(-1.0), Vec3::ONE);
        let base = base.abs() + Vec3::splat(1e-3);
        let spread = [0.0, 1e-3, 0.05, 0.5][rng.below(4) as usize];
        let rays = (0..8)
            .map(|_| {
                let o = if shared {
                    centre
                } else {
                    centre + rng.in_box(Vec3::splat(-spread), Vec3::splat(spread))
                };
                let mut d = base + rng.in_box(Vec3::ZERO, Vec3::splat(spread));
                if rng.below(8) == 0 {
                    d.x = 1e-7 * rng.next_f32() + 1e-30;
                }
                let d = d * sign;
                if rng.below(3) == 0 {
                    Ray::segment(o, d, rng.range_f32(0.0, 0.5), rng.range_f32(0.5, 4.0))
                } else {
                    Ray::new(o, d)
                }
            })
            .collect();
        let act = if rng.below(4) == 0 {
            rng.next_u32() & 0xff
        } else {
            0xff
        };
        (rays, act)
    }

    /// Eight random boxes near the origin, some slots unused, some flat.
    fn node(rng: &mut Pcg32) -> Box8 {
        let mut b = Box8::EMPTY;
        for s in 0..8 {
            if rng.below(5) == 0 {
                continue;
            }
            let lo = rng.in_box(Vec3::splat(-2.5), Vec3::splat(2.5));
            let mut size = rng.in_box(Vec3::ZERO, Vec3::splat(1.0));
            if rng.below(6) == 0 {
                size.y = 0.0;
            }
            for a in 0..3 {
                b.planes[2 * a][s] = lo[a];
                b.planes[2 * a + 1][s] = lo[a] + size[a];
            }
        }
        b
    }

    /// Every slot that some ray in play enters by the single-ray box test
    /// (whose arithmetic the packet kernel's test repeats lane by lane) is
    /// among the bundle's slots, over 50 000 random packets and nodes; and
    /// the bundle does skip slots (so the test would notice bounds that
    /// were never usable).
    #[test]
    fn bundle_keeps_every_slot_a_ray_enters() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("note: no AVX2 on this CPU: the packet bundle test is skipped");
            return;
        }
        let mut rng = Pcg32::new(2007);
        let (mut skipped, mut entered) = (0usize, 0usize);
        for _ in 0..50_000 {
            let b = node(&mut rng);
            let s = rng.below(8) as usize;
            let target = Vec3::new(b.planes[0][s], b.planes[2][s], b.planes[4][s]);
            let (rays, act) = packet(&mut rng, target.clamp(Vec3::splat(-3.0), Vec3::splat(3.0)));
            let near = [0, 1, 2].map(|a| 2 * a + (rays[0].dir[a] < 0.0) as usize);
            let row =
                |f: &dyn Fn(&Ray) -> f32| -> [f32; 8] { std::array::from_fn(|l| f(&rays[l])) };
            let tfar: [f32; 8] = std::array::from_fn(|l| {
                if act & (1 << l) != 0 {
                    rays[l].traversal_tfar()
                } else {
                    f32::NAN
                }
            });
            let o = [0, 1, 2].map(|a| L8::load(&row(&|r| r.origin[a])));
            let inv = [0, 1, 2].map(|a| L8::load(&row(&|r| r.inv_dir[a])));
            let tfar_v = L8::load(&tfar);
            let bundle = Frustum::of::<8, L8>(
                &o,
                &inv,
                L8::load(&row(&|r| r.tnear)),
                tfar_v,
                tfar_v.ordered(),
                near,
            );
            // SAFETY: the CPU has AVX2.
            let maybe = unsafe { bundle.slots8(&b.planes, near) };
            let mut want = 0u32;
            for (l, ray) in rays.iter().enumerate() {
                if act & (1 << l) != 0 {
                    want |= b.entries_scalar(&RayBox::new(ray), ray.tnear, tfar[l]).mask;
                }
            }
            assert_eq!(
                want & !maybe,
                0,
                "slots entered but skipped: {rays:?} act {act:#x} {b:?}"
            );
            skipped += (0xff & !maybe).count_ones() as usize;
            entered += want.count_ones() as usize;
        }
        assert!(entered > 20_000, "too few entered slots to test: {entered}");
        assert!(
            skipped > 200_000,
            "the bundle skipped too few slots: {skipped}"
        );
    }
}
