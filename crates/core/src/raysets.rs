//! The standard ray sets used by `raykit rays`, `raykit bench` and the
//! comparisons with other engines: coherent primary rays, shadow rays from
//! the primary hits to a point light, and incoherent rays through the scene.

use crate::aabb::Aabb;
use crate::accel::Accel;
use crate::camera::Camera;
use crate::hit::Hit;
use crate::mesh::TriangleMesh;
use crate::ray::{unit_direction, Ray};
use crate::rng::Pcg32;
use glam::Vec3;

/// The kinds of standard ray sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RayKind {
    /// Pinhole camera rays, one per pixel of a square image.
    Primary,
    /// From each primary hit, offset along the normal, to a point light.
    Shadow,
    /// Origins on a sphere around the scene, aimed at random points inside it.
    Incoherent,
}

impl RayKind {
    /// Every kind, in a fixed order.
    pub const ALL: [RayKind; 3] = [RayKind::Primary, RayKind::Shadow, RayKind::Incoherent];

    /// The ray set's name, as `Display` writes it.
    pub fn name(self) -> &'static str {
        match self {
            RayKind::Primary => "primary",
            RayKind::Shadow => "shadow",
            RayKind::Incoherent => "incoherent",
        }
    }

    /// The ray set with this name, if any.
    pub fn from_name(name: &str) -> Option<RayKind> {
        name.parse().ok()
    }
}

crate::names::named_choice!(RayKind, "ray set");

/// Vertical field of view of the standard primary camera, degrees.
pub const PRIMARY_FOV_DEG: f32 = 40.0;

/// The standard camera for `mesh`: [`Camera::fit_points`] on its vertices
/// for a square image with [`PRIMARY_FOV_DEG`].
pub fn standard_camera(mesh: &TriangleMesh) -> Camera {
    Camera::fit_points(&mesh.bounds(), &mesh.positions, PRIMARY_FOV_DEG, 1.0)
}

/// The standard point light for `bounds`: above and to the side of the
/// scene, one box diagonal from its centre.
pub fn standard_light(bounds: &Aabb) -> Vec3 {
    bounds.center() + Vec3::new(0.4, 1.0, 0.6).normalize() * bounds.placing_length()
}

/// `size` × `size` primary rays from `camera`, row by row from the top-left.
pub fn primary(camera: &Camera, size: u32) -> Vec<Ray> {
    let gen = camera.rays(size, size);
    (0..size)
        .flat_map(|y| (0..size).map(move |x| gen.pixel(x, y)))
        .collect()
}

/// Shadow rays: for each primary ray with a hit, a segment from the hit
/// point (offset along the geometric normal towards the ray's side by
/// `1e-4 × scene diagonal`) to `light`, with `tfar` just short of the light.
/// Primary rays without a hit give no shadow ray.
pub fn shadow(mesh: &TriangleMesh, primary: &[Ray], hits: &[Option<Hit>], light: Vec3) -> Vec<Ray> {
    let eps = 1e-4 * mesh.bounds().placing_length();
    primary
        .iter()
        .zip(hits)
        .filter_map(|(ray, hit)| {
            let hit = (*hit)?;
            let mut n = mesh.unit_normal(hit.prim as usize);
            if n.dot(ray.dir) > 0.0 {
                n = -n;
            }
            let origin = ray.at(hit.t) + n * eps;
            Some(Ray::segment(origin, light - origin, 0.0, 1.0 - 1e-4))
        })
        .collect()
}

/// `count` incoherent rays: origins uniformly on the sphere of radius = box
/// diagonal around the box centre, unit directions towards uniformly random
/// points inside the box. Deterministic from `seed`.
pub fn incoherent(bounds: &Aabb, count: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Pcg32::with_stream(seed, 0x1c0e);
    let c = bounds.center();
    let r = bounds.placing_length();
    (0..count)
        .map(|_| {
            let origin = c + rng.unit_vector() * r;
            let target = rng.in_box(bounds.min, bounds.max);
            Ray::new(origin, unit_direction(target - origin))
        })
        .collect()
}

/// All three standard sets for `mesh`: `size`² primary rays, the shadow
/// rays of their hits (found with `accel`) and `size`² incoherent rays.
pub fn standard_sets(
    mesh: &TriangleMesh,
    accel: &dyn Accel,
    size: u32,
    seed: u64,
) -> [Vec<Ray>; 3] {
    let bounds = mesh.bounds();
    let prim = primary(&standard_camera(mesh), size);
    let mut hits = vec![None; prim.len()];
    accel.intersect_batch(&prim, &mut hits);
    let shad = shadow(mesh, &prim, &hits, standard_light(&bounds));
    let inc = incoherent(&bounds, (size as usize).pow(2), seed);
    [prim, shad, inc]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Incoherent rays around boxes from 10⁻³⁰ to 10³⁰ across start one
    /// diagonal from the centre (checked in `f64`) with unit directions
    /// that pass through the box (the slab test in `f64`).
    #[test]
    fn incoherent_rays_circle_boxes_of_every_size() {
        for side in [1e-30f32, 1e-20, 1e-6, 1.0, 1e6, 1e20, 1e30] {
            let b = Aabb::new(
                Vec3::splat(side),
                Vec3::new(2.0 * side, 3.0 * side, 2.5 * side),
            );
            let c = b.center().as_dvec3();
            let diagonal = (b.max - b.min).as_dvec3().length();
            for ray in incoherent(&b, 200, 7) {
                let (o, d) = (ray.origin.as_dvec3(), ray.dir().as_dvec3());
                assert!(
                    ((o - c).length() / diagonal - 1.0).abs() < 1e-5,
                    "side {side}"
                );
                assert!((d.length() - 1.0).abs() < 1e-6, "side {side}: {d}");
                let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
                let (mut t0, mut t1) = (0f64, f64::INFINITY);
                for a in 0..3 {
                    let (ta, tb) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
                    t0 = t0.max(ta.min(tb));
                    t1 = t1.min(ta.max(tb));
                }
                assert!(t0 <= t1 * (1.0 + 1e-5), "side {side}: misses the box");
            }
        }
    }
}
