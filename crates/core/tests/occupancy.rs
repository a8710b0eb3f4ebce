//! Occupancy counted by crossings — one ray through the surface and the
//! cap that closes it, less the cap's solid angle — against the `f64` sum
//! of every triangle's solid angle, on closed, open, duplicated, flipped
//! and overlapping surfaces, a random soup and the shared teapot (open)
//! and bunny; and the crossing classifier against `f64` on rays aimed at
//! edges and corners.

mod query_support;
mod shared_meshes;

use query_support::{random_soup, sphere, transformed, without};
use raykit_core::query::winding::winding_number_brute;
use raykit_core::query::SurfaceBvh;
use raykit_core::rng::Pcg32;
use raykit_core::tri::moller::Moller;
use raykit_core::tri::TriangleTest;
use raykit_core::{Ray, TriangleMesh, Vec3};
use shared_meshes::shared_obj;

/// Points uniform in the box grown by a quarter, and vertices moved by up
/// to a thousandth of the diagonal.
fn points(mesh: &TriangleMesh, n: usize, seed: u64) -> Vec<Vec3> {
    let b = mesh.bounds();
    let (lo, hi) = (b.min, b.max);
    let pad = (hi - lo) * 0.25;
    let diag = (hi - lo).length();
    let mut rng = Pcg32::new(seed);
    let mut out: Vec<Vec3> = (0..n).map(|_| rng.in_box(lo - pad, hi + pad)).collect();
    for _ in 0..n / 2 {
        let v = mesh.positions[rng.below(mesh.positions.len() as u32) as usize];
        out.push(v + rng.unit_vector() * diag * 1e-3 * rng.next_f32());
    }
    out
}

/// Every point's counted winding number, where there is one, within
/// `tol` of the `f64` sum; occupancy right wherever the `f64` winding
/// number is clearly on one side of ½; and most points counted (the sum
/// is the fallback, which must stay rare for the count to be worth it),
/// or none where `counts` is false (a soup, whose cap outweighs it).
fn check(name: &str, mesh: &TriangleMesh, tol: f64, counts: bool) {
    let bvh = SurfaceBvh::build(mesh);
    let pts = points(mesh, 400, 5);
    let mut counted = 0;
    let mut batch = vec![false; pts.len()];
    bvh.inside_batch(&pts, &mut batch);
    for (p, &inside_batch) in pts.iter().zip(&batch) {
        let want = winding_number_brute(mesh, p.as_dvec3());
        if let Some(w) = bvh.winding_number_counted(*p) {
            counted += 1;
            assert!(
                (w as f64 - want).abs() < tol,
                "{name}: counted {w} vs f64 {want} at {p}"
            );
        }
        let inside = bvh.is_inside(*p);
        assert_eq!(
            inside, inside_batch,
            "{name}: batch and single differ at {p}"
        );
        if (want - 0.5).abs() > 0.05 {
            assert_eq!(
                inside,
                want >= 0.5,
                "{name}: inside {inside}, f64 winding number {want} at {p}"
            );
        }
    }
    if counts {
        assert!(
            counted * 10 >= pts.len() * 9,
            "{name}: only {counted} of {} points counted",
            pts.len()
        );
    } else {
        assert_eq!(counted, 0, "{name}: a soup is summed, not counted");
    }
}

#[test]
fn counted_winding_numbers_match_the_f64_sum() {
    let ball = sphere(3);
    let mut duplicated = ball.clone();
    duplicated.indices.push(ball.indices[7]);
    let mut flipped = ball.clone();
    flipped.indices[20].swap(0, 1);
    let mut overlapping = ball.clone();
    let other = transformed(&ball, 0.8, Vec3::new(0.6, 0.1, 0.0));
    let base = overlapping.positions.len() as u32;
    overlapping.positions.extend(&other.positions);
    overlapping
        .indices
        .extend(other.indices.iter().map(|t| t.map(|i| i + base)));
    // Closed surfaces count exactly; open ones carry the cap's fast
    // winding number (within 1% at Barill et al.'s accuracy).
    check("closed sphere", &ball, 1e-4, true);
    check("duplicated triangle", &duplicated, 0.02, true);
    check("flipped triangle", &flipped, 0.02, true);
    check("overlapping spheres", &overlapping, 1e-4, true);
    check("open sphere", &without(&ball, |c| c.y > 0.5), 0.02, true);
    check("random soup", &random_soup(1500, 11), 0.02, false);
    check("teapot", &shared_obj("teapot_992.obj"), 0.02, true);
    check("bunny", &shared_obj("bunny_3674.obj"), 0.02, true);
}

