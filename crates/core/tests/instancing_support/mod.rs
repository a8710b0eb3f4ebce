//! Test support for instanced scenes: random placements of meshes, the same
//! scene flattened into one mesh, and `f64` brute-force references computed
//! on the object-space corners mapped to world space in `f64`.
#![allow(dead_code)]

use raykit_core::glam::{Affine3A, DAffine3, DVec3, Quat, Vec3};
use raykit_core::instancing::{InstancedScene, SceneBuilder, SceneHit};
use raykit_core::rng::Pcg32;
use raykit_core::tri::reference::{edge_distance_f64, intersect_f64};
use raykit_core::{Aabb, Ray, TriangleMesh};

/// A scene description kept beside the built scene: the meshes and, per
/// instance, its geometry, transform and mask.
pub struct Placed {
    pub meshes: Vec<TriangleMesh>,
    pub instances: Vec<(u32, Affine3A, u32)>,
}

/// A rotation, scale (some non-uniform, some mirrored) and translation
/// placing objects of size about `size` within a cube of side `spread`.
pub fn random_transform(rng: &mut Pcg32, size: f32, spread: f32) -> Affine3A {
    let axis = rng.unit_vector();
    let rot = Quat::from_axis_angle(axis, rng.range_f32(0.0, std::f32::consts::TAU));
    let s = rng.range_f32(0.5, 1.5) / size;
    let mut scale = Vec3::new(
        s * rng.range_f32(0.7, 1.3),
        s * rng.range_f32(0.7, 1.3),
        s * rng.range_f32(0.7, 1.3),
    );
    if rng.below(4) == 0 {
        scale.x = -scale.x;
    }
    let at = rng.in_box(Vec3::ZERO, Vec3::splat(spread));
    Affine3A::from_scale_rotation_translation(scale, rot, at)
}

impl Placed {
    /// `count` instances of `meshes` (each mesh at least once, the rest
    /// random), random transforms, all masks set.
    pub fn random(meshes: Vec<TriangleMesh>, count: usize, spread: f32, seed: u64) -> Placed {
        let mut rng = Pcg32::new(seed);
        let mut instances = Vec::new();
        for i in 0..count {
            let g = if i < meshes.len() {
                i as u32
            } else {
                rng.below(meshes.len() as u32)
            };
            let size = meshes[g as usize].bounds().extent().max_element();
            instances.push((g, random_transform(&mut rng, size, spread), u32::MAX));
        }
        Placed { meshes, instances }
    }

    /// Build the instanced scene (masks on the instances).
    pub fn scene(&self) -> InstancedScene {
        let mut b = SceneBuilder::new();
        for m in &self.meshes {
            b.add_geometry(m.clone()).unwrap();
        }
        for (g, t, mask) in &self.instances {
            let i = b.add_instance(*g, *t).unwrap();
            b.set_instance_mask(i, *mask).unwrap();
        }
        b.build(&Default::default())
    }

    /// The scene flattened: every instance's triangles mapped to world
    /// space in `f32` and concatenated, and per triangle its
    /// `(geometry, instance, prim)`. Only instances whose mask shares a bit
    /// with `mask`.
    pub fn flattened(&self, mask: u32) -> (TriangleMesh, Vec<(u32, u32, u32)>) {
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        let mut ids = Vec::new();
        for (i, (g, t, m)) in self.instances.iter().enumerate() {
            if m & mask == 0 {
                continue;
            }
            let mesh = &self.meshes[*g as usize];
            let base = positions.len() as u32;
            positions.extend(mesh.positions.iter().map(|p| t.transform_point3(*p)));
            for (k, tri) in mesh.indices.iter().enumerate() {
                indices.push(tri.map(|v| v + base));
                ids.push((*g, i as u32, k as u32));
            }
        }
        (TriangleMesh::new(positions, indices), ids)
    }

