//! The ground-truth evaluator on synthetic assemblies
//! whose visibility is known from their geometry, and `compare` on
//! hand-made kept masks.

use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::tri::TestKind;
use raykit_core::{Aabb, TriangleMesh, Vec3};
use raykit_cull::escape::fibonacci;
use raykit_cull::synthetic::{assembly, box_surface, closed_box, icosphere};
use raykit_cull::{compare, evaluate, evaluate_beyond, EvalOptions, GroundTruth};

fn aabb(lo: f32, hi: f32) -> Aabb {
    Aabb::new(Vec3::splat(lo), Vec3::splat(hi))
}

/// Small counts, so that the tests stay quick (the CLI uses the defaults).
fn quick() -> EvalOptions {
    EvalOptions {
        points: 2,
        directions: 8,
        viewpoints: 200,
        image: 24,
        max_rounds: 4,
        ..Default::default()
    }
}

fn truth_of(mesh: &TriangleMesh, options: &EvalOptions) -> GroundTruth {
    let accel = build_accel(
        AccelKind::Bvh2,
        TestKind::Plucker,
        mesh,
        &BuildOptions::default(),
    );
    evaluate(mesh, accel.as_ref(), options)
}

/// A closed unit box (part 0) with spheres and small boxes inside.
fn box_with_parts() -> TriangleMesh {
    assembly([
        closed_box(&aabb(0.0, 1.0), 4),
        icosphere(Vec3::splat(0.5), 0.2, 1),
        icosphere(Vec3::new(0.25, 0.25, 0.7), 0.08, 1),
        closed_box(
            &Aabb::new(Vec3::new(0.6, 0.2, 0.2), Vec3::new(0.8, 0.35, 0.3)),
            1,
        ),
    ])
}

#[test]
fn closed_box_exactly_the_box_is_visible() {
    let mesh = box_with_parts();
    let truth = truth_of(&mesh, &quick());
    let expected: Vec<bool> = (0..mesh.num_triangles())
        .map(|t| mesh.part_of(t) == 0)
        .collect();
    assert_eq!(truth.visible, expected);
    assert_eq!(truth.visible_count, 4 * 4 * 2 * 6);
    assert!(truth.converged, "last change {}", truth.last_change);
    assert_eq!(truth.degenerate, 0);
}

#[test]
fn parts_in_line_with_a_hole_are_visible() {
    // A square hole of 2/8 in the +x wall, a sphere right behind it, a
    // sphere sealed in its own small box far from it.
    let wall = box_surface(&aabb(0.0, 1.0), 8, |axis, max_side, i, j| {
        axis == 0 && max_side && (3..5).contains(&i) && (3..5).contains(&j)
    });
    let behind = Vec3::new(0.8, 0.5, 0.5);
    let mesh = assembly([
        wall,
        icosphere(behind, 0.1, 2),
        closed_box(
            &Aabb::new(Vec3::new(0.05, 0.05, 0.05), Vec3::new(0.25, 0.25, 0.25)),
            1,
        ),
        icosphere(Vec3::splat(0.15), 0.05, 1),
    ]);
    let truth = truth_of(&mesh, &quick());
    // Triangles seen through the hole at grazing angles keep turning up as
    // the counts grow, so the quick settings need not converge here.
    assert!(truth.rounds == 4 || truth.converged);
    let m = &mesh;
    let tris = |p: u32| (0..m.num_triangles()).filter(move |&t| m.part_of(t) == p);
    let centroid = |t: usize| {
        let [a, b, c] = mesh.triangle(t);
        (a + b + c) / 3.0
    };
    // Every wall triangle is seen from outside.
    assert!(tris(0).all(|t| truth.visible[t]));
    // The sphere's cap facing the hole is seen, its far side is not.
    for t in tris(1) {
        let facing = (centroid(t) - behind).normalize();
        if facing.x > 0.9 {
            assert!(truth.visible[t], "sphere triangle {t} faces the hole");
        }
        if facing.x < -0.5 {
            assert!(!truth.visible[t], "sphere triangle {t} faces away");
        }
    }
    // The sealed sphere is hidden.
    assert!(tris(3).all(|t| !truth.visible[t]));
}

