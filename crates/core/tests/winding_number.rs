//! Generalized winding number, occupancy and signed distance against `f64`
//! brute force, and the cases where the parity of one ray's crossings is
//! wrong while the winding number is right: a mesh with a hole, a
//! duplicated triangle, and two overlapping closed surfaces.

mod query_support;

use query_support::{centroid, random_soup, sphere, transformed, without};
use raykit_core::query::closest::closest_point_brute;
use raykit_core::query::winding::winding_number_brute;
use raykit_core::query::SurfaceBvh;
use raykit_core::rng::Pcg32;
use raykit_core::{Ray, TriangleMesh, Vec3};

/// Inside by the parity of the crossings of one ray from `p` along `dir`
/// (what Open3D's `compute_occupancy` and signed distance do).
fn parity_inside(bvh: &SurfaceBvh, p: Vec3, dir: Vec3) -> bool {
    bvh.count_hits(&Ray::new(p, dir)) % 2 == 1
}

#[test]
fn fast_winding_number_matches_the_exact_sum() {
    // Points within `reach` of the origin; the large meshes (and their far
    // points) overflowed f32 in the far field's powers of the distance.
    let meshes = [
        ("closed sphere", sphere(4), 2.0),
        ("open sphere", without(&sphere(4), |c| c.y > 0.5), 2.0),
        (
            "random soup",
            transformed(&random_soup(2000, 4), 2.0, Vec3::splat(-1.0)),
            2.0,
        ),
        (
            "closed sphere × 1e6",
            transformed(&sphere(4), 1e6, Vec3::ZERO),
            2e7,
        ),
        (
            "open sphere × 1e12",
            transformed(&without(&sphere(4), |c| c.y > 0.5), 1e12, Vec3::ZERO),
            2e12,
        ),
    ];
    let mut rng = Pcg32::new(9);
    for (name, mesh, reach) in &meshes {
        let bvh = SurfaceBvh::build(mesh);
        let pts: Vec<Vec3> = (0..300)
            .map(|_| rng.in_box(Vec3::splat(-reach), Vec3::splat(*reach)))
            .collect();
        let mut batch = vec![0.0; pts.len()];
        bvh.winding_numbers(&pts, &mut batch);
        for (p, &wb) in pts.iter().zip(&batch) {
            let want = winding_number_brute(mesh, p.as_dvec3());
            let exact = bvh.winding_number_with(*p, f32::INFINITY) as f64;
            let fast = bvh.winding_number(*p) as f64;
            assert_eq!(wb as f64, fast, "{name} at {p}");
            assert!(
                (exact - want).abs() < 1e-3,
                "{name}: exact sum {exact} vs {want} at {p}"
            );
            assert!(
                (fast - want).abs() < 0.01,
                "{name}: beta = 2 gives {fast} vs {want} at {p}"
            );
        }
    }
}

#[test]
fn closed_sphere_inside_outside_and_signed_distance() {
    let mesh = transformed(&sphere(4), 0.7, Vec3::new(3.0, -2.0, 1.0));
    let center = Vec3::new(3.0, -2.0, 1.0);
    let bvh = SurfaceBvh::build(&mesh);
    let mut rng = Pcg32::new(2);
    let mut checked = 0;
    for _ in 0..1000 {
        let p = center + rng.in_box(Vec3::splat(-1.2), Vec3::splat(1.2));
        let w = winding_number_brute(&mesh, p.as_dvec3());
        let (d, _, _) = closest_point_brute(&mesh, p.as_dvec3()).unwrap();
        if (w - 0.5).abs() < 0.05 {
            continue;
        }
        checked += 1;
        let inside = w >= 0.5;
        assert_eq!(bvh.is_inside(p), inside, "at {p}: brute winding {w}");
        let sd = bvh.signed_distance(p) as f64;
        let want = if inside { -d } else { d };
        assert!(
            (sd - want).abs() <= 1e-5 * (1.0 + d),
            "signed distance {sd} vs {want}"
        );
        // Away from the polygonal surface, the reference agrees with the
        // round sphere.
        let r = (p - center).length();
        if (r - 0.7).abs() > 0.02 {
            assert_eq!(inside, r < 0.7);
        }
    }
    assert!(checked > 900);
    let mut sd = vec![0.0; 3];
    let mut ins = vec![false; 3];
    let pts = [center, center + Vec3::X * 2.0, Vec3::NAN];
    bvh.signed_distances(&pts, &mut sd);
    bvh.inside_batch(&pts, &mut ins);
    assert!(sd[0] < 0.0 && sd[1] > 0.0 && sd[2].is_nan());
    assert_eq!(ins, [true, false, false]);
    assert!(bvh
        .winding_number(Vec3::new(f32::INFINITY, 0.0, 0.0))
        .is_nan());
}

