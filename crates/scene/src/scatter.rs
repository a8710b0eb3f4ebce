//! Many small icospheres, each randomly rotated and non-uniformly stretched,
//! scattered uniformly in a cube whose volume grows with their number (so the
//! density stays the same), lit by one point light.

use crate::builder::material;
use crate::{PointLight, Scene};
use raykit_core::glam::{Affine3A, Quat, Vec3};
use raykit_core::rng::Pcg32;
use raykit_core::Icosphere;
use raykit_core::{Aabb, Camera, Part, TriangleMesh};
use rayon::prelude::*;

/// Triangles when none are asked for.
pub const DEFAULT_TRIANGLES: usize = 500_000;
/// Subdivisions of each icosphere.
pub const SUBDIVISIONS: u32 = 1;
/// Triangles per icosphere (`20 · 4^SUBDIVISIONS`).
pub const TRIANGLES_PER_SPHERE: usize = 20 * 4usize.pow(SUBDIVISIONS);
/// Fewest triangles (one icosphere).
pub const MIN_TRIANGLES: usize = TRIANGLES_PER_SPHERE;
/// Side of the cube holding the default number of spheres.
pub const DEFAULT_SIDE: f32 = 40.0;

/// Number of icospheres for about `triangles` triangles (nearest, at least 1);
/// the mesh has `TRIANGLES_PER_SPHERE` times as many triangles.
pub fn sphere_count(triangles: usize) -> usize {
    ((triangles as f64 / TRIANGLES_PER_SPHERE as f64).round() as usize).max(1)
}

/// A uniformly distributed rotation (Shoemake 1992).
fn random_rotation(rng: &mut Pcg32) -> Quat {
    let (u1, u2, u3) = (rng.next_f32(), rng.next_f32(), rng.next_f32());
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let (t2, t3) = (std::f32::consts::TAU * u2, std::f32::consts::TAU * u3);
    Quat::from_xyzw(a * t2.sin(), a * t2.cos(), b * t3.sin(), b * t3.cos()).normalize()
}

/// The scene with `sphere_count(triangles)` icospheres of 80 triangles each,
/// one part `icosphere K` per sphere (each closed), 8 random colours.
pub fn scatter(seed: u64, triangles: usize) -> Scene {
    let count = sphere_count(triangles);
    let default_count = sphere_count(DEFAULT_TRIANGLES);
    let side = DEFAULT_SIDE * (count as f32 / default_count as f32).cbrt();
    let half = Vec3::splat(0.5 * side);

    let mut rng = Pcg32::new(seed);
    let transforms: Vec<(Affine3A, u32)> = (0..count)
        .map(|_| {
            let center = rng.in_box(-half, half);
            let rotation = random_rotation(&mut rng);
            let r = rng.range_f32(0.35, 0.7);
            let scale = Vec3::new(
                r * rng.range_f32(0.5, 1.6),
                r * rng.range_f32(0.5, 1.6),
                r * rng.range_f32(0.5, 1.6),
            );
            let m = rng.below(8);
            (
                Affine3A::from_scale_rotation_translation(scale, rotation, center),
                m,
            )
        })
        .collect();

    let ico = Icosphere::new(SUBDIVISIONS);
    let (nv, nt) = (ico.positions.len(), ico.indices.len());
    let mut positions = vec![Vec3::ZERO; count * nv];
    let mut normals = vec![Vec3::ZERO; count * nv];
    let mut indices = vec![[0u32; 3]; count * nt];
    positions
        .par_chunks_mut(nv)
        .zip(normals.par_chunks_mut(nv))
        .zip(indices.par_chunks_mut(nt))
        .zip(transforms.par_iter())
        .enumerate()
        .for_each(|(k, (((pos, nor), tris), (t, _)))| {
            let normal_matrix = t.matrix3.inverse().transpose();
            for ((p, n), &q) in pos.iter_mut().zip(nor.iter_mut()).zip(&ico.positions) {
                *p = t.transform_point3(q);
                *n = (normal_matrix * q).normalize();
            }
            let base = (k * nv) as u32;
            for (dst, src) in tris.iter_mut().zip(&ico.indices) {
                *dst = src.map(|i| i + base);
            }
        });
    let tri_material = transforms
        .iter()
        .flat_map(|&(_, m)| std::iter::repeat_n(m, nt))
        .collect();
    let tri_part = (0..count as u32)
        .flat_map(|k| std::iter::repeat_n(k, nt))
        .collect();
    let parts = (0..count)
        .map(|k| Part {
            name: format!("icosphere {k}"),
            node: None,
        })
        .collect();
    let palette = [
        ("red", [0.75, 0.15, 0.12]),
        ("orange", [0.85, 0.45, 0.10]),
        ("yellow", [0.85, 0.75, 0.20]),
        ("green", [0.20, 0.60, 0.20]),
        ("teal", [0.10, 0.55, 0.55]),
        ("blue", [0.15, 0.30, 0.80]),
        ("purple", [0.50, 0.20, 0.65]),
        ("white", [0.85, 0.85, 0.85]),
    ];
    let materials = palette
        .iter()
        .map(|&(name, c)| material(name, c, 0.3, 32.0))
        .collect();

    let bounds = Aabb::new(-half - 1.0, half + 1.0);
    // Frame the bounding sphere, then move in: the cube fills less of it.
    let mut camera = Camera::framing(&bounds, 45.0);
    camera.eye = camera.target + (camera.eye - camera.target) * 0.88;
    let light_at = Vec3::new(-0.6, 1.0, 0.8).normalize() * 1.2 * side;
    Scene {
        name: "scatter".into(),
        mesh: TriangleMesh {
            positions,
            indices,
            normals: Some(normals),
            uvs: None,
            materials,
            tri_material,
            parts,
            tri_part,
        },
        lights: vec![
            PointLight::with_irradiance_at(light_at, Vec3::splat(1.6), light_at.length()).into(),
        ],
        camera: Some(camera),
    }
}
