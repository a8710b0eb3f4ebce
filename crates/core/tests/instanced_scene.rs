//! Instanced scenes (two-level BVH) against the same scenes flattened into
//! one mesh and traced by the single-mesh `Bvh8`, and against an `f64`
//! brute force over the world triangles, ray for ray: nearest hits with
//! their ids and normals, occlusion, masks, filtered any-hit, all hits,
//! first `k` and counts; bad transforms and bad rays.

mod instancing_support;

use instancing_support::shared_meshes::shared_obj;
use instancing_support::{
    agree_with_flattened, close_on_plane, crossings, ids, near_edge, rays, Crossing, Placed,
};
use raykit_core::accel::BuildOptions;
use raykit_core::glam::{Affine3A, DVec3, Mat3, Vec3};
use raykit_core::instancing::{InstancedScene, SceneBuilder, SceneError, MASK_ALL};
use raykit_core::{Ray, TriangleMesh};

/// The bunny and the teapot (open meshes), each placed several times with
/// rotations, non-uniform and mirroring scales.
fn real_scene(count: usize, seed: u64) -> Placed {
    Placed::random(
        vec![shared_obj("bunny_3674.obj"), shared_obj("teapot_992.obj")],
        count,
        2.5,
        seed,
    )
}

#[test]
fn nearest_hits_match_f64_brute_force_on_the_world_triangles() {
    let placed = real_scene(16, 1);
    let scene = placed.scene();
    let world = placed.world_f64(MASK_ALL);
    let rays = rays(&placed.bounds(), 700, 2);
    let scale = placed.bounds().extent().max_element() as f64;
    let (mut hits, mut excused) = (0, 0);
    for (k, ray) in rays.iter().enumerate() {
        let reference = crossings(&world, ray);
        let got = scene.intersect(ray, MASK_ALL);
        match (got, reference.first()) {
            (None, None) => {}
            (Some(g), Some(r)) => {
                hits += 1;
                assert!(
                    close_on_plane(g.t as f64, r.t, r.normal, ray.dir().as_dvec3(), scale),
                    "ray {k}: t {} vs f64 {}",
                    g.t,
                    r.t
                );
                if ids(&g) == r.ids {
                    let n = r.normal.normalize();
                    assert!(
                        g.normal.as_dvec3().dot(n) > 0.999,
                        "ray {k}: normal {:?} vs {n:?}",
                        g.normal
                    );
                } else {
                    assert!(
                        near_edge(&reference, ray.dir().as_dvec3(), scale),
                        "ray {k}: {g:?} vs {r:?}"
                    );
                    excused += 1;
                }
            }
            (g, _) => {
                let graze = near_edge(&reference, ray.dir().as_dvec3(), scale)
                    || g.is_some_and(|g| {
                        // A hit just outside its triangle (the tolerance band).
                        let tri = world.iter().find(|w| w.1 == ids(&g)).unwrap().0;
                        let p = ray.origin.as_dvec3() + ray.dir().as_dvec3() * g.t as f64;
                        raykit_core::tri::reference::edge_distance_f64(tri[0], tri[1], tri[2], p)
                            < 1e-3
                    });
                assert!(graze, "ray {k}: {g:?} vs {:?}", reference.first());
                excused += 1;
            }
        }
    }
    assert!(hits > 150, "too few hits ({hits}) to test anything");
    assert!(excused * 100 <= rays.len(), "{excused} grazes or ties");
}

#[test]
fn nearest_and_occlusion_match_the_flattened_scene_ray_for_ray() {
    let placed = real_scene(40, 3);
    let scene = placed.scene();
    let stats = scene.stats();
    assert_eq!(stats.instances, 40);
    assert_eq!(
        stats.stored_triangles,
        placed
            .meshes
            .iter()
            .map(|m| m.num_triangles())
            .sum::<usize>()
    );
    assert_eq!(
        stats.instanced_triangles,
        placed.flattened(MASK_ALL).0.num_triangles()
    );
    let rays = rays(&placed.bounds(), 4000, 4);
    agree_with_flattened(&placed, &scene, MASK_ALL, &rays);
}

