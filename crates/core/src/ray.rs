//! Rays with a parametric interval and a precomputed reciprocal direction.

use glam::Vec3;

/// The unit vector along `d`, also for a `d` so short or so long that
/// `|d|²` underflows or overflows (models nanometres or 10¹⁹ across): such
/// a `d` is first brought to a largest component of 1. Not finite for a
/// zero `d`.
pub fn unit_direction(d: Vec3) -> Vec3 {
    let squared = d.length_squared();
    if (f32::MIN_POSITIVE..=f32::MAX).contains(&squared) {
        d.normalize()
    } else {
        (d / d.abs().max_element()).normalize()
    }
}

/// A ray `origin + t * dir` restricted to `t` in `[tnear, tfar]`.
///
/// The ray keeps the component-wise reciprocal of its direction, computed
/// once so that slab tests against boxes (BVH and kd-tree traversal) need
/// only multiplies. A zero component gives an infinite reciprocal, which the
/// slab tests handle. The direction need not be unit length: `t` is measured
/// in units of `dir`. Direction and reciprocal are private and change only
/// together ([`Ray::set_dir`]), so the reciprocal cannot go stale; origin
/// and interval are plain fields.
///
/// The layout is C's, fields in this order (44 bytes), so that the packet
/// path can move eight rays into its lanes with vector loads
/// (`accel/bvh/packet/gather.rs`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Ray {
    /// Start point.
    pub origin: Vec3,
    /// Direction (any non-zero length); read with [`Ray::dir`].
    pub(crate) dir: Vec3,
    /// Smallest accepted distance.
    pub tnear: f32,
    /// Largest accepted distance.
    pub tfar: f32,
    /// `1 / dir`, component-wise; read with [`Ray::inv_dir`].
    pub(crate) inv_dir: Vec3,
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

    /// The direction.
    #[inline(always)]
    pub fn dir(&self) -> Vec3 {
        self.dir
    }

    /// The component-wise reciprocal of the direction.
    #[inline(always)]
    pub fn inv_dir(&self) -> Vec3 {
        self.inv_dir
    }

    /// Change the direction, and its reciprocal with it.
    #[inline]
    pub fn set_dir(&mut self, dir: Vec3) {
        self.dir = dir;
        self.inv_dir = Vec3::ONE / dir;
    }

    /// `[origin, dir, tnear, tfar]` as eight floats: the 32-byte record
    /// of ray files and of the GPU's ray buffers.
    pub fn to_array(&self) -> [f32; 8] {
        let (o, d) = (self.origin, self.dir);
        [o.x, o.y, o.z, d.x, d.y, d.z, self.tnear, self.tfar]
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

    /// True when origin and direction are finite, the direction is not zero,
    /// and the interval is a non-empty range of numbers (tnear may be -inf,
    /// the whole line behind the origin, and tfar +inf).
    pub fn is_valid(&self) -> bool {
        self.origin.is_finite()
            && self.dir.is_finite()
            && self.dir != Vec3::ZERO
            && self.tnear < f32::INFINITY
            && !self.tfar.is_nan()
            && self.tnear <= self.tfar
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_dir_keeps_the_reciprocal_with_the_direction() {
        let mut ray = Ray::segment(Vec3::ZERO, Vec3::new(1.0, 2.0, 4.0), 0.5, 9.0);
        ray.set_dir(Vec3::new(-0.25, 0.0, 8.0));
        assert_eq!(ray.dir(), Vec3::new(-0.25, 0.0, 8.0));
        // Each component against an f64 division of the new direction.
        let want = [1.0 / -0.25f64, f64::INFINITY, 1.0 / 8.0];
        for (got, want) in ray.inv_dir().to_array().into_iter().zip(want) {
            assert_eq!(got as f64, want);
        }
        assert_eq!((ray.tnear, ray.tfar), (0.5, 9.0));
    }
}
