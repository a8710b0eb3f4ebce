//! Triangles without area (collinear corners, as CAD tessellations leave
//! them) are left out of the packed leaves of the wide BVHs over Möller,
//! since no ray can hit them: the rays' answers stay brute force's, the
//! region queries still find them, a saved tree keeps them out, and a
//! refit that gives one of them area rebuilds the tree.

mod shared_meshes;
mod soup;

use raykit_core::accel::{Accel, BruteForce, BuildOptions, Bvh4, Bvh8};
use raykit_core::query::triangles_in_box;
use raykit_core::rng::Pcg32;
use raykit_core::tri::Moller;
use raykit_core::{glam, Aabb, Ray, TriangleMesh, Vec3};
use shared_meshes::{agree, bits, rays};
use std::path::PathBuf;

/// A wavy grid of `n`² quads, then slivers on it: triangles repeating a
/// corner, and triangles of three points on one line parallel to an axis
/// (so the differences of their corners, and their cross product, are
/// exactly zero in `f32`), some short, some across the whole grid.
fn grid_with_slivers(n: usize, seed: u64) -> TriangleMesh {
    let mut rng = Pcg32::new(seed);
    let TriangleMesh {
        mut positions,
        mut indices,
        ..
    } = soup::grid(n, || 0.1 * rng.next_f32());
    let grid = positions.len() as u32;
    for k in 0..(n * n / 3) as u32 {
        let a = rng.below(grid);
        let b = rng.below(grid);
        indices.push(if k % 2 == 0 { [a, a, b] } else { [a, b, b] });
    }
    for k in 0..40 {
        let y = 0.02 + 0.1 * rng.next_f32();
        let z = rng.next_f32();
        let (x0, len) = if k % 4 == 0 {
            (0.0, 1.0)
        } else {
            (rng.next_f32() * 0.8, 0.05)
        };
        let first = positions.len() as u32;
        for t in [0.0, 0.5, 1.0] {
            positions.push(Vec3::new(x0 + t * len, y, z));
        }
        indices.push([first, first + 1, first + 2]);
    }
    TriangleMesh::new(positions, indices)
}

/// The triangles whose corners are collinear, computed apart from the
/// library: the cross product of the corners' differences in `f64`.
fn without_area(mesh: &TriangleMesh) -> Vec<u32> {
    (0..mesh.num_triangles())
        .filter(|&i| {
            let [a, b, c] = mesh.triangle(i).map(|v| v.as_dvec3());
            (b - a).cross(c - a) == glam::DVec3::ZERO
        })
        .map(|i| i as u32)
        .collect()
}

/// The rays of `shared_meshes::rays`, and rays aimed at each sliver's
/// corners and midpoints from above, below and along its line.
fn rays_at_slivers(mesh: &TriangleMesh, slivers: &[u32]) -> Vec<Ray> {
    let mut out = rays(mesh, 4000, 9);
    for &i in slivers {
        let [a, b, c] = mesh.triangle(i as usize);
        for p in [a, b, c, (a + c) * 0.5, (a + b) * 0.5] {
            for from in [Vec3::Y, -Vec3::Y, Vec3::new(0.3, 1.0, 0.2)] {
                out.push(Ray::new(p + from, -from));
            }
            let along = (c - a).normalize_or_zero();
            if along != Vec3::ZERO {
                out.push(Ray::new(p - along * 2.0, along));
            }
        }
    }
    out
}

fn same_as_brute(accel: &dyn Accel, mesh: &TriangleMesh, rays: &[Ray]) {
    let brute = BruteForce::<Moller>::new(mesh);
    let mut hits = 0;
    for ray in rays {
        let (got, want) = (accel.intersect(ray), brute.intersect(ray));
        assert!(agree(got, want), "{ray:?}: {got:?} against {want:?}");
        assert_eq!(accel.occluded(ray), brute.occluded(ray), "{ray:?}");
        hits += got.is_some() as usize;
    }
    let mut batch = vec![None; rays.len()];
    accel.intersect_batch(rays, &mut batch);
    for (ray, (one, many)) in rays
        .iter()
        .zip(rays.iter().map(|r| accel.intersect(r)).zip(batch))
    {
        assert_eq!(bits(one), bits(many), "{ray:?}");
    }
    assert!(hits > rays.len() / 10, "{hits} hits of {} rays", rays.len());
}

