//! Synthetic assemblies with known visibility (test models):
//! boxes (closed, or with openings), icospheres, boxes full of parts, nested
//! shells. Each appended piece becomes one part, as a CAD assembly's nodes.
//! Used by the tests and the timings of Min's (2008) method.

use raykit_core::{Aabb, TriangleMesh, Vec3};

/// The surface of box `b`, each face cut into `n × n` squares of two
/// triangles, facing outwards; the square `(i, j)` of face `(axis, max_side)`
/// is left out where `open(axis, max_side, i, j)` is true (to make holes).
/// Square `(i, j)` spans the face's first cross axis (`(axis + 1) % 3`) by
/// `i` and the second by `j`.
pub fn box_surface(
    b: &Aabb,
    n: usize,
    open: impl Fn(usize, bool, usize, usize) -> bool,
) -> TriangleMesh {
    let n = n.max(1);
    let mut mesh = TriangleMesh::default();
    for axis in 0..3 {
        let (ba, ca) = ((axis + 1) % 3, (axis + 2) % 3);
        for max_side in [false, true] {
            let base = mesh.positions.len() as u32;
            for j in 0..=n {
                for i in 0..=n {
                    let mut p = Vec3::ZERO;
                    p[axis] = if max_side { b.max[axis] } else { b.min[axis] };
                    let lerp = |a: usize, k: usize| {
                        if k == n {
                            b.max[a]
                        } else {
                            b.min[a] + (b.max[a] - b.min[a]) * (k as f32 / n as f32)
                        }
                    };
                    p[ba] = lerp(ba, i);
                    p[ca] = lerp(ca, j);
                    mesh.positions.push(p);
                }
            }
            let v = |i: usize, j: usize| base + (i + (n + 1) * j) as u32;
            for j in 0..n {
                for i in 0..n {
                    if open(axis, max_side, i, j) {
                        continue;
                    }
                    let (a, b1, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
                    if max_side {
                        mesh.indices.push([a, b1, c]);
                        mesh.indices.push([a, c, d]);
                    } else {
                        mesh.indices.push([a, c, b1]);
                        mesh.indices.push([a, d, c]);
                    }
                }
            }
        }
    }
    mesh
}

/// The closed surface of box `b` (12 triangles per `n = 1`).
pub fn closed_box(b: &Aabb, n: usize) -> TriangleMesh {
    box_surface(b, n, |_, _, _, _| false)
}

/// An icosphere: the icosahedron with each triangle cut into four
/// `subdivisions` times (20 · 4^s triangles), projected onto the sphere.
pub fn icosphere(center: Vec3, radius: f32, subdivisions: u32) -> TriangleMesh {
    let ico = raykit_core::Icosphere::new(subdivisions);
    let positions = ico.positions.iter().map(|&p| center + p * radius).collect();
    TriangleMesh::new(positions, ico.indices)
}

/// One mesh holding `pieces` in order, each as its own part.
pub fn assembly(pieces: impl IntoIterator<Item = TriangleMesh>) -> TriangleMesh {
    let mut mesh = TriangleMesh::default();
    for p in pieces {
        mesh.append(&p);
    }
    mesh
}

/// The unit box (`n × n` squares per face) holding a `k × k × k` lattice of
/// icospheres with `subdivisions`, radius a third of their lattice cell; the
/// box is part 0, the spheres parts 1…k³. Every sphere is hidden. With
/// `k = 10, subdivisions = 3` it has 1,280,000 triangles of spheres (plus
/// `12 n²` of the box).
pub fn box_of_spheres(n: usize, k: usize, subdivisions: u32) -> TriangleMesh {
    let unit = Aabb::new(Vec3::ZERO, Vec3::ONE);
    let cell = 0.8 / k.max(1) as f32;
    let mut pieces = vec![closed_box(&unit, n)];
    for z in 0..k {
        for y in 0..k {
            for x in 0..k {
                let c = Vec3::splat(0.1) + cell * (Vec3::new(x as f32, y as f32, z as f32) + 0.5);
                pieces.push(icosphere(c, cell / 3.0, subdivisions));
            }
        }
    }
    assembly(pieces)
}
