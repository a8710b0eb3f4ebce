//! The point and multi-hit ray queries on the real meshes of the shared
//! data folder against `f64` brute force: closest points and distances,
//! winding numbers (exact and fast), inside/outside and signed distance,
//! and all hits along rays. The teapot and the bunny are open meshes.

use raykit_core::query::all_hits::ray_hits_brute;
use raykit_core::query::closest::{closest_on_triangle64, closest_point_brute};
use raykit_core::query::winding::winding_number_brute;
use raykit_core::query::SurfaceBvh;
use raykit_core::rng::Pcg32;
use raykit_core::{Ray, TriangleMesh, Vec3};
use std::path::PathBuf;

/// The test data folder: `data/` in the repository, or `$RAYKIT_SHARED_DATA`.
fn shared_data() -> PathBuf {
    let dir = std::env::var_os("RAYKIT_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data"));
    assert!(
        dir.join("meshes").is_dir(),
        "test data folder not found at {} (set RAYKIT_SHARED_DATA): these tests need the real meshes",
        dir.display()
    );
    dir
}

fn load(file: &str) -> TriangleMesh {
    raykit_io::load_mesh(&shared_data().join("meshes").join(file)).unwrap_or_else(|e| panic!("{e}"))
}

const MESHES: [(&str, usize); 5] = [
    ("teapot_992.obj", 300),
    ("bunny_3674.obj", 200),
    ("bearing.stl", 100),
    ("dragon_vrip_res4.ply.gz", 60),
    ("2CylinderEngine.glb", 60),
];

/// Points in the mesh's box grown by a third, and points near the surface.
fn points(mesh: &TriangleMesh, n: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = Pcg32::new(seed);
    let b = mesh.bounds();
    let pad = b.extent() / 3.0;
    (0..n)
        .map(|i| {
            if i % 2 == 0 {
                rng.in_box(b.min - pad, b.max + pad)
            } else {
                let [a, bb, c] = mesh.triangle(rng.below(mesh.num_triangles() as u32) as usize);
                (a + bb + c) / 3.0 + rng.unit_vector() * 0.01 * b.diagonal() * rng.next_f32()
            }
        })
        .collect()
}

#[test]
fn closest_points_match_brute_force() {
    for (file, n) in MESHES {
        let mesh = load(file);
        let bvh = SurfaceBvh::build(&mesh);
        let scale = mesh.bounds().diagonal() as f64;
        for p in points(&mesh, n, 1) {
            let (d_ref, _, _) = closest_point_brute(&mesh, p.as_dvec3()).unwrap();
            let got = bvh.closest_point(p, f32::INFINITY).expect("an answer");
            let tol = 1e-6 * scale + 1e-5 * d_ref;
            assert!(
                (got.distance as f64 - d_ref).abs() <= tol,
                "{file}: {} vs {d_ref}",
                got.distance
            );
            let tri = mesh.triangle(got.prim as usize).map(|c| c.as_dvec3());
            let (q, _, _) = closest_on_triangle64(p.as_dvec3(), &tri);
            assert!(
                got.point.as_dvec3().distance(q) <= tol,
                "{file}: point off its triangle"
            );
        }
    }
}

#[test]
fn winding_numbers_and_signs_match_brute_force() {
    for (file, n) in MESHES {
        let mesh = load(file);
        let bvh = SurfaceBvh::build(&mesh);
        let mut worst = 0.0f64;
        let mut inside = 0;
        for p in points(&mesh, n, 2) {
            let w = winding_number_brute(&mesh, p.as_dvec3());
            let fast = bvh.winding_number(p) as f64;
            let exact = bvh.winding_number_with(p, f32::INFINITY) as f64;
            assert!((exact - w).abs() < 2e-3, "{file}: exact sum {exact} vs {w}");
            worst = worst.max((fast - w).abs());
            if (w - 0.5).abs() > 0.05 {
                assert_eq!(
                    bvh.is_inside(p),
                    w >= 0.5,
                    "{file}: occupancy at {p} (w = {w})"
                );
                let (d, _, _) = closest_point_brute(&mesh, p.as_dvec3()).unwrap();
                let want = if w >= 0.5 { -d } else { d };
                let sd = bvh.signed_distance(p) as f64;
                assert!(
                    (sd - want).abs() <= 1e-5 * (1.0 + d.abs()) + 1e-6,
                    "{file}: {sd} vs {want}"
                );
                inside += usize::from(w >= 0.5);
            }
        }
        assert!(worst < 0.03, "{file}: fast winding number off by {worst}");
        assert!(inside > 0, "{file}: no point inside");
    }
}

#[test]
fn all_hits_match_brute_force() {
    for (file, n) in MESHES {
        let mesh = load(file);
        let bvh = SurfaceBvh::build(&mesh);
        let b = mesh.bounds();
        let mut rng = Pcg32::new(3);
        let (mut checked, mut hits) = (0, 0);
        while checked < n {
            let o = rng.in_box(b.min - b.extent(), b.max + b.extent());
            let ray = Ray::new(o, rng.in_box(b.min, b.max) - o);
            let want = ray_hits_brute(&mesh, &ray);
            if want.iter().any(|c| c.margin < 1e-4) {
                continue;
            }
            checked += 1;
            let got = bvh.ray_hits(&ray, usize::MAX);
            assert_eq!(got.len(), want.len(), "{file}: hit count");
            assert_eq!(bvh.count_hits(&ray) as usize, want.len());
            for (g, w) in got.iter().zip(&want) {
                assert!((g.t as f64 - w.t).abs() <= 1e-4 * (1.0 + w.t), "{file}: t");
            }
            hits += want.len();
        }
        assert!(hits > n, "{file}: too few hits");
    }
}
