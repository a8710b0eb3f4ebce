//! A model far smaller than a unit, judged at unit size. The ray-triangle
//! tests multiply two or three coordinate differences in `f32` (Möller and
//! Trumbore 1997's determinant, its rounding-error bounds), the closest
//! point four (Ericson 2005's region tests): on a model a few nanometres
//! across in metres those products fall to the bottom of `f32`'s range,
//! and distances, then hits, come out wrong. Scaling the model by a power
//! of two is exact (the same geometry, no rounding), so the structures
//! are built over the scaled model and each query is scaled in and its
//! answer scaled back; the answers are those of the same model at unit
//! size, divided by the factor. Models whose box is at least
//! [`SCALED_BELOW`] across are used as they are, so that they pay nothing
//! (the scaled rays cost a model's one-ray queries about 4%).

use crate::aabb::Aabb;
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use glam::Vec3;
use std::borrow::Cow;

/// The size below which a model is scaled: `2⁻¹⁶`, 15 µm in metres. On
/// the full Stanford dragon (871,414 triangles) shrunk by powers of two,
/// distances first differed from the unit model's at `2⁻²⁴` across, and
/// hits at `2⁻³⁶` (BENCHMARKS.md); this leaves a margin of eight binary
/// orders for finer meshes.
pub const SCALED_BELOW: f32 = 1.0 / 65_536.0;

/// The power of two a model smaller than [`SCALED_BELOW`] is scaled by so
/// that the largest side of its box lies in `[1, 2)`; one for any other
/// model, empty or not finite. For the triangle tests that work on
/// coordinates rather than on differences from the ray's origin (see
/// [`UnitScale::for_mesh_near_origin`]), also the point a model far from
/// the origin is moved from, so that its box's centre is at the origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UnitScale {
    /// The factor as two powers of two that are each finite in `f32` (a
    /// box as small as `2⁻¹⁴⁹` needs `2¹⁴⁹`, beyond `f32::MAX`).
    factor: (f32, f32),
    /// The point of the model that goes to the origin, in the model's
    /// units (subtracted before scaling).
    offset: Vec3,
}

impl UnitScale {
    /// No scaling.
    pub const ONE: UnitScale = UnitScale {
        factor: (1.0, 1.0),
        offset: Vec3::ZERO,
    };

    /// The scale for a model whose box has `side` as its largest side.
    pub fn for_side(side: f32) -> Self {
        if !(side > 0.0 && side < SCALED_BELOW && side.is_finite()) {
            return UnitScale::ONE;
        }
        // The exponent that brings `side` into [1, 2): f32 sides are at
        // least 2^-149, so it is at most 149, applied in two steps that
        // are each a finite power of two.
        let k = -(side as f64).log2().floor() as i32;
        let k = if side as f64 * 2f64.powi(k) < 1.0 {
            k + 1
        } else {
            k
        };
        UnitScale {
            factor: (2f32.powi(k / 2), 2f32.powi(k - k / 2)),
            offset: Vec3::ZERO,
        }
    }

    /// The scale for `mesh`, from the box of the vertices its triangles
    /// use (one for a mesh without triangles): a vertex that no triangle
    /// uses, however far, does not keep a tiny model at its own size. An
    /// index out of range is passed over here (the structures refuse it).
    pub fn for_mesh(mesh: &TriangleMesh) -> Self {
        Self::for_bounds(&used_bounds(mesh))
    }

    /// The scale for a model whose box is `b`.
    pub(crate) fn for_bounds(b: &Aabb) -> Self {
        Self::for_side((b.max - b.min).max_element())
    }

    /// [`UnitScale::for_mesh`], and the centre of the box of `mesh` moved
    /// to the origin when it is further from it than the box's largest
    /// side. The Plücker test (Plücker coordinates of edges through the
    /// origin) and the projection test (planes through it) multiply
    /// coordinates, not their differences: on a 100 m model at UTM
    /// coordinates, 3% of the nearest hits of primary rays changed. The
    /// subtraction is exact in `f32` for every coordinate within a factor
    /// of two of the centre's (Sterbenz), which holds for a model of that
    /// kind.
    pub fn for_mesh_near_origin(mesh: &TriangleMesh) -> Self {
        Self::for_bounds_near_origin(&used_bounds(mesh))
    }

    /// [`UnitScale::for_mesh_near_origin`] for a model whose box is `b`.
    pub(crate) fn for_bounds_near_origin(b: &Aabb) -> Self {
        let mut scale = Self::for_bounds(b);
        let (centre, side) = ((b.min + b.max) * 0.5, (b.max - b.min).max_element());
        if centre.is_finite() && centre.abs().max_element() > side {
            scale.offset = centre;
        }
        scale
    }

    /// The scale for `mesh` and `mesh` at that scale: what a structure
    /// over it is built from.
    pub fn of(mesh: &TriangleMesh) -> (Self, Cow<'_, TriangleMesh>) {
        let scale = Self::for_mesh(mesh);
        (scale, scale.mesh(mesh))
    }

