//! Meshes for the point and multi-hit ray query tests: random soups,
//! closed spheres, and the same spheres opened, with a duplicated triangle,
//! or overlapping.
#![allow(dead_code)]

use raykit_core::{TriangleMesh, Vec3};
use std::collections::HashMap;

#[path = "../soup/mod.rs"]
mod soup;

/// A soup of `n` random triangles of varied size inside the unit cube.
pub fn random_soup(n: usize, seed: u64) -> TriangleMesh {
    soup::soup(n, seed, 0.002, 0.1, 3)
}

/// A closed unit sphere, counter-clockwise seen from outside: an
/// octahedron subdivided `levels` times, vertices shared.
pub fn sphere(levels: u32) -> TriangleMesh {
    let mut pos = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let mut idx: Vec<[u32; 3]> = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    for _ in 0..levels {
        let mut mid = HashMap::new();
        let mut next = Vec::new();
        for [a, b, c] in idx {
            let mut m = |x: u32, y: u32| {
                *mid.entry((x.min(y), x.max(y))).or_insert_with(|| {
                    pos.push((pos[x as usize] + pos[y as usize]).normalize());
                    pos.len() as u32 - 1
                })
            };
            let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
            next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        idx = next;
    }
    TriangleMesh::new(pos, idx)
}

/// `mesh` moved by `offset` and scaled by `scale` about the origin first.
pub fn transformed(mesh: &TriangleMesh, scale: f32, offset: Vec3) -> TriangleMesh {
    let mut m = mesh.clone();
    for p in &mut m.positions {
        *p = *p * scale + offset;
    }
    m
}

/// `mesh` without the triangles whose centroid `drop` selects.
pub fn without(mesh: &TriangleMesh, drop: impl Fn(Vec3) -> bool) -> TriangleMesh {
    let indices = (0..mesh.num_triangles())
        .filter(|&t| {
            let [a, b, c] = mesh.triangle(t);
            !drop((a + b + c) / 3.0)
        })
        .map(|t| mesh.indices[t])
        .collect();
    TriangleMesh::new(mesh.positions.clone(), indices)
}

/// The centroid of triangle `t`.
pub fn centroid(mesh: &TriangleMesh, t: usize) -> Vec3 {
    let [a, b, c] = mesh.triangle(t);
    (a + b + c) / 3.0
}
