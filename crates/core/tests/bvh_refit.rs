//! Refit of the wide BVHs over deforming meshes: the refit tree's nearest
//! hits equal a fresh build's bit for bit, ray for ray, and both agree with
//! brute force on the deformed mesh; every leaf's box holds its triangles;
//! the SAH degradation triggers a rebuild; a mesh that is not the tree's is
//! refused.

mod shared_meshes;

use raykit_core::accel::bvh::DEFAULT_MAX_DEGRADATION;
use raykit_core::accel::{Accel, BruteForce, BuildOptions, Bvh4, Bvh8, RefitError};
use raykit_core::rng::Pcg32;
use raykit_core::tri::{Moller, Plucker, TriangleTest};
use raykit_core::{Aabb, Icosphere, TriangleMesh};
use shared_meshes::{agree, bits, deformed, rays, shared_obj};

fn sphere() -> TriangleMesh {
    let s = Icosphere::new(4);
    TriangleMesh::new(s.positions, s.indices)
}

/// `tree`'s answers on `mesh`: nearest-hit `t` bit for bit as `rebuilt`'s
/// (the same triangles, so the same nearest distance; the triangle may
/// differ only at a tie), occlusion equal, both agreeing with brute force.
fn check_against_rebuild(
    tree: &dyn Accel,
    rebuilt: &dyn Accel,
    brute: &dyn Accel,
    mesh: &TriangleMesh,
    seed: u64,
) {
    let rays = rays(mesh, 10_000, seed);
    let mut hits = 0;
    for ray in &rays {
        let (r, b, want) = (
            tree.intersect(ray),
            rebuilt.intersect(ray),
            brute.intersect(ray),
        );
        assert_eq!(
            r.map(|h| h.t.to_bits()),
            b.map(|h| h.t.to_bits()),
            "{ray:?} {r:?} {b:?}"
        );
        assert!(
            agree(r, want),
            "refit vs brute force: {ray:?} {r:?} {want:?}"
        );
        assert!(
            agree(b, want),
            "rebuild vs brute force: {ray:?} {b:?} {want:?}"
        );
        assert_eq!(tree.occluded(ray), want.is_some(), "{ray:?}");
        hits += r.is_some() as usize;
    }
    assert!(hits > 2000, "{hits}");
    // The packet path of the batch query gives the single-ray answers.
    let mut batch = vec![None; rays.len()];
    tree.intersect_batch(&rays, &mut batch);
    for (ray, h) in rays.iter().zip(&batch) {
        assert_eq!(bits(*h), bits(tree.intersect(ray)));
    }
}

/// The regions are conservative: a walk entering only the regions that
/// contain a corner of a triangle reaches a leaf holding that triangle
/// (for a sample of triangles and corners).
fn check_boxes_hold_triangles(tree: &dyn Accel, mesh: &TriangleMesh) {
    let mut rng = Pcg32::new(77);
    for _ in 0..300 {
        let t = rng.below(mesh.num_triangles() as u32);
        let corner = mesh.triangle(t as usize)[rng.below(3) as usize];
        let mut found = false;
        tree.visit_regions(
            &mut |b: &Aabb| corner.cmpge(b.min).all() && corner.cmple(b.max).all(),
            &mut |prims| found |= prims.contains(&t),
        );
        assert!(found, "triangle {t}'s corner {corner} is outside its boxes");
    }
}

fn refit_frames<T: TriangleTest>(mesh: &TriangleMesh, amp: f32) {
    let opts = BuildOptions::default();
    let mut t8 = Bvh8::<T>::build(mesh, &opts);
    let mut t4 = Bvh4::<T>::build(mesh, &opts);
    for (frame, phase) in [0.4f32, 1.1, 2.0, 3.3].into_iter().enumerate() {
        let moved = deformed(mesh, phase, amp);
        let r8 = t8.refit(&moved).unwrap();
        let r4 = t4.refit(&moved).unwrap();
        assert!(!r8.rebuilt && r8.degradation().is_finite() && r4.degradation().is_finite());
        let brute = BruteForce::<T>::new(&moved);
        let seed = 100 + frame as u64;
        check_against_rebuild(&t8, &Bvh8::<T>::build(&moved, &opts), &brute, &moved, seed);
        check_against_rebuild(&t4, &Bvh4::<T>::build(&moved, &opts), &brute, &moved, seed);
        check_boxes_hold_triangles(&t8, &moved);
        check_boxes_hold_triangles(&t4, &moved);
    }
}

