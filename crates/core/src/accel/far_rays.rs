//! [`FarRays`]: rays that start far from the model moved up to it before
//! they are traced.
//!
//! The triangle tests work on the difference between the ray's origin and a
//! corner (Möller and Trumbore 1997), in `f32`. From an origin `D` away that
//! difference carries a rounding error of about `D·2⁻²⁴`, and the edge tests
//! divide it by the triangle's size: rays from 10⁵ model radii away missed a
//! closed sphere through triangles they pass well inside, each corner
//! rounded differently, so that neighbours no longer close up. Moving the
//! origin along the ray to just outside the model's bounding sphere (in
//! `f64`, then rounded once) gives every test of one ray the same origin,
//! near the model, where the tests are exact to their tolerance; the hit's
//! distance is the moved ray's plus the distance moved.

use super::{Accel, AccelStats, PersistError, RefitError, RefitReport};
use crate::aabb::Aabb;
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::Ray;
use crate::unit_scale::UnitScale;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// An origin farther from the model's centre than this many radii of its
/// bounding sphere is moved. Nearer, the corners' differences keep their
/// rounding within the triangle tests' tolerance, and the ray is traced as
/// given, so cameras and sample points around a model are untouched.
pub const FAR_RADII: f32 = 16.0;

/// How far, in units of `dir`, a ray from `origin` moves along itself to
/// lie twice `radius` before its closest approach to `centre`: from there
/// on it is where [`FarRays`] traces it. Points before the new origin lie
/// outside the sphere, so no hit is passed over. Not finite when `dir` is
/// zero or not finite.
///
/// The moved origin `origin + t·dir` rounds to the spacing of doubles at
/// the origin's (or the centre's) largest coordinate, which from about
/// 10¹⁶ exceeds a unit model's radius: the start backs off by four such
/// spacings too, so that however it rounds it stays outside the sphere.
#[inline]
pub fn approach_start(origin: DVec3, dir: DVec3, centre: DVec3, radius: f64) -> f64 {
    let dd = dir.dot(dir);
    let spacing = f64::EPSILON * origin.abs().max_element().max(centre.abs().max_element());
    (centre - origin).dot(dir) / dd - (2.0 * radius + 4.0 * spacing) / dd.sqrt()
}

/// Rays per run of a batch: each run is checked for far origins and, when
/// it has none, handed on as it is, while its rays are still in cache.
const RUN: usize = 4096;

/// A structure whose rays from far away ([`FAR_RADII`]) are moved up to
/// its model before they are traced, so that Möller and Trumbore's (1997)
/// differences from the origin stay small; every other ray, and every other
/// query, goes to the structure as it is. [`super::build_accel`] and
/// [`super::load_accel`] wrap every structure over Möller's test in it.
pub struct FarRays<A: Accel + ?Sized = dyn Accel> {
    /// The centre of the model's bounding sphere.
    centre: Vec3,
    /// The sphere's radius.
    radius: f32,
    /// `(FAR_RADII · radius)²`.
    far2: f32,
    inner: Box<A>,
}

impl FarRays {
    /// `inner`, built over `mesh` (in the units rays come in).
    pub fn wrap(inner: Box<dyn Accel>, mesh: &TriangleMesh) -> Box<dyn Accel> {
        Box::new(FarRays::around(inner, mesh))
    }
}

impl<A: Accel + ?Sized> FarRays<A> {
    /// `inner`, built over `mesh`.
    pub fn around(inner: Box<A>, mesh: &TriangleMesh) -> Self {
        let mut far = FarRays {
            centre: Vec3::ZERO,
            radius: 0.0,
            far2: f32::INFINITY,
            inner,
        };
        far.fit(mesh);
        far
    }

    /// The structure the rays go to.
    pub fn inner(&self) -> &A {
        &self.inner
    }

    /// The sphere around `mesh`'s box. An empty mesh keeps every ray as
    /// it is (an infinite limit).
    fn fit(&mut self, mesh: &TriangleMesh) {
        let b = mesh.bounds();
        let (centre, radius) = (b.center(), 0.5 * b.diagonal());
        let ok = centre.is_finite() && radius.is_finite() && mesh.num_triangles() > 0;
        self.centre = if ok { centre } else { Vec3::ZERO };
        // A point model still has a sphere to move rays up to.
        self.radius = if ok {
            radius.max(f32::MIN_POSITIVE)
        } else {
            0.0
        };
        self.far2 = if ok {
            (FAR_RADII * self.radius).powi(2)
        } else {
            f32::INFINITY
        };
    }

    /// Whether `ray` starts far from the model (false for a NaN origin:
    /// the structure refuses it as it is).
    #[inline(always)]
    fn is_far(&self, ray: &Ray) -> bool {
        let d = ray.origin - self.centre;
        d.dot(d) > self.far2
    }