#[test]
fn points_on_the_surface_and_not_finite_do_not_panic() {
    let mesh = shared_obj("teapot_992.obj");
    let bvh = SurfaceBvh::build(&mesh);
    for &p in mesh.positions.iter().take(200) {
        let _ = bvh.is_inside(p);
        let _ = bvh.winding_number_counted(p);
    }
    for p in [
        Vec3::NAN,
        Vec3::INFINITY,
        Vec3::new(0.0, f32::NEG_INFINITY, 1.0),
    ] {
        assert!(!bvh.is_inside(p));
        assert_eq!(bvh.winding_number_counted(p), None);
    }
    let empty = SurfaceBvh::build(&TriangleMesh::default());
    assert_eq!(empty.winding_number_counted(Vec3::ZERO), Some(0.0));
    assert!(!empty.is_inside(Vec3::ZERO));
}

/// `f64` Möller–Trumbore on the `f32` inputs: `Some(side)` when the ray
/// meets the triangle at `t > tnear` (side: `det < 0`), else None.
fn crossing64(tri: &[Vec3; 3], ray: &Ray) -> Option<bool> {
    let [a, b, c] = tri.map(|v| v.as_dvec3());
    let (o, d) = (ray.origin.as_dvec3(), ray.dir().as_dvec3());
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let s = o - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t >= ray.tnear as f64).then_some(det < 0.0)
}

#[test]
fn sure_crossings_agree_with_f64_on_edges_corners_and_interiors() {
    let mut rng = Pcg32::new(17);
    let (mut sure, mut unsure) = (0, 0);
    for i in 0..200_000 {
        let scale = 10f32.powf(rng.range_f32(-2.0, 2.0));
        let at = rng.in_box(Vec3::splat(-100.0), Vec3::splat(100.0));
        let tri = [0, 1, 2].map(|_| at + rng.in_box(Vec3::splat(-scale), Vec3::splat(scale)));
        // Aim at a corner, a point of an edge, or the interior.
        let w = match i % 3 {
            0 => [1.0, 0.0, 0.0],
            1 => {
                let x = rng.next_f32();
                [x, 1.0 - x, 0.0]
            }
            _ => {
                let (x, y) = (rng.next_f32(), rng.next_f32());
                let (x, y) = if x + y > 1.0 {
                    (1.0 - x, 1.0 - y)
                } else {
                    (x, y)
                };
                [x, y, 1.0 - x - y]
            }
        };
        let k = rng.below(3) as usize;
        let target = tri[k] * w[0] + tri[(k + 1) % 3] * w[1] + tri[(k + 2) % 3] * w[2];
        let origin = target + rng.unit_vector() * scale * rng.range_f32(0.1, 1000.0);
        let ray = Ray::new(origin, target - origin);
        let pre = Moller::precompute(tri[0], tri[1], tri[2]);
        let scale_r = Moller::prepare(&ray);
        let got = Moller::crossing::<true>(&pre, &ray, scale_r, f32::INFINITY);
        let want = crossing64(&tri, &ray);
        match got {
            Some(c) if c.sure => {
                sure += 1;
                assert!(c.hit, "sure crossings are hits: {tri:?} {ray:?}");
                assert_eq!(want, Some(c.det < 0.0), "{tri:?} {ray:?}");
            }
            Some(c) => {
                unsure += 1;
                // The textbook answer is always reported.
                let strict = Moller::intersect_strict(&pre, &ray, f32::INFINITY);
                assert_eq!(c.hit, strict.is_some());
            }
            None => assert_eq!(want, None, "dismissed a crossing: {tri:?} {ray:?}"),
        }
    }
    // Interior aims are mostly sure; edges and corners mostly not.
    assert!(
        sure > 50_000 && unsure > 50_000,
        "sure {sure}, unsure {unsure}"
    );
}