#[test]
fn refit_sphere_matches_rebuild_every_frame() {
    refit_frames::<Moller>(&sphere(), 0.08);
    refit_frames::<Plucker>(&sphere(), 0.08);
}

#[test]
fn refit_bunny_matches_rebuild_every_frame() {
    refit_frames::<Moller>(&shared_obj("bunny_3674.obj"), 0.05);
    refit_frames::<Plucker>(&shared_obj("bunny_3674.obj"), 0.05);
}

/// A refit to the very mesh the tree was built over changes nothing: the
/// same regions, hits and SAH cost as built (the boxes are the build's).
#[test]
fn refit_to_the_same_mesh_is_the_build() {
    let bunny = shared_obj("bunny_3674.obj");
    let built = Bvh8::<Moller>::build(&bunny, &BuildOptions::default());
    let mut refit = Bvh8::<Moller>::build(&bunny, &BuildOptions::default());
    let report = refit.refit(&bunny).unwrap();
    assert_eq!(report.degradation(), 1.0);
    assert_eq!(refit.sah_costs(), built.sah_costs());
    let regions = |t: &dyn Accel| {
        let mut out = Vec::new();
        t.visit_regions(
            &mut |b| {
                out.push(*b);
                true
            },
            &mut |_| {},
        );
        out
    };
    assert_eq!(regions(&refit), regions(&built));
    for ray in rays(&bunny, 5000, 1) {
        assert_eq!(bits(refit.intersect(&ray)), bits(built.intersect(&ray)));
    }
}

/// Rigid motion keeps the tree's quality; scrambling the vertices ruins
/// it, and `refit_or_rebuild` rebuilds past the limit, after which the
/// tree is as good as a fresh build and answers as brute force.
#[test]
fn degradation_triggers_a_rebuild() {
    let bunny = shared_obj("bunny_3674.obj");
    let opts = BuildOptions::default();
    let mut tree = Bvh8::<Moller>::build(&bunny, &opts);

    let mut moved = bunny.clone();
    for p in &mut moved.positions {
        *p = *p * 2.0 + raykit_core::Vec3::new(1.0, -3.0, 0.5);
    }
    let r = tree
        .refit_or_rebuild(&moved, &opts, DEFAULT_MAX_DEGRADATION)
        .unwrap();
    assert!(!r.rebuilt && (r.degradation() - 1.0).abs() < 0.05, "{r:?}");

    let mut scrambled = moved.clone();
    let mut rng = Pcg32::new(4);
    let n = scrambled.positions.len();
    for i in (1..n).rev() {
        scrambled
            .positions
            .swap(i, rng.below(i as u32 + 1) as usize);
    }
    let r = tree
        .refit_or_rebuild(&scrambled, &opts, DEFAULT_MAX_DEGRADATION)
        .unwrap();
    assert!(
        r.rebuilt && r.degradation() > DEFAULT_MAX_DEGRADATION,
        "{r:?}"
    );
    let fresh = Bvh8::<Moller>::build(&scrambled, &opts);
    assert_eq!(tree.sah_costs(), fresh.sah_costs());
    assert_eq!(r.sah, fresh.sah_costs().0);
    let brute = BruteForce::<Moller>::new(&scrambled);
    for ray in rays(&scrambled, 3000, 2) {
        assert!(agree(tree.intersect(&ray), brute.intersect(&ray)));
    }
}