#[test]
fn doubling_terminates_and_doubles() {
    let mesh = box_with_parts();
    let options = quick();
    let truth = truth_of(&mesh, &options);
    assert!(truth.rounds >= 2 && truth.rounds <= options.max_rounds);
    // Rays per triangle double every round: points (with the viewpoints)
    // on odd rounds, directions on even ones.
    let last = truth.rounds as u32 - 1;
    assert_eq!(truth.points, options.points << last.div_ceil(2));
    assert_eq!(truth.directions, options.directions << (last / 2));
    assert_eq!(
        truth.viewpoints,
        options.viewpoints << last.div_ceil(2) as usize
    );
    assert_eq!(truth.round_log.len(), truth.rounds);
    for w in truth.round_log.windows(2) {
        assert_eq!(
            w[1].points * w[1].directions,
            2 * w[0].points * w[0].directions
        );
    }
    let found: usize = truth
        .round_log
        .iter()
        .map(|r| r.by_surface_rays + r.by_renders + r.by_sharing)
        .sum();
    assert_eq!(found, truth.visible_count);
    assert_eq!(truth.last_change, 0);
    assert!(truth.rays > 0 && truth.seconds >= 0.0);
    // With a cap of two rounds it still stops, and reports the change.
    let capped = truth_of(
        &mesh,
        &EvalOptions {
            max_rounds: 2,
            ..options
        },
    );
    assert!(capped.rounds <= 2);
    assert!(!capped.converged || capped.last_change == 0);
    // No triangles: nothing to do.
    let empty = truth_of(&TriangleMesh::default(), &options);
    assert!(empty.visible.is_empty() && empty.converged);
}

#[test]
fn fibonacci_points_are_unit_and_spread() {
    let n = 1000;
    let pts: Vec<Vec3> = (0..n).map(|i| fibonacci(i, n)).collect();
    assert!(pts.iter().all(|p| (p.length() - 1.0).abs() < 1e-5));
    let mean = pts.iter().copied().sum::<Vec3>() / n as f32;
    assert!(mean.length() < 0.01, "{mean}");
}

