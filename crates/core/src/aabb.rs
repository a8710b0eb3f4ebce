//! Axis-aligned bounding boxes.

use crate::ray::Ray;
use glam::Vec3;

/// An axis-aligned box `[min, max]`. The empty box has `min = +inf`,
/// `max = -inf`, so that growing it by a point gives that point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box (contains nothing; the identity of `union`).
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The box with the given corners.
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Aabb { min, max }
    }

    /// The smallest box holding every point.
    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a Vec3>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.grow(*p))
    }

    /// True when the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// This box grown to contain `p`.
    #[inline]
    pub fn grow(self, p: Vec3) -> Self {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// The smallest box containing both.
    #[inline]
    pub fn union(self, other: Aabb) -> Self {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// The overlap of both boxes (possibly empty).
    pub fn intersection(self, other: Aabb) -> Self {
        Aabb {
            min: self.min.max(other.min),
            max: self.max.min(other.max),
        }
    }

    /// `max - min` (negative components for the empty box).
    #[inline]
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// The centre point.
    #[inline]
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// The eight corners; corner `i` takes `max` on x when bit 0 of `i` is
    /// set, on y for bit 1 and on z for bit 2.
    pub fn corners(&self) -> [Vec3; 8] {
        std::array::from_fn(|i| {
            Vec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            )
        })
    }

    /// Length of the diagonal (0 for the empty box). Where the squares of
    /// the sides underflow (a box under about 10⁻¹⁹ across) or overflow,
    /// they are summed in `f64`.
    pub fn diagonal(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        let d = e.length();
        if (d > 0.0 && d.is_finite()) || e == Vec3::ZERO {
            d
        } else {
            e.as_dvec3().length() as f32
        }
    }

    /// The diagonal as a length to place cameras, lights and ray origins
    /// by, however small the box: `1e-6` only for a box of no size (one
    /// point) or the empty box, where the diagonal would put them all at
    /// one point.
    pub fn placing_length(&self) -> f32 {
        let d = self.diagonal();
        if d > 0.0 && d.is_finite() {
            d
        } else {
            1e-6
        }
    }

    /// Surface area, the measure the surface area heuristic (SAH) uses;
    /// 0 for the empty box.
    #[inline]
    pub fn surface_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// Index of the longest axis (0 = x, 1 = y, 2 = z).
    pub fn largest_axis(&self) -> usize {
        let e = self.extent();
        if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        }
    }

    /// True when `p` lies inside or on the boundary.
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// True when the boxes share at least one point.
    pub fn overlaps(&self, other: &Aabb) -> bool {
        self.min.cmple(other.max).all() && other.min.cmple(self.max).all()
    }

    /// Slab test (Kay & Kajiya): the parametric interval in which the ray is
    /// inside the box, clipped to `[tmin, tmax]`, or `None` when empty.
    ///
    /// Uses the ray's reciprocal direction; a zero direction component gives
    /// infinities that compare correctly, except for the 0·inf = NaN case when
    /// the origin lies exactly on a slab plane, which `min`/`max` (NaN-ignoring
    /// in glam) resolve as "inside".
    #[inline]
    pub fn clip(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<(f32, f32)> {
        let t0 = (self.min - ray.origin) * ray.inv_dir;
        let t1 = (self.max - ray.origin) * ray.inv_dir;
        let near = t0.min(t1);
        let far = t0.max(t1);
        let enter = near.max_element().max(tmin);
        let exit = far.min_element().min(tmax);
        (enter <= exit).then_some((enter, exit))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The diagonal of a tiny or a huge box is its length, as in `f64`,
    /// where the squares of its sides underflow or overflow `f32`; a point
    /// and the empty box have none.
    #[test]
    fn the_diagonal_of_tiny_and_huge_boxes() {
        for side in [1e-30f32, 1e-20, 1e-10, 1.0, 1e10, 1e20, 1e30] {
            let b = Aabb::new(Vec3::ZERO, Vec3::new(side, 2.0 * side, 2.0 * side));
            let want = 3.0 * f64::from(side);
            let got = f64::from(b.diagonal());
            assert!(
                (got - want).abs() <= 1e-6 * want,
                "side {side}: {got} vs {want}"
            );
            assert_eq!(b.placing_length(), b.diagonal());
        }
        let point = Aabb::new(Vec3::ONE, Vec3::ONE);
        assert_eq!(point.diagonal(), 0.0);
        assert_eq!(point.placing_length(), 1e-6);
        assert_eq!(Aabb::EMPTY.diagonal(), 0.0);
    }

    #[test]
    fn union_with_empty_is_identity() {
        let b = Aabb::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 3.0, 4.0));
        assert_eq!(b.union(Aabb::EMPTY), b);
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
        assert_eq!(b.surface_area(), 2.0 * (2.0 * 3.0 + 3.0 * 2.0 + 2.0 * 2.0));
    }

    #[test]
    fn clip_matches_point_sampling() {
        // Independent reference: walk the ray in small steps and record where
        // it is inside the box.
        let b = Aabb::new(Vec3::new(-1.0, -2.0, -0.5), Vec3::new(2.0, 1.0, 0.5));
        let mut rng = crate::rng::Pcg32::new(11);
        for _ in 0..2000 {
            let o = rng.in_box(Vec3::splat(-4.0), Vec3::splat(4.0));
            let d = rng.unit_vector();
            let ray = Ray::new(o, d);
            let got = b.clip(&ray, 0.0, 20.0);
            let steps = 20_000;
            let mut inside = Vec::new();
            for i in 0..=steps {
                let t = 20.0 * i as f32 / steps as f32;
                if b.contains(ray.at(t)) {
                    inside.push(t);
                }
            }
            match got {
                None => assert!(inside.len() <= 1, "missed {} samples", inside.len()),
                Some((t0, t1)) => {
                    let first = *inside.first().unwrap_or(&t0);
                    let last = *inside.last().unwrap_or(&t1);
                    assert!(
                        (first - t0).abs() < 2e-3 && (last - t1).abs() < 2e-3,
                        "{t0} {t1} vs {first} {last}"
                    );
                }
            }
        }
    }

    #[test]
    fn axis_parallel_rays_on_and_off_the_box() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let hit = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::Z);
        assert_eq!(b.clip(&hit, 0.0, f32::INFINITY), Some((1.0, 2.0)));
        let miss = Ray::new(Vec3::new(1.5, 0.5, -1.0), Vec3::Z);
        assert_eq!(b.clip(&miss, 0.0, f32::INFINITY), None);
    }
}