#[test]
fn batch_queries_answer_as_the_single_ray_ones() {
    let placed = real_scene(12, 5);
    let scene = placed.scene();
    let rays = rays(&placed.bounds(), 3000, 6);
    let mut hits = vec![None; rays.len()];
    let mut occ = vec![false; rays.len()];
    let mut counts = vec![0; rays.len()];
    scene.intersect_batch(&rays, MASK_ALL, &mut hits);
    scene.occluded_batch(&rays, MASK_ALL, &mut occ);
    scene.count_hits_batch(&rays, MASK_ALL, &mut counts);
    let lists = scene.ray_hits_batch(&rays, MASK_ALL, 5);
    for (k, r) in rays.iter().enumerate() {
        assert_eq!(hits[k], scene.intersect(r, MASK_ALL));
        assert_eq!(occ[k], scene.occluded(r, MASK_ALL));
        assert_eq!(counts[k], scene.count_hits(r, MASK_ALL));
        assert_eq!(lists[k], scene.ray_hits(r, MASK_ALL, 5));
    }
}

/// A pinhole camera's rays: `side`² rays from one eye `away` diagonals of
/// `bounds` from its centre, looking at it, in image order; the image
/// plane at distance 1 is `field` wide.
fn camera_rays(bounds: &raykit_core::Aabb, side: usize, field: f32, away: f32) -> Vec<Ray> {
    let centre = bounds.center();
    let eye = centre + Vec3::new(0.3, 0.4, 1.0).normalize() * (away * bounds.diagonal());
    let forward = (centre - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    (0..side * side)
        .map(|p| {
            let x = ((p % side) as f32 + 0.5) / side as f32 - 0.5;
            let y = ((p / side) as f32 + 0.5) / side as f32 - 0.5;
            Ray::new(eye, (forward + field * (x * right + y * up)).normalize())
        })
        .collect()
}

#[test]
fn rays_from_one_eye_traced_instance_by_instance_answer_as_single_rays() {
    // Rays leaving one point are traced instance by instance through each
    // geometry's packets; each must find what the single-ray walk finds.
    // At equal t the two may keep different instances (coincident faces):
    // then the batch's hit must be its instance's own nearest hit. A narrow
    // field finds the instances by one cone, a wide one ray by ray.
    let placed = real_scene(30, 8);
    let scene = placed.scene();
    for (field, away) in [(0.6, 2.0), (4.0, 0.4)] {
        let rays = camera_rays(&placed.bounds(), 96, field, away);
        batch_against_single_rays(&placed, &scene, &rays);
    }
}

#[test]
fn lines_through_one_eye_find_the_instances_behind_it() {
    // A bunny ahead of the eye and one behind it: rays from the eye over
    // the whole line (tnear = -inf) meet the one behind first (t < 0),
    // which no cone round the rays' forward halves holds.
    let bunny = shared_obj("bunny_3674.obj");
    let b = bunny.bounds();
    let step = Vec3::X * 3.0 * b.diagonal();
    let placed = Placed {
        meshes: vec![bunny.clone()],
        instances: vec![
            (0, Affine3A::IDENTITY, u32::MAX),
            (0, Affine3A::from_translation(2.0 * step), u32::MAX),
        ],
    };
    let scene = placed.scene();
    let eye = b.center() + step;
    let lines: Vec<Ray> = (0..64 * 64)
        .map(|p| {
            let (x, y) = ((p % 64) as f32 / 63.0 - 0.5, (p / 64) as f32 / 63.0 - 0.5);
            let dir = -Vec3::X + 0.4 * Vec3::new(0.0, y, x);
            Ray::segment(eye, dir, f32::NEG_INFINITY, f32::INFINITY)
        })
        .collect();
    batch_against_single_rays(&placed, &scene, &lines);
    let behind = lines
        .iter()
        .filter_map(|r| scene.intersect(r, MASK_ALL))
        .filter(|h| h.t < 0.0)
        .count();
    assert!(behind > 100, "{behind} hits behind the eye");
}

#[test]
fn random_rays_entering_few_instance_boxes_are_traced_instance_by_instance() {
    // Rays from many points that enter few instance boxes each (here the
    // bunny's, a teapot far away) are traced instance by instance too.
    let bunny = shared_obj("bunny_3674.obj");
    let far = Affine3A::from_translation(Vec3::X * 50.0 * bunny.bounds().diagonal());
    let placed = Placed {
        meshes: vec![bunny.clone(), shared_obj("teapot_992.obj")],
        instances: vec![(0, Affine3A::IDENTITY, u32::MAX), (1, far, u32::MAX)],
    };
    let scene = placed.scene();
    batch_against_single_rays(&placed, &scene, &rays(&bunny.bounds(), 6000, 21));
}

/// The batch answers of `rays` against the single-ray ones.
fn batch_against_single_rays(placed: &Placed, scene: &InstancedScene, rays: &[Ray]) {
    let mut hits = vec![None; rays.len()];
    let mut occ = vec![false; rays.len()];
    scene.intersect_batch(rays, MASK_ALL, &mut hits);
    scene.occluded_batch(rays, MASK_ALL, &mut occ);
    let mut seen = 0;
    for (k, r) in rays.iter().enumerate() {
        let single = scene.intersect(r, MASK_ALL);
        assert_eq!(occ[k], scene.occluded(r, MASK_ALL), "ray {k}");
        assert_eq!(occ[k], single.is_some(), "ray {k}");
        match (hits[k], single) {
            (Some(b), Some(s)) if b != s => {
                assert_eq!(b.t, s.t, "ray {k}");
                let one = Placed {
                    meshes: placed.meshes.clone(),
                    instances: vec![placed.instances[b.instance as usize]],
                };
                let own = one.scene().intersect(r, MASK_ALL).expect("its own hit");
                assert_eq!((own.t, own.prim), (b.t, b.prim), "ray {k}");
            }
            (b, s) => assert_eq!(b, s, "ray {k}"),
        }
        seen += usize::from(single.is_some());
    }
    // The rays find the scene and miss it too.
    assert!(seen > rays.len() / 100 && seen < rays.len(), "{seen}");
}

#[test]
fn one_geometry_in_place_answers_batches_as_single_rays() {
    // The batch path of a scene that is one geometry at the identity walks
    // the geometry's rays in turn; the single-ray path goes through the top
    // level and the instance.
    let placed = Placed {
        meshes: vec![shared_obj("bunny_3674.obj")],
        instances: vec![(0, Affine3A::IDENTITY, u32::MAX)],
    };
    let scene = placed.scene();
    let mut rays = rays(&placed.bounds(), 3000, 12);
    rays.push(Ray::new(Vec3::NAN, Vec3::X));
    rays.push(Ray::new(Vec3::ZERO, Vec3::ZERO));
    for mask in [MASK_ALL, 0] {
        let mut counts = vec![0; rays.len()];
        scene.count_hits_batch(&rays, mask, &mut counts);
        let all = scene.ray_hits_batch(&rays, mask, usize::MAX);
        let first = scene.ray_hits_batch(&rays, mask, 3);
        let mut crossed = 0;
        for (k, r) in rays.iter().enumerate() {
            assert_eq!(counts[k], scene.count_hits(r, mask));
            assert_eq!(all[k], scene.ray_hits(r, mask, usize::MAX));
            assert_eq!(first[k], scene.ray_hits(r, mask, 3));
            assert_eq!(all[k].len(), counts[k] as usize);
            crossed += counts[k];
        }
        assert_eq!(crossed > 0, mask == MASK_ALL);
    }
}

#[test]
fn masks_hide_instances_and_geometries_as_the_flattened_subset() {
    let mut placed = real_scene(30, 7);
    for (i, inst) in placed.instances.iter_mut().enumerate() {
        inst.2 = 1 << (i % 3);
    }
    let scene = placed.scene();
    let rays = rays(&placed.bounds(), 1500, 8);
    for mask in [0b001, 0b010, 0b110, MASK_ALL] {
        agree_with_flattened(&placed, &scene, mask, &rays);
    }
    // A mask no instance shares sees nothing.
    assert!(rays.iter().all(|r| scene.intersect(r, 0b1000).is_none()));
    assert!(rays.iter().all(|r| !scene.occluded(r, 0)));
    // A geometry mask hides every instance of that geometry.
    let mut b = SceneBuilder::new();
    for m in &placed.meshes {
        b.add_geometry(m.clone()).unwrap();
    }
    b.set_geometry_mask(0, 0b10).unwrap();
    for (g, t, _) in &placed.instances {
        b.add_instance(*g, *t).unwrap();
    }
    let by_geometry = b.build(&BuildOptions::default());
    let mut teapots_only = Placed {
        meshes: placed.meshes.clone(),
        instances: placed.instances.clone(),
    };
    for inst in &mut teapots_only.instances {
        inst.2 = if inst.0 == 0 { 0 } else { MASK_ALL };
    }
    agree_with_flattened(&teapots_only, &by_geometry, 0b01, &rays);
}

/// Rays whose reference crossings all lie clear of triangle edges (where
/// the `f32` crossing test may count a crossing on both neighbours or
/// neither), with the reference.
fn clear_rays(placed: &Placed, n: usize, seed: u64) -> Vec<(Ray, Vec<Crossing>)> {
    let world = placed.world_f64(MASK_ALL);
    rays(&placed.bounds(), n, seed)
        .into_iter()
        .filter_map(|r| {
            let c = crossings(&world, &r);
            c.iter().all(|c| c.margin > 1e-4).then_some((r, c))
        })
        .collect()
}

#[test]
fn all_hits_first_k_and_counts_match_f64_brute_force() {
    let placed = real_scene(14, 9);
    let scene = placed.scene();
    let cases = clear_rays(&placed, 500, 10);
    assert!(cases.len() > 300);
    let scale = placed.bounds().extent().max_element() as f64;
    let mut multi = 0;
    for (k, (ray, want)) in cases.iter().enumerate() {
        let all = scene.ray_hits(ray, MASK_ALL, usize::MAX);
        assert_eq!(
            scene.count_hits(ray, MASK_ALL) as usize,
            want.len(),
            "ray {k}"
        );
        assert_eq!(all.len(), want.len(), "ray {k}");
        let mut got_ids: Vec<_> = all.iter().map(ids).collect();
        let mut want_ids: Vec<_> = want.iter().map(|c| c.ids).collect();
        got_ids.sort_unstable();
        want_ids.sort_unstable();
        assert_eq!(got_ids, want_ids, "ray {k}");
        let d = ray.dir().as_dvec3();
        for (g, w) in all.iter().zip(want) {
            assert!(
                close_on_plane(g.t as f64, w.t, w.normal, d, scale),
                "ray {k}: t {} vs {}",
                g.t,
                w.t
            );
        }
        assert!(
            all.windows(2).all(|p| p[0].t <= p[1].t),
            "ray {k}: not sorted"
        );
        multi += (want.len() > 2) as usize;
        for cap in [1, 2, 3] {
            let first = scene.first_hits(ray, MASK_ALL, cap);
            assert_eq!(first.len(), want.len().min(cap), "ray {k}");
            for (g, w) in first.iter().zip(want) {
                assert!(
                    close_on_plane(g.t as f64, w.t, w.normal, d, scale),
                    "ray {k} cap {cap}"
                );
            }
        }
    }
    assert!(multi > 20, "too few rays crossing more than two triangles");
}

#[test]
fn filtered_any_hit_and_filtered_hits_match_a_brute_force_filter() {
    let placed = real_scene(14, 11);
    let scene = placed.scene();
    let cases = clear_rays(&placed, 500, 12);
    let scale = placed.bounds().extent().max_element() as f64;
    // Front faces of odd instances only.
    let keep_ref = |c: &Crossing, dir: DVec3| c.ids.1 % 2 == 1 && c.normal.dot(dir) < 0.0;
    let (mut some, mut none) = (0, 0);
    for (k, (ray, want)) in cases.iter().enumerate() {
        let dir = ray.dir().as_dvec3();
        let accepted: Vec<&Crossing> = want.iter().filter(|c| keep_ref(c, dir)).collect();
        let mut asked = 0;
        let got = scene.any_hit_filtered(ray, MASK_ALL, |h| {
            asked += 1;
            h.instance % 2 == 1 && !h.is_back_face(ray.dir())
        });
        match got {
            Some(h) => {
                some += 1;
                assert!(
                    accepted.iter().any(|c| c.ids == ids(&h)
                        && close_on_plane(c.t, h.t as f64, c.normal, dir, scale)),
                    "ray {k}: {h:?} is not an accepted crossing"
                );
            }
            None => {
                none += 1;
                assert!(accepted.is_empty(), "ray {k}: missed {:?}", accepted[0]);
                assert!(asked <= want.len());
            }
        }
        let mut kept = Vec::new();
        scene.ray_hits_filtered(
            ray,
            MASK_ALL,
            usize::MAX,
            |h| h.instance % 2 == 1 && !h.is_back_face(ray.dir()),
            &mut kept,
        );
        let got_ids: Vec<_> = kept.iter().map(ids).collect();
        let want_ids: Vec<_> = accepted.iter().map(|c| c.ids).collect();
        assert_eq!(got_ids.len(), want_ids.len(), "ray {k}");
        for (g, w) in kept.iter().zip(&accepted) {
            assert!(
                close_on_plane(g.t as f64, w.t, w.normal, dir, scale),
                "ray {k}"
            );
        }
    }
    assert!(some > 50 && none > 50, "{some} accepted, {none} without");
}

#[test]
fn bad_transforms_and_unknown_ids_are_refused_by_name() {
    let mut b = SceneBuilder::new();
    let g = b.add_geometry(shared_obj("teapot_992.obj")).unwrap();
    b.add_instance(g, Affine3A::IDENTITY).unwrap();
    let flat = Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0));
    let err = b.add_named_instance("lid", g, flat).unwrap_err();
    assert!(matches!(err, SceneError::BadTransform { instance: 1, .. }));
    let msg = err.to_string();
    assert!(
        msg.contains("instance 1") && msg.contains("\"lid\"") && msg.contains("not invertible"),
        "{msg}"
    );
    // Dependent columns: the third is the sum of the first two.
    let dependent = Affine3A::from_mat3(Mat3::from_cols(
        Vec3::new(1.0, 2.0, 3.0),
        Vec3::new(-1.0, 0.5, 2.0),
        Vec3::new(0.0, 2.5, 5.0),
    ));
    assert!(b
        .add_instance(g, dependent)
        .unwrap_err()
        .to_string()
        .contains("not invertible"));
    let nan = Affine3A::from_translation(Vec3::new(f32::NAN, 0.0, 0.0));
    assert!(b
        .add_instance(g, nan)
        .unwrap_err()
        .to_string()
        .contains("NaN"));
    let inf = Affine3A::from_scale(Vec3::splat(f32::INFINITY));
    assert!(b.add_instance(g, inf).is_err());
    let err = b.add_instance(7, Affine3A::IDENTITY).unwrap_err();
    assert!(
        err.to_string().contains("geometry 7 does not exist"),
        "{err}"
    );
    assert!(b.set_instance_mask(9, 1).is_err());
    let mut bad = TriangleMesh::new(vec![Vec3::ZERO], vec![[0, 0, 1]]);
    assert!(matches!(
        b.add_geometry(bad.clone()),
        Err(SceneError::BadMesh { geometry: 1, .. })
    ));
    bad.positions = vec![Vec3::splat(f32::NAN); 2];
    assert!(b.add_geometry(bad).is_err());
    // The refused instances left no trace: one instance, one geometry.
    assert_eq!((b.num_geometries(), b.num_instances()), (1, 1));
    // Small but regular transforms are accepted.
    let tiny = Affine3A::from_scale(Vec3::new(1e-6, 1e-3, 1e4));
    assert!(b.add_instance(g, tiny).is_ok());
}

