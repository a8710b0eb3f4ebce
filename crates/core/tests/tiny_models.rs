//! A model far smaller than a unit answers as the same model at unit size.
//! The Stanford bunny of the shared data, brought to unit size, is shrunk
//! by `2^-e` (exact in `f32`), and every query on it, through every
//! structure, the point and multi-hit queries, an instanced scene and a
//! saved structure, must give the unit model's answers times `2^-e` bit
//! for bit; nearest hits and distances are also checked against brute
//! force in `f64` on the tiny model itself. Without the unit scaling the
//! ray tests' products of coordinates underflow: at `2^-60` hits are
//! lost, and from `2^-30` distances are off by up to 0.8% of the model.

mod query_support;
mod shared_meshes;

use raykit_core::accel::{build_accel, load_accel, AccelKind, BuildOptions};
use raykit_core::glam::Affine3A;
use raykit_core::instancing::SceneBuilder;
use raykit_core::query::all_hits::ray_hits_brute;
use raykit_core::query::closest::closest_point_brute;
use raykit_core::query::{triangles_in_box, ClosestPoint, SurfaceBvh};
use raykit_core::rng::Pcg32;
use raykit_core::tri::TestKind;
use raykit_core::{Aabb, Hit, Ray, TriangleMesh, Vec3};
use shared_meshes::shared_obj;

/// The exponents tried: the unit model's coordinates, rays and distances
/// stay normal `f32` numbers at each (so shrinking is exact).
const EXPONENTS: [i32; 3] = [30, 60, 90];

/// The bunny at unit size: the largest side of its box in `[1, 2)` and
/// every coordinate in `[1.5, 3.5)`, away from zero so that no coordinate
/// becomes subnormal when shrunk.
fn unit_bunny() -> TriangleMesh {
    let mut mesh = shared_obj("bunny_3674.obj");
    let b = mesh.bounds();
    let side = (b.max - b.min).max_element();
    let s = 2f32.powi(-side.log2().floor() as i32);
    for p in &mut mesh.positions {
        *p = (*p - b.min) * s + Vec3::splat(1.5);
    }
    let b = mesh.bounds();
    assert!((1.0..2.0).contains(&(b.max - b.min).max_element()));
    mesh
}

fn shrunk(mesh: &TriangleMesh, f: f32) -> TriangleMesh {
    let mut m = mesh.clone();
    for p in &mut m.positions {
        *p *= f;
    }
    m
}

/// Rays from a sphere of radius 2 around the centre of `mesh`'s box
/// towards random points of the box, half of them segments.
fn rays(mesh: &TriangleMesh, n: usize) -> Vec<Ray> {
    let mut rng = Pcg32::new(7);
    let b = mesh.bounds();
    let c = (b.min + b.max) / 2.0;
    (0..n)
        .map(|i| {
            let o = c + rng.unit_vector() * 2.0;
            let target = rng.in_box(b.min, b.max);
            let d = (target - o).normalize();
            if i % 2 == 0 {
                Ray::new(o, d)
            } else {
                Ray::segment(o, d, 0.25, 2.0 + rng.next_f32())
            }
        })
        .collect()
}

fn shrink_ray(r: &Ray, f: f32) -> Ray {
    Ray::segment(r.origin * f, r.dir(), r.tnear * f, r.tfar * f)
}

/// Points uniform in the box grown by a quarter, and points near the
/// surface.
fn points(mesh: &TriangleMesh, n: usize) -> Vec<Vec3> {
    let mut rng = Pcg32::new(11);
    (0..n)
        .map(|i| {
            if i % 2 == 0 {
                rng.in_box(Vec3::splat(1.25), Vec3::splat(3.75))
            } else {
                let [a, b, c] = mesh.triangle(rng.below(mesh.num_triangles() as u32) as usize);
                (a + b + c) / 3.0 + rng.unit_vector() * 0.02 * rng.next_f32()
            }
        })
        .collect()
}