#[test]
fn ray_parity_fails_through_a_hole_where_the_winding_number_is_right() {
    // The unit sphere with the cap above y = 0.8 cut away (an open mesh,
    // like scanned models with holes). Points well inside, rays up through
    // the hole: no crossing, parity says outside.
    let mesh = without(&sphere(4), |c| c.y > 0.8);
    let bvh = SurfaceBvh::build(&mesh);
    let mut rng = Pcg32::new(13);
    let mut parity_wrong = 0;
    for _ in 0..200 {
        let p = rng.in_box(Vec3::splat(-0.3), Vec3::splat(0.3));
        let w = winding_number_brute(&mesh, p.as_dvec3());
        assert!(w > 0.6, "the brute-force winding number says inside ({w})");
        assert!(bvh.is_inside(p), "winding number occupancy at {p}");
        assert!(bvh.signed_distance(p) < 0.0);
        if !parity_inside(&bvh, p, Vec3::Y) {
            parity_wrong += 1;
        }
    }
    assert_eq!(
        parity_wrong, 200,
        "every ray up through the hole has even parity"
    );
}

#[test]
fn ray_parity_fails_on_a_duplicated_triangle_where_the_winding_number_is_right() {
    // A closed sphere with one triangle stored twice (common in meshes
    // merged from parts): a ray through it crosses the surface "twice".
    let base = sphere(3);
    let mut mesh = base.clone();
    let dup = 17;
    mesh.indices.push(mesh.indices[dup]);
    let bvh = SurfaceBvh::build(&mesh);
    let p = Vec3::new(0.05, -0.1, 0.02);
    let dir = (centroid(&mesh, dup) - p).normalize();
    assert_eq!(bvh.count_hits(&Ray::new(p, dir)), 2);
    assert!(!parity_inside(&bvh, p, dir), "parity says outside");
    let w = winding_number_brute(&mesh, p.as_dvec3());
    assert!(w > 0.9, "brute-force winding number {w}");
    assert!(bvh.is_inside(p));
    assert!(bvh.signed_distance(p) < 0.0);
}

#[test]
fn ray_parity_fails_in_overlapping_closed_surfaces_where_the_winding_number_is_right() {
    // Two closed spheres that overlap (a self-intersecting union, as CAD
    // exports of touching parts): in the overlap a ray crosses both, twice.
    let mut mesh = sphere(3);
    mesh.append(&transformed(&sphere(3), 1.0, Vec3::new(1.0, 0.0, 0.0)));
    let bvh = SurfaceBvh::build(&mesh);
    let p = Vec3::new(0.5, 0.01, 0.02);
    let dir = Vec3::new(0.1, 1.0, 0.2);
    assert_eq!(bvh.count_hits(&Ray::new(p, dir)), 2);
    assert!(!parity_inside(&bvh, p, dir));
    let w = winding_number_brute(&mesh, p.as_dvec3());
    assert!((w - 2.0).abs() < 0.01, "brute-force winding number {w}");
    assert!(bvh.is_inside(p) && (bvh.winding_number(p) - 2.0).abs() < 0.02);
    // Outside both, still outside.
    assert!(!bvh.is_inside(Vec3::new(0.5, 1.2, 0.0)));
}

#[test]
fn empty_mesh_has_nothing_inside() {
    let bvh = SurfaceBvh::build(&TriangleMesh::default());
    assert_eq!(bvh.winding_number(Vec3::ZERO), 0.0);
    assert!(!bvh.is_inside(Vec3::ZERO));
    assert_eq!(bvh.signed_distance(Vec3::ZERO), f32::INFINITY);
}
