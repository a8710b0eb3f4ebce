//! A procedural terrain: an fBm noise height field sampled on a regular
//! `n × n` grid of cells, each split into two triangles, lit by a far sun.

use crate::builder::material;
use crate::noise::Fbm;
use crate::{PointLight, Scene};
use raykit_core::glam::{Vec2, Vec3};
use raykit_core::{Camera, Part, TriangleMesh};
use rayon::prelude::*;

/// Triangles when none are asked for.
pub const DEFAULT_TRIANGLES: usize = 200_000;
/// Fewest triangles (one cell).
pub const MIN_TRIANGLES: usize = 2;
/// Side of the square the terrain covers, centred on the origin in x and z.
pub const SIZE: f32 = 100.0;
/// Height scale: heights lie within about `±0.5 · HEIGHT`.
pub const HEIGHT: f32 = 28.0;
/// Wavelength of the lowest noise octave.
pub const FEATURE: f32 = 40.0;
/// Noise octaves.
pub const OCTAVES: usize = 8;

/// Cells per side for about `triangles` triangles: the `n` with `2n²`
/// nearest to `triangles` (at least 1).
pub fn grid_size(triangles: usize) -> u32 {
    ((triangles as f64 / 2.0).sqrt().round() as u32).max(1)
}

/// Height of the terrain at `(x, z)` for noise `fbm`.
fn height(fbm: &Fbm, x: f32, z: f32) -> f32 {
    let f = fbm.sample(Vec2::new(x, z) / FEATURE);
    // Flatten the valleys a little and sharpen the peaks.
    HEIGHT * if f < 0.0 { 0.6 * f } else { f + 0.5 * f * f }
}

/// The terrain with `2n²` triangles, `n = grid_size(triangles)`; vertex
/// normals from central differences of the heights; materials by height and
/// slope (sand, grass, rock, snow); one part `terrain`.
pub fn terrain(seed: u64, triangles: usize) -> Scene {
    let n = grid_size(triangles) as usize;
    let w = n + 1;
    let fbm = Fbm::new(seed, OCTAVES);
    let step = SIZE / n as f32;
    let coord = |i: usize| -0.5 * SIZE + i as f32 * step;
    let heights: Vec<f32> = (0..w * w)
        .into_par_iter()
        .with_min_len(1024)
        .map(|k| height(&fbm, coord(k % w), coord(k / w)))
        .collect();
    let at = |i: usize, j: usize| heights[j * w + i];
    let positions: Vec<Vec3> = (0..w * w)
        .into_par_iter()
        .with_min_len(1024)
        .map(|k| Vec3::new(coord(k % w), heights[k], coord(k / w)))
        .collect();
    let normals: Vec<Vec3> = (0..w * w)
        .into_par_iter()
        .with_min_len(1024)
        .map(|k| {
            let (i, j) = (k % w, k / w);
            let (i0, i1) = (i.saturating_sub(1), (i + 1).min(n));
            let (j0, j1) = (j.saturating_sub(1), (j + 1).min(n));
            let dx = (at(i1, j) - at(i0, j)) / ((i1 - i0) as f32 * step);
            let dz = (at(i, j1) - at(i, j0)) / ((j1 - j0) as f32 * step);
            Vec3::new(-dx, 1.0, -dz).normalize()
        })
        .collect();

    let materials = vec![
        material("sand", [0.72, 0.65, 0.46], 0.02, 8.0),
        material("grass", [0.22, 0.40, 0.14], 0.02, 8.0),
        material("rock", [0.42, 0.39, 0.36], 0.05, 16.0),
        material("snow", [0.90, 0.91, 0.95], 0.15, 32.0),
    ];
    let classify = |tri: [u32; 3]| {
        let p = tri.map(|v| positions[v as usize]);
        let ny = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero().y;
        let h = (p[0].y + p[1].y + p[2].y) / 3.0;
        if h > 0.3 * HEIGHT && ny > 0.6 {
            3
        } else if ny < 0.75 {
            2
        } else if h < -0.12 * HEIGHT {
            0
        } else {
            1
        }
    };
    let mut indices = vec![[0u32; 3]; 2 * n * n];
    let mut tri_material = vec![0u32; 2 * n * n];
    indices
        .par_chunks_mut(2 * n)
        .zip(tri_material.par_chunks_mut(2 * n))
        .enumerate()
        .for_each(|(j, (tris, mats))| {
            for i in 0..n {
                let v = |i: usize, j: usize| (j * w + i) as u32;
                let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
                // Counter-clockwise seen from above (+y).
                tris[2 * i] = [a, d, b];
                tris[2 * i + 1] = [b, d, c];
                mats[2 * i] = classify(tris[2 * i]);
                mats[2 * i + 1] = classify(tris[2 * i + 1]);
            }
        });

    let mesh = TriangleMesh {
        positions,
        indices,
        normals: Some(normals),
        uvs: None,
        materials,
        tri_material,
        parts: vec![Part {
            name: "terrain".into(),
            node: None,
        }],
        tri_part: vec![0; 2 * n * n],
    };
    let sun_dir = Vec3::new(-0.45, 0.6, 0.35).normalize();
    let sun_distance = 100.0 * SIZE;
    Scene {
        name: "terrain".into(),
        mesh,
        lights: vec![PointLight::with_irradiance_at(
            sun_dir * sun_distance,
            Vec3::new(1.0, 0.95, 0.85) * 1.0,
            sun_distance,
        )
        .into()],
        camera: Some(Camera {
            eye: Vec3::new(0.0, 0.6 * SIZE, 0.8 * SIZE),
            target: Vec3::new(0.0, -0.1 * SIZE, -0.05 * SIZE),
            up: Vec3::Y,
            vfov_deg: 50.0,
        }),
    }
}