/// Every triangle the regions report, once each at least.
fn reported(accel: &dyn Accel) -> Vec<u32> {
    let mut seen = Vec::new();
    accel.visit_regions(&mut |_| true, &mut |tris| seen.extend_from_slice(tris));
    seen.sort_unstable();
    seen.dedup();
    seen
}

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("unhittable_triangles");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn slivers_are_left_out_and_rays_answer_as_brute_force() {
    let mesh = grid_with_slivers(40, 3);
    let slivers = without_area(&mesh);
    assert!(slivers.len() > 500, "{} slivers", slivers.len());
    let rays = rays_at_slivers(&mesh, &slivers);
    for options in [
        BuildOptions::default(),
        BuildOptions::best(),
        BuildOptions::fast(),
    ] {
        let bvh8 = Bvh8::<Moller>::build(&mesh, &options);
        let bvh4 = Bvh4::<Moller>::build(&mesh, &options);
        for accel in [&bvh8 as &dyn Accel, &bvh4] {
            assert_eq!(
                accel.stats().triangle_refs,
                mesh.num_triangles() - slivers.len()
            );
            same_as_brute(accel, &mesh, &rays);
            let all: Vec<u32> = (0..mesh.num_triangles() as u32).collect();
            assert_eq!(reported(accel), all);
        }
    }
}

#[test]
fn box_queries_find_the_slivers() {
    let mesh = grid_with_slivers(24, 5);
    let bvh = Bvh8::<Moller>::build(&mesh, &BuildOptions::default());
    let brute = BruteForce::<Moller>::new(&mesh);
    let slivers = without_area(&mesh);
    let mut found = 0;
    for (k, &i) in slivers.iter().enumerate().step_by(7) {
        let [a, b, c] = mesh.triangle(i as usize);
        let p = [a, b, c][k % 3];
        let query = Aabb::new(p - Vec3::splat(0.01), p + Vec3::splat(0.01));
        let got = triangles_in_box(&bvh, &mesh, &query);
        assert_eq!(got, triangles_in_box(&brute, &mesh, &query), "{query:?}");
        assert!(got.contains(&i), "sliver {i} not in the box query at {p}");
        found += 1;
    }
    assert!(found > 20, "{found} queries");
}

#[test]
fn a_saved_tree_keeps_its_slivers_out() {
    let mesh = grid_with_slivers(30, 7);
    let slivers = without_area(&mesh);
    let built = Bvh8::<Moller>::build(&mesh, &BuildOptions::default());
    let path = scratch("slivers.rkb");
    built.save(&path, &mesh).unwrap();
    let loaded = Bvh8::<Moller>::load(&path, &mesh).unwrap();
    assert_eq!(loaded.stats().triangle_refs, built.stats().triangle_refs);
    let rays = rays_at_slivers(&mesh, &slivers);
    for ray in &rays {
        assert_eq!(
            bits(built.intersect(ray)),
            bits(loaded.intersect(ray)),
            "{ray:?}"
        );
    }
    assert_eq!(reported(&loaded), reported(&built));

    // The same counts of triangles and vertices, one sliver given area: the
    // file is not this mesh's tree.
    let mut other = mesh.clone();
    let i = slivers[slivers.len() - 1] as usize;
    let corner = other.indices[i][1] as usize;
    other.positions[corner].y += 0.05;
    assert!(Bvh8::<Moller>::load(&path, &other).is_err());
}

#[test]
fn a_refit_keeps_slivers_out_until_one_gains_area() {
    let mesh = grid_with_slivers(30, 11);
    let slivers = without_area(&mesh);
    let mut bvh = Bvh8::<Moller>::build(&mesh, &BuildOptions::default());

    // Every vertex lifted alike: the slivers stay slivers.
    let mut lifted = mesh.clone();
    for p in &mut lifted.positions {
        p.y += 0.25;
    }
    let report = bvh.refit(&lifted).unwrap();
    assert!(!report.rebuilt);
    assert_eq!(
        bvh.stats().triangle_refs,
        mesh.num_triangles() - slivers.len()
    );
    same_as_brute(&bvh, &lifted, &rays_at_slivers(&lifted, &slivers));

    // The last sliver's middle corner raised high above the grid: it is a
    // triangle now, upright, which rays hit, so the tree is built again
    // with it in a leaf.
    let mut raised = lifted.clone();
    let last = *slivers.last().unwrap() as usize;
    let middle = raised.indices[last][1] as usize;
    raised.positions[middle].y += 2.0;
    assert_eq!(without_area(&raised).len(), slivers.len() - 1);
    let report = bvh.refit(&raised).unwrap();
    assert!(report.rebuilt);
    assert_eq!(
        bvh.stats().triangle_refs,
        mesh.num_triangles() - slivers.len() + 1
    );
    let [a, b, c] = raised.triangle(last);
    let at = (a + b + c) / 3.0;
    let across = Ray::new(at - Vec3::Z, Vec3::Z);
    let brute = BruteForce::<Moller>::new(&raised);
    assert_eq!(brute.intersect(&across).map(|h| h.prim), Some(last as u32));
    assert_eq!(bvh.intersect(&across).map(|h| h.prim), Some(last as u32));
    same_as_brute(&bvh, &raised, &rays_at_slivers(&raised, &slivers));
}
