//! Rays with a parametric interval and a precomputed reciprocal direction.

use glam::Vec3;

/// A ray `origin + t * dir` restricted to `t` in `[tnear, tfar]`.
///
/// `inv_dir` is the component-wise reciprocal of `dir`, precomputed once so that
/// slab tests against boxes (BVH and kd-tree traversal) need only multiplies.
/// A zero component gives an infinite reciprocal, which the slab tests handle.
/// The direction need not be unit length: `t` is measured in units of `dir`.
///
/// The layout is C's, fields in this order (44 bytes), so that the packet
/// path can move eight rays into its lanes with vector loads
/// (`accel/bvh/packet/gather.rs`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Ray {
    /// Start point.
    pub origin: Vec3,
    /// Direction (any non-zero length).
    pub dir: Vec3,
    /// Smallest accepted distance.
    pub tnear: f32,
    /// Largest accepted distance.
    pub tfar: f32,
    /// `1 / dir`, component-wise.
    pub inv_dir: Vec3,
}

impl Ray {
    /// A ray over `[0, +inf)`.
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self::segment(origin, dir, 0.0, f32::INFINITY)
    }

    /// A ray over `[tnear, tfar]`.
    pub fn segment(origin: Vec3, dir: Vec3, tnear: f32, tfar: f32) -> Self {
        Ray {
            origin,
            dir,
            tnear,
            tfar,
            inv_dir: Vec3::ONE / dir,
        }
    }

    /// The point at distance `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }

    /// The `tfar` a traversal starts from: the ray's own, or NaN when its
    /// origin or direction is not finite. A NaN `tfar` fails every box and
    /// triangle test, so such a ray hits nothing; without it, a NaN from
    /// its slab arithmetic is dropped by the `min`/`max` that drop `0·∞`,
    /// and it entered the inverted boxes of the wide BVHs' unused slots.
    #[inline(always)]
    pub(crate) fn traversal_tfar(&self) -> f32 {
        if self.origin.is_finite() && self.dir.is_finite() {
            self.tfar
        } else {
            f32::NAN
        }
    }

    /// True when origin, direction and interval are finite numbers (tfar may be
    /// +inf) and the direction is not zero.
    pub fn is_valid(&self) -> bool {
        self.origin.is_finite()
            && self.dir.is_finite()
            && self.dir != Vec3::ZERO
            && self.tnear.is_finite()
            && !self.tfar.is_nan()
            && self.tnear <= self.tfar
    }
}