fn shrink_hit(h: Option<Hit>, f: f32) -> Option<Hit> {
    h.map(|h| Hit { t: h.t * f, ..h })
}

#[test]
fn every_structure_answers_a_tiny_model_as_at_unit_size() {
    let unit = unit_bunny();
    let rays = rays(&unit, 2_000);
    let options = BuildOptions::default();
    for kind in AccelKind::ALL {
        for test in [TestKind::Moller, TestKind::Plucker] {
            let at_unit = build_accel(kind, test, &unit, &options);
            let want: Vec<Option<Hit>> = rays.iter().map(|r| at_unit.intersect(r)).collect();
            let want_occ: Vec<bool> = rays.iter().map(|r| at_unit.occluded(r)).collect();
            assert!(want.iter().filter(|h| h.is_some()).count() > 500);
            for e in EXPONENTS {
                let f = 2f32.powi(-e);
                let tiny = shrunk(&unit, f);
                let accel = build_accel(kind, test, &tiny, &options);
                let small: Vec<Ray> = rays.iter().map(|r| shrink_ray(r, f)).collect();
                let what = format!("{kind:?} {test:?} 2^-{e}");
                for (i, r) in small.iter().enumerate() {
                    assert_eq!(accel.intersect(r), shrink_hit(want[i], f), "{what} ray {i}");
                    assert_eq!(accel.occluded(r), want_occ[i], "{what} ray {i}");
                }
                let mut hits = vec![None; small.len()];
                accel.intersect_batch(&small, &mut hits);
                let mut occ = vec![false; small.len()];
                accel.occluded_batch(&small, &mut occ);
                for i in 0..small.len() {
                    assert_eq!(hits[i], shrink_hit(want[i], f), "{what} batch ray {i}");
                    assert_eq!(occ[i], want_occ[i], "{what} batch ray {i}");
                }
                // Regions come back in the model's units.
                let query = Aabb::new(Vec3::splat(2.0), Vec3::new(2.6, 3.0, 2.4));
                let small_query = Aabb::new(query.min * f, query.max * f);
                assert_eq!(
                    triangles_in_box(accel.as_ref(), &tiny, &small_query),
                    triangles_in_box(at_unit.as_ref(), &unit, &query),
                    "{what}"
                );
            }
        }
    }
}

#[test]
fn nearest_hits_on_a_tiny_model_match_brute_force_in_f64() {
    let unit = unit_bunny();
    for e in EXPONENTS {
        let f = 2f32.powi(-e);
        let tiny = shrunk(&unit, f);
        let accel = build_accel(
            AccelKind::Bvh8,
            TestKind::Moller,
            &tiny,
            &BuildOptions::default(),
        );
        let mut checked = 0;
        for r in rays(&unit, 1_000).iter().map(|r| shrink_ray(r, f)) {
            let brute = ray_hits_brute(&tiny, &r);
            let got = accel.intersect(&r);
            // Rays whose nearest crossing is clearly inside its triangle, beyond
            // the tolerance band (`MAX_EDGE_TOLERANCE`) of its neighbours.
            match brute.first() {
                None => assert_eq!(got, None, "2^-{e}"),
                Some(c) if c.margin > 0.02 => {
                    let h = got.unwrap_or_else(|| panic!("2^-{e}: a hit at t {} lost", c.t));
                    assert_eq!(
                        h.prim,
                        c.prim,
                        "2^-{e}: {h:?} {:?}",
                        &brute[..brute.len().min(3)]
                    );
                    assert!(((h.t as f64) - c.t).abs() <= 1e-5 * c.t, "2^-{e}");
                    checked += 1;
                }
                Some(_) => {}
            }
        }
        assert!(checked > 300, "2^-{e}: {checked}");
    }
}

