//! The independent reference for the culling tests: ray-traced visibility.
//! A triangle is visible when some ray from a sample point on it (either
//! face) meets no other triangle, so it leaves the bounding sphere. Uses the
//! Plücker test through a BVH, not the grid.

#![allow(dead_code)]

use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::rng::Pcg32;
use raykit_core::tri::TestKind;
use raykit_core::{Accel, Ray, TriangleMesh, Vec3};
use rayon::prelude::*;

/// Per triangle: seen by some of `points` sample points × both faces ×
/// (`dirs` random directions + one direction towards each of `targets`).
pub fn reference_visible(
    mesh: &TriangleMesh,
    points: u32,
    dirs: u32,
    targets: &[Vec3],
) -> Vec<bool> {
    let accel = build_accel(
        AccelKind::Bvh2,
        TestKind::Plucker,
        mesh,
        &BuildOptions::default(),
    );
    (0..mesh.num_triangles())
        .into_par_iter()
        .map(|t| seen(mesh, accel.as_ref(), t, points, dirs, targets))
        .collect()
}

fn seen(
    mesh: &TriangleMesh,
    accel: &dyn Accel,
    t: usize,
    points: u32,
    dirs: u32,
    targets: &[Vec3],
) -> bool {
    let [a, b, c] = mesh.triangle(t);
    let n = (b - a).cross(c - a).normalize_or_zero();
    let mut rng = Pcg32::with_stream(12345, t as u64);
    for k in 0..points {
        // First the centroid, then random points.
        let (mut u, mut v) = if k == 0 {
            (1.0 / 3.0, 1.0 / 3.0)
        } else {
            (rng.next_f32(), rng.next_f32())
        };
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let p = a + u * (b - a) + v * (c - a);
        for face in [n, -n] {
            let o = p + face * 1e-4;
            let random = (0..dirs).map(|_| {
                let d = rng.unit_vector();
                if d.dot(face) < 0.0 {
                    -d
                } else {
                    d
                }
            });
            let aimed: Vec<Vec3> = targets
                .iter()
                .map(|&q| (q - o).normalize_or_zero())
                .filter(|d| d.dot(face) > 0.0)
                .collect();
            for d in random.chain(aimed) {
                if !escaped(accel, o, d, t as u32) {
                    continue;
                }
                return true;
            }
        }
    }
    false
}

fn escaped(accel: &dyn Accel, o: Vec3, d: Vec3, own: u32) -> bool {
    let mut tnear = 0.0f32;
    for _ in 0..4 {
        match accel.intersect(&Ray::segment(o, d, tnear, f32::INFINITY)) {
            None => return true,
            Some(h) if h.prim == own => tnear = h.t.next_up(),
            Some(_) => return false,
        }
    }
    false
}

/// Triangles the reference sees but `kept` removes (false removals).
pub fn false_removals(reference: &[bool], kept: &[bool]) -> Vec<usize> {
    (0..reference.len())
        .filter(|&t| reference[t] && !kept[t])
        .collect()
}