    /// The world box of all instances.
    pub fn bounds(&self) -> Aabb {
        let (flat, _) = self.flattened(u32::MAX);
        flat.bounds()
    }

    /// Every world triangle in `f64`: object corners mapped by the `f64`
    /// transform, with its `(geometry, instance, prim)`; instances whose
    /// mask misses `mask` left out.
    pub fn world_f64(&self, mask: u32) -> Vec<WorldTri> {
        let mut out = Vec::new();
        for (i, (g, t, m)) in self.instances.iter().enumerate() {
            if m & mask == 0 {
                continue;
            }
            let d = DAffine3::from_cols_array(&t.to_cols_array().map(f64::from));
            let mesh = &self.meshes[*g as usize];
            for k in 0..mesh.num_triangles() {
                let c = mesh.triangle(k).map(|v| d.transform_point3(v.as_dvec3()));
                out.push((c, (*g, i as u32, k as u32)));
            }
        }
        out
    }
}

/// A world triangle in `f64` with its `(geometry, instance, prim)`.
pub type WorldTri = ([DVec3; 3], (u32, u32, u32));

/// A crossing of the `f64` reference: `t`, ids, the world normal
/// (`e1 × e2`, not normalised) and the crossing's distance from the
/// triangle's boundary relative to its size.
#[derive(Clone, Copy, Debug)]
pub struct Crossing {
    pub t: f64,
    pub ids: (u32, u32, u32),
    pub normal: DVec3,
    pub margin: f64,
}

/// Every crossing of `ray` with `world` within `[tnear, tfar]`, sorted by `t`.
pub fn crossings(world: &[WorldTri], ray: &Ray) -> Vec<Crossing> {
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let mut out = Vec::new();
    for ([a, b, c], ids) in world {
        if let Some((t, _, _)) = intersect_f64(*a, *b, *c, o, d) {
            if t >= ray.tnear as f64 && t <= ray.tfar as f64 {
                out.push(Crossing {
                    t,
                    ids: *ids,
                    normal: (*b - *a).cross(*c - *a),
                    margin: edge_distance_f64(*a, *b, *c, o + d * t),
                });
            }
        }
    }
    out.sort_by(|x, y| x.t.total_cmp(&y.t));
    out
}

/// Rays at the scene: from a sphere around it towards points of its box,
/// a quarter from inside the box in random directions, a fifth of all as
/// segments.
pub fn rays(bounds: &Aabb, n: usize, seed: u64) -> Vec<Ray> {
    let (c, r) = (bounds.center(), bounds.extent().length());
    let mut rng = Pcg32::new(seed);
    (0..n)
        .map(|i| {
            let target = rng.in_box(bounds.min, bounds.max);
            let origin = if i % 4 == 0 {
                rng.in_box(bounds.min, bounds.max)
            } else {
                c + rng.unit_vector() * r
            };
            let dir = if i % 4 == 0 {
                rng.unit_vector()
            } else {
                target - origin
            };
            if i % 5 == 0 {
                Ray::segment(origin, dir, 0.05 * rng.next_f32(), 0.3 + rng.next_f32())
            } else {
                Ray::new(origin, dir)
            }
        })
        .collect()
}

/// Relative agreement of two distances.
pub fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-6)
}

/// Two distances to hits on (nearly) the same plane agree: the points
/// they give differ along the unit normal `n` by at most `1e-5 · scale`
/// (the rounding of corners and transforms of a scene of size `scale`),
/// which at a grazing angle is a large difference in `t`; or they agree to
/// `1e-4` relative.
pub fn close_on_plane(a: f64, b: f64, n: DVec3, dir: DVec3, scale: f64) -> bool {
    let along = n.normalize_or_zero().dot(dir).abs();
    close(a, b, 1e-4) || (a - b).abs() * along <= 1e-5 * scale
}

/// The ids of a scene hit.
pub fn ids(h: &SceneHit) -> (u32, u32, u32) {
    (h.geometry, h.instance, h.prim)
}
