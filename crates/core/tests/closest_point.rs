//! Closest point and unsigned distance against brute force in `f64`: the
//! 8-wide [`SurfaceBvh`] and the generic search through every structure's
//! regions, on random soups and an open sphere; the search radius; points
//! that are not finite.

mod query_support;
mod shared_meshes;

use query_support::{random_soup, sphere, without};
use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::query::closest::{closest_on_triangle64, closest_point_brute, closest_point_in};
use raykit_core::query::{ClosestPoint, SurfaceBvh};
use raykit_core::rng::Pcg32;
use raykit_core::tri::TestKind;
use raykit_core::{TriangleMesh, Vec3};
use shared_meshes::shared_obj;

/// Query points: uniform in a box around the mesh, and near the surface
/// (a random point of a random triangle moved a little off it).
fn query_points(mesh: &TriangleMesh, n: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = Pcg32::new(seed);
    let b = mesh.bounds();
    let pad = b.extent() * 0.5;
    (0..n)
        .map(|i| {
            if i % 2 == 0 {
                rng.in_box(b.min - pad, b.max + pad)
            } else {
                let [a, bb, c] = mesh.triangle(rng.below(mesh.num_triangles() as u32) as usize);
                let (mut u, mut v) = (rng.next_f32(), rng.next_f32());
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                a + (bb - a) * u + (c - a) * v + rng.unit_vector() * 0.01 * rng.next_f32()
            }
        })
        .collect()
}

/// `got` is a right answer for `p`: its distance is the brute-force
/// minimum, and its point is the closest point of the triangle it names,
/// with barycentrics that give that point.
fn check(mesh: &TriangleMesh, p: Vec3, got: Option<ClosestPoint>, what: &str) {
    let p64 = p.as_dvec3();
    let (d_ref, _, _) = closest_point_brute(mesh, p64).expect("non-empty mesh");
    let got = got.unwrap_or_else(|| panic!("{what}: no answer for {p}"));
    // Besides the distance's share, the f32 rounding of coordinates as
    // large as the point's (a few ulps).
    let tol = 1e-5 * (1.0 + d_ref) + 1e-6 * p64.abs().max_element();
    assert!(
        (got.distance as f64 - d_ref).abs() <= tol,
        "{what}: distance {} vs brute {d_ref} at {p}",
        got.distance
    );
    let tri = mesh.triangle(got.prim as usize).map(|c| c.as_dvec3());
    let (q, _, _) = closest_on_triangle64(p64, &tri);
    assert!(
        (q.distance(p64) - d_ref).abs() <= tol,
        "{what}: prim {} is not nearest",
        got.prim
    );
    assert!(
        got.point.as_dvec3().distance(q) <= tol,
        "{what}: point off its triangle's closest point"
    );
    let (u, v) = (got.u as f64, got.v as f64);
    let from_uv = tri[0] * (1.0 - u - v) + tri[1] * u + tri[2] * v;
    assert!(
        from_uv.distance(q) <= 1e-4 * (1.0 + d_ref) + 1e-6 * p64.abs().max_element(),
        "{what}: barycentrics do not give the point"
    );
    assert!(u >= 0.0 && v >= 0.0 && u + v <= 1.0 + 1e-6);
}

#[test]
fn surface_bvh_matches_brute_force_on_random_soups() {
    for seed in 1..4 {
        let mesh = random_soup(3000, seed);
        let bvh = SurfaceBvh::build(&mesh);
        let pts = query_points(&mesh, 400, seed + 10);
        let mut batch = vec![None; pts.len()];
        bvh.closest_points(&pts, f32::INFINITY, &mut batch);
        for (p, b) in pts.iter().zip(&batch) {
            let one = bvh.closest_point(*p, f32::INFINITY);
            assert_eq!(one, *b, "batch and single answers differ");
            check(&mesh, *p, one, "surface bvh");
            let d = bvh.distance(*p);
            assert_eq!(Some(d), one.map(|c| c.distance));
        }
    }
}

/// Meshes far larger than a unit, whose f32 products in Ericson's test
/// overflowed (a panic through `clamp`): answered as brute force in f64.
#[test]
fn huge_meshes_match_brute_force() {
    for scale in [1e6f32, 1e10, 1e15, 1e18] {
        let mesh = query_support::transformed(&random_soup(300, 8), scale, Vec3::ZERO);
        let bvh = SurfaceBvh::build(&mesh);
        let pts = query_points(&mesh, 200, 31);
        let mut batch = vec![None; pts.len()];
        bvh.closest_points(&pts, f32::INFINITY, &mut batch);
        for (p, b) in pts.iter().zip(&batch) {
            check(&mesh, *p, *b, &format!("scale {scale}"));
        }
    }
}