    /// [`UnitScale::of`] with [`UnitScale::for_mesh_near_origin`].
    pub fn of_near_origin(mesh: &TriangleMesh) -> (Self, Cow<'_, TriangleMesh>) {
        let scale = Self::for_mesh_near_origin(mesh);
        (scale, scale.mesh(mesh))
    }

    /// The scale as five `f32` bit patterns (the factor's two powers of
    /// two, the offset), as a saved structure records it.
    pub(crate) fn to_words(self) -> [u32; 5] {
        let (a, b) = self.factor;
        let o = self.offset;
        [a, b, o.x, o.y, o.z].map(f32::to_bits)
    }

    /// The scale [`Self::to_words`] recorded; `None` for words that are no
    /// scale (a factor not a positive power of two, or not finite).
    pub(crate) fn from_words(w: [u32; 5]) -> Option<Self> {
        let [a, b, x, y, z] = w.map(f32::from_bits);
        let power = |f: f32| f.is_finite() && f > 0.0 && f.to_bits() & 0x007f_ffff == 0;
        let offset = Vec3::new(x, y, z);
        (power(a) && power(b) && offset.is_finite()).then_some(UnitScale {
            factor: (a, b),
            offset,
        })
    }

    /// Whether this is no scaling at all.
    pub fn is_one(self) -> bool {
        self == UnitScale::ONE
    }

    /// A point of the model at unit scale (not finite when the point is
    /// so far from the model that scaling overflows `f32`).
    #[inline]
    pub fn point(self, p: Vec3) -> Vec3 {
        (p - self.offset) * self.factor.0 * self.factor.1
    }

    /// A length of the model at unit scale.
    #[inline]
    pub fn length(self, l: f32) -> f32 {
        l * self.factor.0 * self.factor.1
    }

    /// A length measured at unit scale, in the model's units.
    #[inline]
    pub fn to_model(self, l: f32) -> f32 {
        l / self.factor.0 / self.factor.1
    }

    /// A point at unit scale, in the model's units.
    #[inline]
    pub fn point_to_model(self, p: Vec3) -> Vec3 {
        p / self.factor.0 / self.factor.1 + self.offset
    }

    /// `mesh` at unit scale: itself when no scaling is needed.
    pub fn mesh(self, mesh: &TriangleMesh) -> Cow<'_, TriangleMesh> {
        if self.is_one() {
            return Cow::Borrowed(mesh);
        }
        let mut scaled = mesh.clone();
        for p in &mut scaled.positions {
            *p = self.point(*p);
        }
        Cow::Owned(scaled)
    }

    /// `ray` at unit scale: its origin and its interval scaled, its
    /// direction kept, so that a hit's `t` is scaled as lengths are.
    #[inline]
    pub fn ray(self, ray: &Ray) -> Ray {
        Ray {
            origin: self.point(ray.origin),
            tnear: self.length(ray.tnear),
            tfar: self.length(ray.tfar),
            ..*ray
        }
    }

    /// `rays` at unit scale: themselves when no scaling is needed.
    pub fn rays(self, rays: &[Ray]) -> Cow<'_, [Ray]> {
        if self.is_one() {
            return Cow::Borrowed(rays);
        }
        Cow::Owned(rays.iter().map(|r| self.ray(r)).collect())
    }

    /// Hits found at unit scale, in the model's units.
    pub fn hits_to_model(self, hits: &mut [Option<Hit>]) {
        if self.is_one() {
            return;
        }
        for h in hits.iter_mut().flatten() {
            *h = self.hit_to_model(*h);
        }
    }

    /// A hit found at unit scale, in the model's units.
    #[inline]
    pub fn hit_to_model(self, hit: Hit) -> Hit {
        Hit {
            t: self.to_model(hit.t),
            ..hit
        }
    }

    /// A box at unit scale, in the model's units.
    pub fn aabb_to_model(self, b: &Aabb) -> Aabb {
        Aabb::new(self.point_to_model(b.min), self.point_to_model(b.max))
    }
}

