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

/// `k[0] × k[1] × k[2]` copies of `mesh` side by side, `gap` times its
/// extent apart (0.1: a tenth of its size), each copy's parts its own —
/// an instanced assembly flattened.
pub fn copies(mesh: &TriangleMesh, k: [usize; 3], gap: f32) -> TriangleMesh {
    let step = mesh.bounds().extent() * (1.0 + gap);
    let mut out = TriangleMesh::default();
    for z in 0..k[2] {
        for y in 0..k[1] {
            for x in 0..k[0] {
                let mut copy = mesh.clone();
                let shift = step * Vec3::new(x as f32, y as f32, z as f32);
                for p in &mut copy.positions {
                    *p += shift;
                }
                out.append(&copy);
            }
        }
    }
    out
}

/// A closed box shell around `inner` (its bounds widened by `margin` times
/// their largest extent on every side), each face cut into `n × n` squares;
/// with `hole = Some(h)`, the `h × h` squares at the centre of the `+z` face
/// are left out. The shell is part 0, `inner`'s parts follow. Closed, every
/// triangle of `inner` is hidden and every shell triangle visible (its outer
/// face lies on the bounding box).
pub fn shell_around(
    inner: &TriangleMesh,
    margin: f32,
    n: usize,
    hole: Option<usize>,
) -> TriangleMesh {
    let b = inner.bounds();
    let pad = Vec3::splat(b.extent().max_element() * margin);
    let outer = Aabb::new(b.min - pad, b.max + pad);
    let n = n.max(1);
    let shell = box_surface(&outer, n, |axis, max_side, i, j| match hole {
        Some(h) if axis == 2 && max_side => {
            let lo = n.saturating_sub(h) / 2;
            (lo..lo + h).contains(&i) && (lo..lo + h).contains(&j)
        }
        _ => false,
    });
    let mut out = shell;
    out.append(inner);
    out
}

/// The unit box (`n × n` squares per face) with a slit `width` wide across
/// its whole `+x` face (parallel to y, at z = 0.5), and inside: a sphere
/// behind the slit (part 1, partly seen through it) and a sealed small box
/// (part 2) holding a sphere (part 3, hidden). The `+x` face is two plates
/// of `n × n/2` squares either side of the slit. A `width` below a grid
/// spacing closes the slit to a grid's outside air.
pub fn slit_box(n: usize, width: f32, subdivisions: u32) -> TriangleMesh {
    let unit = Aabb::new(Vec3::ZERO, Vec3::ONE);
    let n = n.max(2);
    let mut shell = box_surface(&unit, n, |axis, max_side, _, _| axis == 0 && max_side);
    let half = (0.5 - width * 0.5).max(0.0);
    for (z0, z1) in [(0.0, half), (1.0 - half, 1.0)] {
        // A plate on x = 1 facing +x: box_surface's +x face of a flat box.
        let plate = box_surface(
            &Aabb::new(Vec3::new(1.0, 0.0, z0), Vec3::new(1.0, 1.0, z1)),
            n,
            |axis, max_side, _, _| !(axis == 0 && max_side),
        );
        shell.append(&plate);
    }
    shell.tri_part.clear();
    shell.parts.clear();
    assembly([
        shell,
        icosphere(Vec3::new(0.75, 0.5, 0.5), 0.12, subdivisions),
        closed_box(
            &Aabb::new(Vec3::new(0.1, 0.1, 0.1), Vec3::new(0.35, 0.35, 0.35)),
            2,
        ),
        icosphere(Vec3::splat(0.225), 0.08, subdivisions),
    ])
}