/// Batches larger than one task are answered in Morton order, each search
/// bounded by the previous point's triangle: on a real mesh (shared
/// corners and edges, so ties between triangles) with points that are not
/// finite mixed in, every batch answer is a right one and has the distance
/// of the single query.
#[test]
fn large_batches_answer_as_single_queries() {
    let bunny = shared_obj("bunny_3674.obj");
    let bvh = SurfaceBvh::build(&bunny);
    let mut pts = query_points(&bunny, 5000, 21);
    for i in (0..pts.len()).step_by(97) {
        pts[i] = Vec3::new(f32::NAN, 0.0, f32::INFINITY * (i % 2) as f32);
    }
    let mut batch = vec![None; pts.len()];
    bvh.closest_points(&pts, f32::INFINITY, &mut batch);
    let mut dists = vec![0.0; pts.len()];
    bvh.distances(&pts, &mut dists);
    for (i, (p, b)) in pts.iter().zip(&batch).enumerate() {
        let one = bvh.closest_point(*p, f32::INFINITY);
        if !p.is_finite() {
            assert!(b.is_none() && dists[i].is_nan(), "point {i} is not finite");
            continue;
        }
        let (one, got) = (one.unwrap(), b.unwrap());
        assert!(
            (one.distance - got.distance).abs() <= 1e-6 * (1.0 + one.distance),
            "point {i}: batch {} vs single {}",
            got.distance,
            one.distance
        );
        assert_eq!(
            dists[i], got.distance,
            "point {i}: distances() vs closest_points()"
        );
        if i % 10 == 1 {
            check(&bunny, *p, Some(got), "bunny batch");
        }
    }
}

#[test]
fn every_structure_finds_the_closest_point() {
    let mesh = random_soup(1500, 7);
    let pts = query_points(&mesh, 150, 8);
    let opts = BuildOptions::default();
    for kind in AccelKind::ALL {
        let accel = build_accel(kind, TestKind::Moller, &mesh, &opts);
        for p in &pts {
            check(
                &mesh,
                *p,
                closest_point_in(accel.as_ref(), &mesh, *p, f32::INFINITY),
                kind.name(),
            );
        }
    }
}

#[test]
fn open_sphere_matches_brute_force() {
    // A sphere with a cap cut off: inner points near the hole are nearest
    // to the rim.
    let mesh = without(&sphere(4), |c| c.y > 0.6);
    let bvh = SurfaceBvh::build(&mesh);
    let mut rng = Pcg32::new(5);
    for _ in 0..400 {
        let p = rng.in_box(Vec3::splat(-1.5), Vec3::splat(1.5));
        check(&mesh, p, bvh.closest_point(p, f32::INFINITY), "open sphere");
    }
}

#[test]
fn search_radius_limits_the_answer() {
    let mesh = random_soup(2000, 11);
    let bvh = SurfaceBvh::build(&mesh);
    for p in query_points(&mesh, 300, 12) {
        let (d_ref, _, _) = closest_point_brute(&mesh, p.as_dvec3()).unwrap();
        let inside = (d_ref * 1.001 + 1e-6) as f32;
        let outside = (d_ref * 0.999 - 1e-6) as f32;
        check(
            &mesh,
            p,
            bvh.closest_point(p, inside),
            "radius above the distance",
        );
        if outside >= 0.0 {
            assert_eq!(
                bvh.closest_point(p, outside),
                None,
                "radius below the distance"
            );
        }
    }
}

#[test]
fn points_that_are_not_finite_have_no_closest_point() {
    let mesh = random_soup(200, 3);
    let bvh = SurfaceBvh::build(&mesh);
    let accel = build_accel(
        AccelKind::Bvh8,
        TestKind::Moller,
        &mesh,
        &BuildOptions::default(),
    );
    for p in [
        Vec3::new(f32::NAN, 0.5, 0.5),
        Vec3::new(0.5, f32::INFINITY, 0.5),
        Vec3::splat(f32::NEG_INFINITY),
    ] {
        assert_eq!(bvh.closest_point(p, f32::INFINITY), None);
        assert!(bvh.distance(p).is_nan());
        assert_eq!(
            closest_point_in(accel.as_ref(), &mesh, p, f32::INFINITY),
            None
        );
    }
    assert_eq!(bvh.closest_point(Vec3::ZERO, f32::NAN), None);
    assert_eq!(bvh.closest_point(Vec3::ZERO, -1.0), None);
    let empty = SurfaceBvh::build(&TriangleMesh::default());
    assert_eq!(empty.closest_point(Vec3::ZERO, f32::INFINITY), None);
    assert_eq!(empty.distance(Vec3::ZERO), f32::INFINITY);
}