/// Closest points, signed distances and occupancy of `pts`.
fn point_answers(
    bvh: &SurfaceBvh,
    pts: &[Vec3],
) -> (Vec<Option<ClosestPoint>>, Vec<f32>, Vec<bool>) {
    let mut closest = vec![None; pts.len()];
    bvh.closest_points(pts, f32::INFINITY, &mut closest);
    let mut signed = vec![0f32; pts.len()];
    bvh.signed_distances(pts, &mut signed);
    let mut inside = vec![false; pts.len()];
    bvh.inside_batch(pts, &mut inside);
    (closest, signed, inside)
}

#[test]
fn point_and_multi_hit_queries_answer_a_tiny_model_as_at_unit_size() {
    let unit = unit_bunny();
    let at_unit = SurfaceBvh::build(&unit);
    let pts = points(&unit, 1_500);
    let rays = rays(&unit, 1_000);
    let (want_closest, want_signed, want_inside) = point_answers(&at_unit, &pts);
    let mut want_counts = vec![0u32; rays.len()];
    at_unit.count_hits_batch(&rays, &mut want_counts);
    let want_lists = at_unit.ray_hits_batch(&rays, 4);
    assert!(want_inside.iter().any(|&x| x) && want_inside.iter().any(|&x| !x));
    for e in EXPONENTS {
        let f = 2f32.powi(-e);
        let tiny = shrunk(&unit, f);
        let bvh = SurfaceBvh::build(&tiny);
        let what = format!("2^-{e}");
        assert_eq!(bvh.bounds().min, unit.bounds().min * f, "{what}");
        let small: Vec<Vec3> = pts.iter().map(|p| *p * f).collect();
        let (closest, signed, inside) = point_answers(&bvh, &small);
        for (i, p) in small.iter().enumerate() {
            let (got, want) = (closest[i].unwrap(), want_closest[i].unwrap());
            assert_eq!(got.distance, want.distance * f, "{what} point {i}");
            assert_eq!(got.point, want.point * f, "{what} point {i}");
            assert_eq!((got.prim, got.u, got.v), (want.prim, want.u, want.v));
            assert_eq!(signed[i], want_signed[i] * f, "{what} point {i}");
            assert_eq!(inside[i], want_inside[i], "{what} point {i}");
            // A single search may name the other triangle of a tie.
            let single = bvh.closest_point(*p, f32::INFINITY).unwrap();
            assert_eq!((single.point, single.distance), (got.point, got.distance));
            assert_eq!(
                bvh.winding_number(*p),
                at_unit.winding_number(pts[i]),
                "{what}"
            );
            // The search radius is in the model's units too.
            let r = want.distance * f * 1.5;
            assert_eq!(
                bvh.closest_point(*p, r).map(|c| c.distance),
                Some(got.distance)
            );
            assert_eq!(bvh.closest_point(*p, want.distance * f * 0.5), None);
            if i % 10 == 0 {
                let (d, _, _) = closest_point_brute(&tiny, p.as_dvec3()).unwrap();
                assert!(
                    (got.distance as f64 - d).abs() <= 1e-5 * d + 1e-6 * (f as f64),
                    "{what}: distance {} against brute force {d}",
                    got.distance
                );
            }
        }
        let small_rays: Vec<Ray> = rays.iter().map(|r| shrink_ray(r, f)).collect();
        let mut counts = vec![0u32; small_rays.len()];
        bvh.count_hits_batch(&small_rays, &mut counts);
        assert_eq!(counts, want_counts, "{what}");
        let lists = bvh.ray_hits_batch(&small_rays, 4);
        for (i, r) in small_rays.iter().enumerate() {
            let want: Vec<Hit> = want_lists[i]
                .iter()
                .map(|h| Hit { t: h.t * f, ..*h })
                .collect();
            assert_eq!(lists[i], want, "{what} ray {i}");
            assert_eq!(bvh.ray_hits(r, 4), want, "{what} ray {i}");
            assert_eq!(bvh.count_hits(r), want_counts[i], "{what} ray {i}");
            let first = bvh.any_hit(r, |h| h.prim % 2 == 0);
            assert_eq!(
                first.map(|h| h.prim % 2),
                at_unit
                    .any_hit(&rays[i], |h| h.prim % 2 == 0)
                    .map(|h| h.prim % 2)
            );
        }
    }
}