#[test]
fn rays_with_nan_or_infinite_parts_miss_everywhere() {
    let placed = real_scene(8, 13);
    let scene = placed.scene();
    let c = placed.bounds().center();
    let bad = [
        Ray::new(Vec3::new(f32::NAN, c.y, c.z), Vec3::X),
        Ray::new(c, Vec3::new(f32::NAN, 1.0, 0.0)),
        Ray::new(Vec3::splat(f32::INFINITY), -Vec3::ONE),
        Ray::new(c, Vec3::new(f32::INFINITY, 0.0, 0.0)),
        Ray::new(c, Vec3::ZERO),
        Ray::segment(c - Vec3::X * 10.0, Vec3::X, f32::NAN, f32::INFINITY),
        Ray::segment(c - Vec3::X * 10.0, Vec3::X, 0.0, f32::NAN),
    ];
    for r in &bad {
        assert!(scene.intersect(r, MASK_ALL).is_none(), "{r:?}");
        assert!(!scene.occluded(r, MASK_ALL), "{r:?}");
        assert_eq!(scene.count_hits(r, MASK_ALL), 0);
        assert!(scene.ray_hits(r, MASK_ALL, 10).is_empty());
        assert!(scene.any_hit_filtered(r, MASK_ALL, |_| true).is_none());
    }
    let mut hits = vec![None; bad.len()];
    scene.intersect_batch(&bad, MASK_ALL, &mut hits);
    assert!(hits.iter().all(|h| h.is_none()));
}

#[test]
fn empty_scenes_and_empty_geometries_miss() {
    let empty = SceneBuilder::new().build(&BuildOptions::default());
    let r = Ray::new(Vec3::ZERO, Vec3::X);
    assert!(empty.intersect(&r, MASK_ALL).is_none());
    let mut b = SceneBuilder::new();
    let g = b.add_geometry(TriangleMesh::default()).unwrap();
    b.add_instance(g, Affine3A::IDENTITY).unwrap();
    let s = b.build(&BuildOptions::default());
    assert!(s.intersect(&r, MASK_ALL).is_none());
    assert_eq!(s.count_hits(&r, MASK_ALL), 0);
}