#[test]
fn compare_counts_false_and_missed_removals() {
    let mesh = box_with_parts();
    let n = mesh.num_triangles();
    let box_tris = 4 * 4 * 2 * 6;
    let visible: Vec<bool> = (0..n).map(|t| mesh.part_of(t) == 0).collect();
    let truth = GroundTruth {
        visible: visible.clone(),
        ..Default::default()
    };

    // Perfect culling.
    let r = compare(&truth, &visible, &mesh);
    assert_eq!((r.false_removals, r.missed_removals), (0, 0));
    assert_eq!(r.triangles, n);
    assert_eq!(r.triangles_removed, n - box_tris);
    assert_eq!((r.truly_visible, r.truly_hidden), (box_tris, n - box_tris));
    assert_eq!((r.parts, r.parts_removed), (4, 3));
    assert!((r.removed_fraction_parts - 0.75).abs() < 1e-12);
    // The area in f64, and within f32 rounding of the mesh's own sum.
    let area64: f64 = (0..n)
        .map(|t| {
            let [a, b, c] = mesh.triangle(t).map(|v| v.as_dvec3());
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    assert!((r.area - area64).abs() < 1e-12 * area64);
    assert!((r.area - mesh.area()).abs() < 1e-5 * mesh.area());
    assert!(
        (r.area - r.area_removed - 6.0).abs() < 1e-4,
        "box area is 6"
    );

    // Keep everything: every hidden triangle is a missed removal.
    let r = compare(&truth, &vec![true; n], &mesh);
    assert_eq!((r.false_removals, r.missed_removals), (0, n - box_tris));
    assert_eq!(r.triangles_removed, 0);
    assert_eq!(r.missed_fraction, 1.0);
    assert_eq!(
        r.missed_removal_ids.len(),
        raykit_cull::evaluate::LISTED_IDS
    );
    assert_eq!(r.missed_removal_ids[0], box_tris);

    // Remove two box triangles and keep three hidden ones.
    let mut kept = visible.clone();
    kept[3] = false;
    kept[10] = false;
    for t in [box_tris, box_tris + 1, n - 1] {
        kept[t] = true;
    }
    let r = compare(&truth, &kept, &mesh);
    assert_eq!(r.false_removals, 2);
    assert_eq!(r.false_removal_ids, vec![3, 10]);
    assert!((r.false_removal_area - 2.0 / 32.0).abs() < 1e-6);
    assert_eq!(r.missed_removals, 3);
    assert_eq!(r.missed_removal_ids, vec![box_tris, box_tris + 1, n - 1]);
    assert_eq!(r.parts_removed, 1, "part 1 and 3 keep a triangle");
    assert_eq!(r.triangles_removed, n - box_tris + 2 - 3);

    // Remove everything: every visible triangle is a false removal.
    let r = compare(&truth, &vec![false; n], &mesh);
    assert_eq!((r.false_removals, r.missed_removals), (box_tris, 0));
    assert_eq!(r.removed_fraction_triangles, 1.0);
    assert!((r.removed_fraction_area - 1.0).abs() < 1e-12);
}

#[test]
fn evaluation_beyond_known_labels_keeps_them_and_finds_the_same_rest() {
    let mesh = box_with_parts();
    let options = quick();
    let accel = build_accel(
        AccelKind::Bvh2,
        TestKind::Plucker,
        &mesh,
        &BuildOptions::default(),
    );
    let full = evaluate(&mesh, accel.as_ref(), &options);
    // Claim the first sphere visible: it stays so, the rest is as before.
    let known: Vec<bool> = (0..mesh.num_triangles())
        .map(|t| mesh.part_of(t) == 1)
        .collect();
    let beyond = evaluate_beyond(&mesh, accel.as_ref(), &options, known.clone(), &|_| {});
    for (t, &k) in known.iter().enumerate() {
        assert_eq!(beyond.visible[t], k || full.visible[t], "triangle {t}");
    }
    assert_eq!(
        beyond.visible_count,
        beyond.visible.iter().filter(|&&v| v).count()
    );
}

#[test]
fn zero_area_triangles_are_neither_visible_nor_hidden() {
    // The box with parts, plus a sliver (three collinear points) inside
    // and one outside: removing or keeping them is never an error.
    let mut mesh = box_with_parts();
    let base = mesh.positions.len() as u32;
    for p in [0.5f32, 0.6, 0.7, 3.0, 3.1, 3.2] {
        mesh.positions.push(Vec3::splat(p));
    }
    mesh.indices.push([base, base + 1, base + 2]);
    mesh.indices.push([base + 3, base + 4, base + 5]);
    let n = mesh.num_triangles();
    let truth = truth_of(&mesh, &quick());
    assert_eq!(truth.degenerate, 2);
    for kept in [vec![true; n], vec![false; n]] {
        let r = compare(&truth, &kept, &mesh);
        assert_eq!(r.degenerate, 2);
        assert_eq!(r.truly_visible + r.truly_hidden, n - 2);
        assert!(r.false_removal_ids.iter().all(|&t| t < n - 2));
        assert!(r.missed_removal_ids.iter().all(|&t| t < n - 2));
    }
    let r = compare(&truth, &vec![true; n], &mesh);
    assert_eq!(r.missed_removals, r.truly_hidden);
}

#[test]
fn the_ground_truth_does_not_depend_on_the_thread_count() {
    // A box with a slot: what is seen through it comes from renders and
    // shared directions, whose order between threads must not matter.
    let wall = box_surface(&aabb(0.0, 1.0), 8, |axis, max_side, i, j| {
        axis == 0 && max_side && i == 4 && (2..6).contains(&j)
    });
    let mesh = assembly([
        wall,
        icosphere(Vec3::new(0.7, 0.5, 0.5), 0.15, 2),
        icosphere(Vec3::new(0.3, 0.4, 0.6), 0.1, 1),
    ]);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| truth_of(&mesh, &quick()))
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one.visible, two.visible);
    assert_eq!(one.round_log.len(), two.round_log.len());
    for (a, b) in one.round_log.iter().zip(&two.round_log) {
        assert_eq!(
            (a.by_surface_rays, a.by_renders, a.by_sharing),
            (b.by_surface_rays, b.by_renders, b.by_sharing)
        );
    }
    assert!(one.visible_count > 0 && one.visible_count < mesh.num_triangles());
}
