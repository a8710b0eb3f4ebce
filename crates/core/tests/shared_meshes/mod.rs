//! Test support for the saved and refit BVHs: the shared data's meshes
//! (read here with a small OBJ reader of their own, as the core does not
//! depend on `raykit-io`), smooth deformations, and random rays.
#![allow(dead_code)]

use raykit_core::rng::Pcg32;
use raykit_core::{Aabb, Hit, Ray, TriangleMesh, Vec3};
use std::path::PathBuf;

/// The test data folder: `data/` in the repository, or
/// `$RAYKIT_SHARED_DATA` (as the other crates' tests find it).
pub fn shared_data() -> PathBuf {
    let root = std::env::var_os("RAYKIT_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data"));
    assert!(
        root.is_dir(),
        "{} is missing: the tests need the test data folder (set RAYKIT_SHARED_DATA)",
        root.display()
    );
    root
}

/// A triangle mesh from the shared data's `meshes/NAME` (an OBJ of `v` and
/// `f` lines; polygons fanned into triangles).
pub fn shared_obj(name: &str) -> TriangleMesh {
    let path = shared_data().join("meshes").join(name);
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (the tests need the shared meshes)", path.display()));
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for (line_no, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let c: Vec<f32> = words.take(3).map(|w| w.parse().unwrap()).collect();
                assert_eq!(c.len(), 3, "{}:{}", path.display(), line_no + 1);
                positions.push(Vec3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let v: Vec<u32> = words
                    .map(|w| w.split('/').next().unwrap().parse::<u32>().unwrap() - 1)
                    .collect();
                for k in 1..v.len() - 1 {
                    indices.push([v[0], v[k], v[k + 1]]);
                }
            }
            _ => {}
        }
    }
    let mesh = TriangleMesh::new(positions, indices);
    mesh.validate().expect("a valid mesh");
    mesh
}

/// `mesh` with every vertex moved by a smooth displacement of phase
/// `phase`: a travelling wave of amplitude `amp` times the mesh's size
/// along the normal-ish direction from the centre, and a twist about y.
pub fn deformed(mesh: &TriangleMesh, phase: f32, amp: f32) -> TriangleMesh {
    let b = mesh.bounds();
    let (c, size) = (b.center(), b.extent().max_element());
    let mut out = mesh.clone();
    for p in &mut out.positions {
        let q = (*p - c) / size;
        let wave = amp * (6.0 * q.y + phase).sin() * (5.0 * q.x - phase).cos();
        let radial = q.normalize_or_zero();
        let twist = amp * 2.0 * q.y * phase.sin();
        let (s, co) = twist.sin_cos();
        let r = Vec3::new(co * q.x + s * q.z, q.y, -s * q.x + co * q.z);
        *p = c + (r + radial * wave) * size;
    }
    out
}

/// `n` rays at `mesh`: see [`rays_in`].
pub fn rays(mesh: &TriangleMesh, n: usize, seed: u64) -> Vec<Ray> {
    rays_in(&mesh.bounds(), n, seed)
}

/// `n` rays at the box `b`: from a sphere around it towards points of the
/// box, a quarter from inside the box in random directions, a fifth of all
/// as segments.
pub fn rays_in(b: &Aabb, n: usize, seed: u64) -> Vec<Ray> {
    let (c, r) = (b.center(), b.extent().length());
    let mut rng = Pcg32::new(seed);
    (0..n)
        .map(|i| {
            let target = rng.in_box(b.min, b.max);
            let origin = if i % 4 == 0 {
                rng.in_box(b.min, b.max)
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

/// Two nearest hits agree up to ties: both miss, or both hit at `t` within
/// 1e-5 relative (another triangle at the same distance may be reported).
pub fn agree(a: Option<Hit>, b: Option<Hit>) -> bool {
    match (a, b) {
        (Some(x), Some(y)) => (x.t - y.t).abs() <= 1e-5 * x.t.abs().max(y.t.abs()).max(1e-6),
        (x, y) => x.is_some() == y.is_some(),
    }
}

/// A hit as its bits, for exact comparison.
pub fn bits(h: Option<Hit>) -> Option<(u32, u32, u32, u32)> {
    h.map(|h| (h.t.to_bits(), h.u.to_bits(), h.v.to_bits(), h.prim))
}