/// The box of the vertices `mesh`'s triangles use, indices out of range
/// passed over (empty for a mesh without triangles).
pub(crate) fn used_bounds(mesh: &TriangleMesh) -> Aabb {
    mesh.indices
        .iter()
        .flatten()
        .filter_map(|&i| mesh.positions.get(i as usize))
        .fold(Aabb::EMPTY, |b, &p| b.grow(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn side_of(mesh: &TriangleMesh) -> f32 {
        let b = mesh.bounds();
        (b.max - b.min).max_element()
    }

    #[test]
    fn tiny_models_come_to_unit_size_exactly() {
        for e in [17, 40, 100, 126, 140] {
            let s = 2f64.powi(-e) as f32 * 1.5;
            let tris = [
                [Vec3::ZERO, Vec3::X * s, Vec3::Y * s * 0.3],
                [Vec3::Z * s * 0.7, Vec3::X * s, Vec3::Y * s],
            ];
            let mesh = TriangleMesh::from_triangles(&tris);
            let unit = UnitScale::for_mesh(&mesh);
            let scaled = unit.mesh(&mesh);
            assert_eq!(unit.to_model(side_of(&scaled)), side_of(&mesh), "2^-{e}");
            assert!((1.0..2.0).contains(&side_of(&scaled)), "2^-{e}");
            // Exact: every coordinate is the original times the factor, in f64.
            let f = side_of(&scaled) as f64 / side_of(&mesh) as f64;
            assert_eq!(f.log2().fract(), 0.0, "2^-{e}: a power of two");
            for (p, q) in mesh.positions.iter().zip(&scaled.positions) {
                for k in 0..3 {
                    assert_eq!(q[k] as f64, p[k] as f64 * f, "2^-{e}");
                    assert_eq!(unit.point_to_model(*q)[k], p[k], "2^-{e}");
                }
            }
        }
        let unit = TriangleMesh::from_triangles(&[[Vec3::ZERO, Vec3::X, Vec3::Y]]);
        assert!(UnitScale::for_mesh(&unit).is_one());
        // Small but ordinary models are used as they are.
        for side in [0.2, 1e-3, SCALED_BELOW] {
            assert!(UnitScale::for_side(side).is_one(), "{side}");
        }
        assert!(!UnitScale::for_side(SCALED_BELOW * 0.99).is_one());
        assert!(matches!(
            UnitScale::for_mesh(&unit).mesh(&unit),
            Cow::Borrowed(_)
        ));
        assert!(UnitScale::for_mesh(&TriangleMesh::default()).is_one());
        let mut bad = TriangleMesh::from_triangles(&[[Vec3::ZERO, Vec3::X * 1e-9, Vec3::Y * 1e-9]]);
        bad.indices[0][2] = 7;
        assert!(!UnitScale::for_mesh(&bad).is_one(), "an index out of range");
    }

    #[test]
    fn a_ray_scaled_hits_at_the_scaled_distance() {
        let s = UnitScale::for_side(3e-12);
        let ray = Ray::segment(Vec3::new(1e-12, -2e-12, 5e-13), Vec3::Z, 1e-13, 4e-12);
        let r = s.ray(&ray);
        assert_eq!(r.dir(), ray.dir());
        assert_eq!(s.to_model(r.tfar), ray.tfar);
        assert_eq!(s.to_model(r.tnear), ray.tnear);
        let h = Hit {
            t: r.tfar,
            u: 0.25,
            v: 0.5,
            prim: 3,
        };
        assert_eq!(s.hit_to_model(h).t, ray.tfar);
        assert_eq!(s.hit_to_model(h).u, 0.25);
    }

    /// A model far from the origin is moved to it for the tests that need
    /// it, exactly where its coordinates lie within a factor of two of the
    /// centre's; one near the origin, or through `for_mesh`, is not.
    #[test]
    fn far_models_move_to_the_origin_exactly() {
        let at = Vec3::new(429_252.0, 5_150_885.0, 300.0);
        let tris = [
            [
                at,
                at + Vec3::new(96.5, 0.0, 2.0),
                at + Vec3::new(0.0, 80.0, -1.5),
            ],
            [
                at + Vec3::Z * 50.0,
                at + Vec3::X * 40.0,
                at + Vec3::Y * 12.5,
            ],
        ];
        let mesh = TriangleMesh::from_triangles(&tris);
        assert!(UnitScale::for_mesh(&mesh).is_one());
        let near = UnitScale::for_mesh_near_origin(&mesh);
        assert!(!near.is_one());
        let moved = near.mesh(&mesh);
        let b = moved.bounds();
        assert!(b.min.abs().max_element() < 100.0 && b.max.abs().max_element() < 100.0);
        for (p, q) in mesh.positions.iter().zip(&moved.positions) {
            assert_eq!(near.point_to_model(*q), *p);
            for k in 0..3 {
                assert_eq!(q[k] as f64, p[k] as f64 - near.offset[k] as f64, "exact");
            }
        }
        // Rays keep their direction and interval: hits' t are unchanged.
        let ray = Ray::segment(at + Vec3::new(10.0, 20.0, 500.0), -Vec3::Z, 1.0, 900.0);
        let r = near.ray(&ray);
        assert_eq!((r.dir(), r.tnear, r.tfar), (ray.dir(), ray.tnear, ray.tfar));
        assert_eq!(near.point_to_model(r.origin), ray.origin);
        // Near the origin (centre within the box's size), nothing moves.
        let centred = TriangleMesh::from_triangles(&[[Vec3::ZERO, Vec3::X, Vec3::Y]]);
        assert!(UnitScale::for_mesh_near_origin(&centred).is_one());
        // Tiny and far: moved, then scaled.
        let tiny = TriangleMesh::from_triangles(&[[
            Vec3::ONE,
            Vec3::ONE + Vec3::X * 1e-6,
            Vec3::ONE + Vec3::Y * 1e-6,
        ]]);
        let both = UnitScale::for_mesh_near_origin(&tiny);
        let side = {
            let b = both.mesh(&tiny).bounds();
            (b.max - b.min).max_element()
        };
        assert!((1.0..2.0).contains(&side), "{side}");
    }
}