    /// `ray` moved along itself to twice the sphere's radius before its
    /// closest approach to the centre, the distance `t0` moved (in units of
    /// its direction) and the length `len` of its direction. Points before
    /// the new origin lie outside the sphere, so the moved ray's interval
    /// `[(tnear − t0)·len, (tfar − t0)·len]` holds the same hits.
    fn moved(&self, ray: &Ray) -> (Ray, f64, f64) {
        let (o, d) = (ray.origin.as_dvec3(), ray.dir().as_dvec3());
        let dd = d.dot(d);
        if !(dd > 0.0 && dd.is_finite() && o.is_finite()) {
            return (*ray, 0.0, 1.0);
        }
        let t0 = approach_start(o, d, self.centre.as_dvec3(), self.radius as f64);
        let origin = (o + d * t0).as_vec3();
        // The moved ray's direction has unit length, so that its distances
        // are those of the model's units (a direction as long as the way
        // from a far origin puts the model within a tiny fraction of `t`).
        let len = dd.sqrt();
        let shift = |t: f32| ((t as f64 - t0) * len) as f32;
        (
            Ray::segment(
                origin,
                (d / len).as_vec3(),
                shift(ray.tnear),
                shift(ray.tfar),
            ),
            t0,
            len,
        )
    }

    /// A hit of the moved ray as a hit of `ray`: its distance moved back,
    /// kept within the ray's interval (the sum's rounding may step out).
    #[inline]
    fn moved_back(ray: &Ray, (t0, len): (f64, f64), hit: Hit) -> Hit {
        let t = ((hit.t as f64 / len + t0) as f32).clamp(ray.tnear, ray.tfar);
        Hit { t, ..hit }
    }
}

impl<A: Accel + ?Sized> Accel for FarRays<A> {
    /// A near ray goes on as a tail call; the far path is out of line, so
    /// that the check is all a near ray pays.
    #[inline]
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if self.is_far(ray) {
            return self.intersect_far(ray);
        }
        self.inner.intersect(ray)
    }

    #[inline]
    fn occluded(&self, ray: &Ray) -> bool {
        if self.is_far(ray) {
            return self.occluded_far(ray);
        }
        self.inner.occluded(ray)
    }

    fn stats(&self) -> AccelStats {
        self.inner.stats()
    }

    fn visit_regions(&self, enter: &mut dyn FnMut(&Aabb) -> bool, leaf: &mut dyn FnMut(&[u32])) {
        self.inner.visit_regions(enter, leaf)
    }

    fn save(&self, path: &std::path::Path, mesh: &TriangleMesh) -> Result<(), PersistError> {
        self.inner.save(path, mesh)
    }

    fn save_at_scale(
        &self,
        path: &std::path::Path,
        mesh: &TriangleMesh,
        scale: UnitScale,
    ) -> Result<(), PersistError> {
        self.inner.save_at_scale(path, mesh, scale)
    }

    /// The structure refit, and the sphere fitted to the moved model.
    fn refit(&mut self, mesh: &TriangleMesh) -> Result<RefitReport, RefitError> {
        let report = self.inner.refit(mesh)?;
        self.fit(mesh);
        Ok(report)
    }

    /// Run by run: a run without far origins goes on as it is; in one
    /// with any, those rays are moved in a copy and their hits moved back.
    fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        rays.par_chunks(RUN)
            .zip(hits.par_chunks_mut(RUN))
            .for_each(|(r, h)| {
                if !r.iter().any(|ray| self.is_far(ray)) {
                    return self.inner.intersect_batch(r, h);
                }
                let (moved, t0) = self.moved_run(r);
                self.inner.intersect_batch(&moved, h);
                for ((hit, ray), &by) in h.iter_mut().zip(r).zip(&t0) {
                    if let Some(x) = hit {
                        *x = Self::moved_back(ray, by, *x);
                    }
                }
            });
    }

    fn occluded_batch(&self, rays: &[Ray], occluded: &mut [bool]) {
        assert_eq!(rays.len(), occluded.len(), "one result per ray");
        rays.par_chunks(RUN)
            .zip(occluded.par_chunks_mut(RUN))
            .for_each(|(r, o)| {
                if !r.iter().any(|ray| self.is_far(ray)) {
                    return self.inner.occluded_batch(r, o);
                }
                self.inner.occluded_batch(&self.moved_run(r).0, o);
            });
    }
}

impl<A: Accel + ?Sized> FarRays<A> {
    #[cold]
    #[inline(never)]
    fn intersect_far(&self, ray: &Ray) -> Option<Hit> {
        let (moved, t0, len) = self.moved(ray);
        let hit = self.inner.intersect(&moved)?;
        Some(Self::moved_back(ray, (t0, len), hit))
    }

    #[cold]
    #[inline(never)]
    fn occluded_far(&self, ray: &Ray) -> bool {
        self.inner.occluded(&self.moved(ray).0)
    }

    /// A run's rays with the far ones moved, and how (see
    /// [`FarRays::moved`]).
    fn moved_run(&self, rays: &[Ray]) -> (Vec<Ray>, Vec<(f64, f64)>) {
        rays.iter()
            .map(|ray| match self.is_far(ray) {
                true => {
                    let (moved, t0, len) = self.moved(ray);
                    (moved, (t0, len))
                }
                false => (*ray, (0.0, 1.0)),
            })
            .unzip()
    }
}