/// A mesh with other triangles or bad indices is refused, the tree kept.
#[test]
fn refit_refuses_another_mesh() {
    let s = sphere();
    let mut tree = Bvh8::<Moller>::build(&s, &BuildOptions::default());
    let mut fewer = s.clone();
    fewer.indices.pop();
    assert!(matches!(
        tree.refit(&fewer),
        Err(RefitError::TriangleCount { .. })
    ));
    let mut bad = s.clone();
    bad.indices[17][1] = s.positions.len() as u32 + 5;
    let err = tree.refit(&bad).unwrap_err();
    assert!(
        matches!(err, RefitError::VertexIndex { triangle: 17, .. }),
        "{err}"
    );
    let brute = BruteForce::<Moller>::new(&s);
    for ray in rays(&s, 2000, 3) {
        assert!(agree(tree.intersect(&ray), brute.intersect(&ray)));
    }
}

/// Through the `Accel` trait: the wide BVHs built by kind refit (and then
/// answer as brute force on the moved mesh); the others say they cannot.
#[test]
fn registry_refit_every_kind() {
    use raykit_core::accel::{build_accel, AccelKind};
    use raykit_core::tri::TestKind;
    let s = sphere();
    let moved = deformed(&s, 0.9, 0.08);
    let brute = BruteForce::<Moller>::new(&moved);
    let rays = rays(&moved, 2000, 13);
    for kind in AccelKind::ALL {
        let mut accel = build_accel(kind, TestKind::Moller, &s, &BuildOptions::default());
        match accel.refit(&moved) {
            Ok(report) => {
                assert!(
                    matches!(kind, AccelKind::Bvh4 | AccelKind::Bvh8),
                    "{kind:?}"
                );
                assert!(report.degradation().is_finite());
                for ray in &rays {
                    assert!(
                        agree(accel.intersect(ray), brute.intersect(ray)),
                        "{kind:?}"
                    );
                }
            }
            Err(e) => {
                assert_eq!(e, RefitError::Unsupported, "{kind:?}");
                assert!(!matches!(kind, AccelKind::Bvh4 | AccelKind::Bvh8));
            }
        }
    }
}

/// `refit_keeps_precision` says when a refit answers as a build over the
/// moved mesh would: true for a deformation in place (the refit's hits are
/// the rebuild's, bit for bit, for every test), false once a Plücker or
/// projection model has moved far from where it was built (its refit hits
/// then differ from the rebuild's, which match brute force) or any model
/// has shrunk to a tiny size.
#[test]
fn refit_keeps_precision_tells_when_to_rebuild() {
    use raykit_core::accel::{build_accel, refit_keeps_precision, AccelKind};
    use raykit_core::tri::TestKind;
    let s = sphere();
    let bent = deformed(&s, 0.9, 0.08);
    let far = TriangleMesh::new(
        s.positions
            .iter()
            .map(|p| *p + raykit_core::Vec3::new(3e4, -2e4, 1e4))
            .collect(),
        s.indices.clone(),
    );
    let tiny = TriangleMesh::new(
        s.positions.iter().map(|p| *p * 1e-9).collect(),
        s.indices.clone(),
    );
    let opts = BuildOptions::default();
    for test in [TestKind::Moller, TestKind::Plucker, TestKind::Projection] {
        assert!(refit_keeps_precision(test, &s, &bent), "{test:?}");
        assert!(!refit_keeps_precision(test, &s, &tiny), "{test:?}");
        let moves_far = !refit_keeps_precision(test, &s, &far);
        assert_eq!(moves_far, test != TestKind::Moller, "{test:?}");
        for (moved, keeps) in [(&bent, true), (&far, !moves_far)] {
            let mut refit = build_accel(AccelKind::Bvh8, test, &s, &opts);
            refit.refit(moved).unwrap();
            let rebuilt = build_accel(AccelKind::Bvh8, test, moved, &opts);
            let brute = build_accel(AccelKind::Brute, test, moved, &opts);
            let rays = rays(moved, 2000, 17);
            let differ = rays
                .iter()
                .filter(|r| bits(refit.intersect(r)) != bits(rebuilt.intersect(r)))
                .count();
            for ray in &rays {
                assert!(
                    agree(rebuilt.intersect(ray), brute.intersect(ray)),
                    "{test:?}"
                );
            }
            if keeps {
                assert_eq!(
                    differ, 0,
                    "{test:?}: the refit should answer as the rebuild"
                );
            } else {
                assert!(
                    differ > 100,
                    "{test:?}: only {differ} of 2000 rays differ far away"
                );
            }
        }
    }
}