#[test]
fn an_instanced_tiny_geometry_and_a_saved_tiny_structure_answer_as_at_unit_size() {
    let unit = unit_bunny();
    let rays = rays(&unit, 1_000);
    let options = BuildOptions::default();
    let at_unit = build_accel(AccelKind::Bvh8, TestKind::Moller, &unit, &options);
    let want: Vec<Option<Hit>> = rays.iter().map(|r| at_unit.intersect(r)).collect();
    let dir = std::env::temp_dir().join(format!("raykit-tiny-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for e in EXPONENTS {
        let f = 2f32.powi(-e);
        let tiny = shrunk(&unit, f);
        let small: Vec<Ray> = rays.iter().map(|r| shrink_ray(r, f)).collect();
        let mut builder = SceneBuilder::new();
        let g = builder.add_geometry(tiny.clone()).unwrap();
        builder.add_instance(g, Affine3A::IDENTITY).unwrap();
        let scene = builder.build(&options);
        let mut batch = vec![None; small.len()];
        scene.intersect_batch(&small, u32::MAX, &mut batch);
        for (i, r) in small.iter().enumerate() {
            let got = scene.intersect(r, u32::MAX).map(|h| (h.t, h.prim));
            let expect = want[i].map(|h| (h.t * f, h.prim));
            assert_eq!(got, expect, "2^-{e} ray {i}");
            assert_eq!(batch[i].map(|h| (h.t, h.prim)), expect, "2^-{e} ray {i}");
        }
        // Saved and loaded again over the tiny model.
        let accel = build_accel(AccelKind::Bvh8, TestKind::Moller, &tiny, &options);
        let path = dir.join(format!("tiny{e}.rkbvh"));
        accel.save(&path, &tiny).unwrap();
        let (_, _, loaded) = load_accel(&path, &tiny).unwrap();
        for (i, r) in small.iter().enumerate() {
            assert_eq!(
                loaded.intersect(r),
                shrink_hit(want[i], f),
                "2^-{e} ray {i}"
            );
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A vertex that no triangle uses, at unit distance from a tiny model (as
/// exporters leave them), does not keep the model at its own size: the
/// structures and the point queries still answer as at unit size.
#[test]
fn a_far_vertex_no_triangle_uses_does_not_keep_a_tiny_model_unscaled() {
    let unit = unit_bunny();
    let rays = rays(&unit, 1_000);
    let pts = points(&unit, 500);
    let options = BuildOptions::default();
    let at_unit = build_accel(AccelKind::Bvh8, TestKind::Moller, &unit, &options);
    let surface_at_unit = SurfaceBvh::build(&unit);
    let e = 60;
    let f = 2f32.powi(-e);
    let mut tiny = shrunk(&unit, f);
    tiny.positions.push(Vec3::ONE);
    let accel = build_accel(AccelKind::Bvh8, TestKind::Moller, &tiny, &options);
    let mut hits = 0;
    for r in &rays {
        let want = at_unit.intersect(r);
        hits += usize::from(want.is_some());
        assert_eq!(accel.intersect(&shrink_ray(r, f)), shrink_hit(want, f));
    }
    assert!(hits > 300, "{hits} hits");
    let surface = SurfaceBvh::build(&tiny);
    for p in &pts {
        let want = surface_at_unit.closest_point(*p, f32::INFINITY).unwrap();
        let got = surface.closest_point(*p * f, f32::INFINITY).unwrap();
        assert_eq!(got.distance, want.distance * f);
        assert_eq!(surface.is_inside(*p * f), surface_at_unit.is_inside(*p));
    }
}
