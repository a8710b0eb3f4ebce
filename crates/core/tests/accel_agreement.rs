//! Every acceleration structure × triangle test agrees with brute force on
//! random meshes: same hit/miss, t within 1e-5 relative, and a different
//! triangle only at a tie (same t).

use raykit_core::accel::{build_accel, AccelKind, BuildOptions, BuildQuality, KdOptions, KdSplit};
use raykit_core::rng::Pcg32;
use raykit_core::tri::TestKind;
use raykit_core::{Hit, Ray, TriangleMesh, Vec3};

mod soup;

/// A soup of `n` random triangles of varied size inside the unit cube.
fn random_soup(n: usize, seed: u64) -> TriangleMesh {
    soup::soup(n, seed, 0.002, 0.08, 3)
}

/// A closed height-field-like grid surface with shared edges (rays hit edges
/// and vertices often), plus coincident duplicate triangles for ties.
fn grid_with_duplicates(n: usize, seed: u64) -> TriangleMesh {
    let mut rng = Pcg32::new(seed);
    let mut mesh = soup::grid(n, || 0.1 * rng.next_f32());
    let dups: Vec<[u32; 3]> = mesh.indices.iter().step_by(7).copied().collect();
    mesh.indices.extend(dups);
    mesh
}

fn random_rays(mesh: &TriangleMesh, n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Pcg32::new(seed);
    let b = mesh.bounds();
    let c = b.center();
    let r = b.diagonal();
    (0..n)
        .map(|i| {
            let target = rng.in_box(b.min, b.max);
            let origin = if i % 3 == 0 {
                // From inside the box: many hits at short distances.
                rng.in_box(b.min, b.max)
            } else {
                c + rng.unit_vector() * r
            };
            let dir = target - origin;
            let mut ray = Ray::new(origin, dir);
            if i % 5 == 0 {
                // Bounded segments exercise tnear/tfar culling.
                ray = Ray::segment(origin, dir, 0.1 * rng.next_f32(), 0.2 + rng.next_f32());
            }
            ray
        })
        .collect()
}

fn agree(a: Option<Hit>, b: Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(x), Some(y)) => {
            let tol = 1e-5 * x.t.abs().max(y.t.abs()).max(1e-6);
            (x.t - y.t).abs() <= tol
        }
        _ => false,
    }
}

fn check_mesh(mesh: &TriangleMesh, rays: &[Ray]) {
    check_kinds(mesh, rays, &BuildOptions::default(), &AccelKind::ALL);
}

fn check_kinds(mesh: &TriangleMesh, rays: &[Ray], opts: &BuildOptions, kinds: &[AccelKind]) {
    let opts = opts.clone();
    for test in TestKind::ALL {
        let brute = build_accel(AccelKind::Brute, test, mesh, &opts);
        let mut want = vec![None; rays.len()];
        brute.intersect_batch(rays, &mut want);
        let mut want_occ = vec![false; rays.len()];
        brute.occluded_batch(rays, &mut want_occ);
        for (w, o) in want.iter().zip(&want_occ) {
            assert_eq!(
                w.is_some(),
                *o,
                "brute force occluded disagrees with intersect"
            );
        }
        for &kind in kinds {
            let accel = build_accel(kind, test, mesh, &opts);
            let mut got = vec![None; rays.len()];
            accel.intersect_batch(rays, &mut got);
            let mut got_occ = vec![false; rays.len()];
            accel.occluded_batch(rays, &mut got_occ);
            let mut bad = 0;
            for i in 0..rays.len() {
                if !agree(want[i], got[i]) {
                    bad += 1;
                    if bad < 5 {
                        eprintln!(
                            "{} × {}: ray {i} {:?}: brute {:?}, got {:?}",
                            kind.name(),
                            test.name(),
                            rays[i],
                            want[i],
                            got[i]
                        );
                    }
                }
                // Single-ray calls give the batch's answers.
                assert_eq!(accel.intersect(&rays[i]), got[i]);
            }
            let bad_occ = (0..rays.len())
                .filter(|&i| want_occ[i] != got_occ[i])
                .count();
            assert_eq!(
                bad,
                0,
                "{} × {}: {bad} of {} rays disagree with brute force",
                kind.name(),
                test.name(),
                rays.len()
            );
            assert_eq!(
                bad_occ,
                0,
                "{} × {}: {bad_occ} occlusion answers disagree",
                kind.name(),
                test.name()
            );
        }
    }
}

/// Segments that start behind their origin (negative `tnear`, down to the
/// whole line at minus infinity) find the hits there, in every structure:
/// the kd-trees' traversals once clipped them to `t >= 0`.
#[test]
fn segments_reaching_behind_the_origin_agree_with_brute_force() {
    let mesh = random_soup(3000, 9);
    let mut rng = Pcg32::new(10);
    let rays: Vec<Ray> = random_rays(&mesh, 3000, 11)
        .into_iter()
        .enumerate()
        .map(|(i, r)| {
            // Origins moved past the soup, looking on; the hits lie behind.
            let origin = r.origin + r.dir() * (1.0 + 2.0 * rng.next_f32());
            let tnear = if i % 2 == 0 {
                f32::NEG_INFINITY
            } else {
                -4.0 * rng.next_f32()
            };
            Ray::segment(
                origin,
                r.dir(),
                tnear,
                if i % 3 == 0 { 0.0 } else { f32::INFINITY },
            )
        })
        .collect();
    check_mesh(&mesh, &rays);
}

#[test]
fn random_soups_agree_with_brute_force() {
    for (n, seed) in [(1, 1), (2, 2), (7, 3), (100, 4), (3000, 5)] {
        let mesh = random_soup(n, seed);
        let rays = random_rays(&mesh, 4000, seed + 100);
        check_mesh(&mesh, &rays);
    }
}

/// The kd-tree traversals on trees from every split rule (the default
/// SAH build is covered by the tests above through `AccelKind::ALL`).
#[test]
fn kd_trees_of_every_split_rule_agree_with_brute_force() {
    let meshes = [
        random_soup(3000, 21),
        grid_with_duplicates(30, 22),
        random_soup(40, 23),
    ];
    for split in [
        KdSplit::Median,
        KdSplit::Game(0),
        KdSplit::Game(7),
        KdSplit::Game(20),
    ] {
        let opts = BuildOptions {
            kd: KdOptions {
                split,
                ..KdOptions::default()
            },
            ..BuildOptions::default()
        };
        for (i, mesh) in meshes.iter().enumerate() {
            let rays = random_rays(mesh, 2500, 30 + i as u64);
            eprintln!("split {}, mesh {i}", split.name());
            check_kinds(mesh, &rays, &opts, &AccelKind::KD);
        }
    }
}

#[test]
fn shared_edge_grid_with_ties_agrees_with_brute_force() {
    let mesh = grid_with_duplicates(40, 9);
    let mut rays = random_rays(&mesh, 4000, 10);
    // Rays aimed exactly at grid vertices and edge midpoints.
    let mut rng = Pcg32::new(11);
    for _ in 0..2000 {
        let t = mesh.indices[rng.below(mesh.indices.len() as u32) as usize];
        let a = mesh.positions[t[0] as usize];
        let b = mesh.positions[t[1] as usize];
        let target = if rng.next_f32() < 0.5 {
            a
        } else {
            (a + b) * 0.5
        };
        let origin = target + Vec3::new(rng.range_f32(-1.0, 1.0), 1.0, rng.range_f32(-1.0, 1.0));
        rays.push(Ray::new(origin, target - origin));
    }
    check_mesh(&mesh, &rays);
}

#[test]
fn axis_parallel_rays_and_flat_meshes_agree() {
    // A flat mesh (zero-thickness bounds in y) and rays along the axes,
    // which produce infinite reciprocal directions in the slab tests.
    let mut mesh = grid_with_duplicates(10, 12);
    for p in &mut mesh.positions {
        p.y = 0.5;
    }
    let mut rng = Pcg32::new(13);
    let mut rays = Vec::new();
    for _ in 0..3000 {
        let p = rng.in_box(Vec3::new(0.0, 0.5, 0.0), Vec3::new(1.0, 0.5, 1.0));
        rays.push(Ray::new(p + Vec3::Y, -Vec3::Y));
        rays.push(Ray::new(p - Vec3::Y * 2.0, Vec3::Y));
        rays.push(Ray::new(Vec3::new(-1.0, 0.5, p.z), Vec3::X));
    }
    check_mesh(&mesh, &rays);
}

#[test]
fn empty_mesh_never_hits() {
    let mesh = TriangleMesh::default();
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    for kind in AccelKind::ALL {
        for test in TestKind::ALL {
            let accel = build_accel(kind, test, &mesh, &BuildOptions::default());
            assert_eq!(accel.intersect(&ray), None);
            assert!(!accel.occluded(&ray));
        }
    }
}

#[test]
fn stats_describe_the_tree() {
    let mesh = random_soup(5000, 21);
    for kind in [AccelKind::Bvh2, AccelKind::ThreadedBvh] {
        let accel = build_accel(kind, TestKind::Moller, &mesh, &BuildOptions::default());
        let s = accel.stats();
        assert_eq!(s.triangle_refs, 5000);
        assert_eq!(s.nodes, 2 * s.leaves - 1, "binary tree");
        assert!(s.leaves >= 5000 / 4, "leaves hold at most 4 triangles");
        assert!(s.depth as usize >= (5000f64 / 4.0).log2().floor() as usize);
        assert!(
            s.sah_cost > 0.0 && s.sah_cost < 5000.0,
            "SAH cost {} is below brute force",
            s.sah_cost
        );
        let expected_bytes = match kind {
            // One 64-byte node per inner node, holding both children's boxes.
            AccelKind::Bvh2 => (s.leaves - 1) * 64,
            // One 32-byte node per node, leaves included.
            _ => s.nodes * 32,
        };
        assert_eq!(s.node_bytes, expected_bytes);
    }
}

/// The BVH layouts over trees from every builder (the
/// binned SAH, with wide nodes filled or not, and the fast linear
/// BVH) agree with brute force.
#[test]
fn bvhs_of_every_build_quality_agree_with_brute_force() {
    let meshes = [
        random_soup(3000, 41),
        grid_with_duplicates(30, 42),
        random_soup(40, 43),
        random_soup(1, 44),
    ];
    for quality in [BuildQuality::Sah, BuildQuality::High, BuildQuality::Fast] {
        for max_leaf_size in [1, 4, 16] {
            let opts = BuildOptions {
                quality,
                max_leaf_size,
                packed_leaf_size: max_leaf_size,
                ..BuildOptions::default()
            };
            for (i, mesh) in meshes.iter().enumerate() {
                let rays = random_rays(mesh, 2500, 50 + i as u64);
                eprintln!("quality {quality:?}, max leaf {max_leaf_size}, mesh {i}");
                check_kinds(
                    mesh,
                    &rays,
                    &opts,
                    &[
                        AccelKind::Bvh2,
                        AccelKind::Bvh4,
                        AccelKind::Bvh8,
                        AccelKind::ThreadedBvh,
                    ],
                );
            }
        }
    }
}

/// Rays whose origin or direction is not finite (NaN or infinite
/// components) hit nothing on every structure, one by one and in
/// batches (packets and interleaved walks), as brute force says: such a
/// ray's slab arithmetic gives NaNs, which the box tests' `min`/`max` drop,
/// and the wide BVHs once entered their unused slots' inverted boxes with
/// them (a crash).
#[test]
fn rays_that_are_not_finite_hit_nothing_on_every_structure() {
    let mesh = random_soup(3000, 17);
    let (nan, inf) = (f32::NAN, f32::INFINITY);
    let bad = [
        Ray::new(Vec3::new(0.5, 0.5, -2.0), Vec3::new(nan, nan, nan)),
        Ray::new(Vec3::new(0.5, 0.5, -2.0), Vec3::new(0.1, nan, 1.0)),
        Ray::new(Vec3::new(0.5, 0.5, -2.0), Vec3::new(inf, 1.0, 1.0)),
        Ray::new(Vec3::new(nan, 0.5, -2.0), Vec3::Z),
        Ray::new(Vec3::new(0.5, inf, -2.0), Vec3::Z),
        Ray::new(Vec3::new(-inf, 0.5, 0.5), Vec3::X),
    ];
    // Each bad ray alone, in a full packet of its copies, and among good
    // rays (a batch long enough for the interleaved walks).
    let good = random_rays(&mesh, 200, 5);
    let mut mixed = good.clone();
    for (i, r) in bad.iter().enumerate() {
        mixed[7 + 31 * i] = *r;
    }
    let brute = build_accel(
        AccelKind::Brute,
        TestKind::Moller,
        &mesh,
        &BuildOptions::default(),
    );
    for kind in AccelKind::ALL {
        let accel = build_accel(kind, TestKind::Moller, &mesh, &BuildOptions::default());
        for r in &bad {
            assert_eq!(brute.intersect(r), None);
            assert_eq!(accel.intersect(r), None, "{kind:?}: {r:?}");
            assert!(!accel.occluded(r), "{kind:?}: {r:?}");
        }
        let copies: Vec<Ray> = bad.iter().flat_map(|r| [*r; 16]).collect();
        for rays in [&copies, &mixed] {
            let mut hits = vec![None; rays.len()];
            accel.intersect_batch(rays, &mut hits);
            let mut occ = vec![false; rays.len()];
            accel.occluded_batch(rays, &mut occ);
            for (i, r) in rays.iter().enumerate() {
                let want = brute.intersect(r);
                assert!(agree(hits[i], want), "{kind:?}: batch ray {i} {r:?}");
                assert_eq!(occ[i], want.is_some(), "{kind:?}: batch ray {i} {r:?}");
            }
        }
    }
}

/// A point just outside an edge of triangle `prim` (outward in its plane)
/// or, with `corner`, beyond its first corner, `delta` of the first edge's
/// length away.
fn beside_edge(
    mesh: &TriangleMesh,
    prim: usize,
    delta: f32,
    corner: bool,
    rng: &mut Pcg32,
) -> Vec3 {
    let [a, b, c] = mesh.triangle(prim);
    if corner {
        a + (a - (a + b + c) / 3.0).normalize() * delta * (b - a).length()
    } else {
        let p = a + (b - a) * rng.next_f32();
        let e = (b - a).normalize();
        let away = (p - c) - e * (p - c).dot(e);
        p + away.normalize() * delta * (b - a).length()
    }
}

/// How many of `rays` brute force (Möller) reports on their `aimed`
/// triangle where the textbook test without tolerance misses it: rays
/// that meet the tolerance band.
fn band_hits(mesh: &TriangleMesh, rays: &[Ray], aimed: &[u32]) -> usize {
    use raykit_core::tri::{Moller, TriangleTest};
    let brute = build_accel(
        AccelKind::Brute,
        TestKind::Moller,
        mesh,
        &BuildOptions::default(),
    );
    rays.iter()
        .zip(aimed)
        .filter(|(r, &p)| {
            let [a, b, c] = mesh.triangle(p as usize);
            let tri = Moller::precompute(a, b, c);
            brute.intersect(r).is_some_and(|h| h.prim == p)
                && Moller::intersect_strict(&tri, r, f32::INFINITY).is_none()
        })
        .count()
}

/// The options of every builder with leaves of one and of sixteen
/// triangles, for the wide BVHs.
fn wide_build_options() -> impl Iterator<Item = BuildOptions> {
    [BuildQuality::Sah, BuildQuality::High, BuildQuality::Fast]
        .into_iter()
        .flat_map(|quality| {
            [1, 16].map(|leaf| BuildOptions {
                quality,
                max_leaf_size: leaf,
                packed_leaf_size: leaf,
                ..BuildOptions::default()
            })
        })
}

/// Every builder and leaf size of `Bvh4` and `Bvh8` against brute force.
fn check_wide_builds(mesh: &TriangleMesh, rays: &[Ray]) {
    for opts in wide_build_options() {
        check_kinds(mesh, rays, &opts, &[AccelKind::Bvh4, AccelKind::Bvh8]);
    }
}

/// Rays through the thin band outside a triangle's edges that the triangle
/// tests also count as hits (`tri::MAX_EDGE_TOLERANCE`), on a soup of tiny
/// triangles among large ones, so that most leaf and inner boxes are far
/// larger than the triangles whose bands they must hold. The wide BVHs
/// store each box as the union of its triangles' bands
/// (`TriangleTest::reach`), not padded by the box's own size, so these
/// are the rays a box too tight would lose. From near and from 10⁴ times
/// the model's size away, where the tests' rounding bounds, and so the
/// band, are widest.
#[test]
fn rays_through_the_edge_tolerance_band_agree_with_brute_force() {
    let mut mesh = soup::soup(600, 71, 0.0005, 0.003, 1);
    let large = soup::soup(12, 72, 0.2, 0.3, 1);
    let base = mesh.positions.len() as u32;
    mesh.positions.extend(&large.positions);
    mesh.indices
        .extend(large.indices.iter().map(|t| t.map(|i| i + base)));
    let mesh = TriangleMesh::new(mesh.positions, mesh.indices);
    let mut rng = Pcg32::new(73);
    let (mut rays, mut aimed) = (Vec::new(), Vec::new());
    let offsets = [1e-6f32, 1e-5, 1e-4, 1e-3, 3e-3];
    let distances = [0.01f32, 1.0, 100.0, 1e4];
    for i in 0..6000 {
        let prim = rng.below(mesh.indices.len() as u32);
        let delta = offsets[i % offsets.len()];
        let target = beside_edge(&mesh, prim as usize, delta, i % 4 == 0, &mut rng);
        let dist = distances[(i / offsets.len()) % distances.len()];
        let origin = target + rng.unit_vector() * dist;
        rays.push(Ray::new(origin, target - origin));
        aimed.push(prim);
    }
    let met = band_hits(&mesh, &rays, &aimed);
    assert!(met > 600, "only {met} rays hit inside the band");
    check_wide_builds(&mesh, &rays);
}

/// The band of a triangle square to an axis, whose box is thinnest across
/// its plane (`TriangleTest::reach`: Möller's and the projection test's
/// hits lie in the plane, so their boxes are only the clearance thick
/// there). Rays through the band of tiny axis-square triangles (some thin,
/// half of them 10³ triangle sizes from the origin) among large ones:
/// grazing the plane at 10⁻⁵ to 10⁻¹ radians or crossing it at random
/// angles, from near and far. The Plücker test's band is a tube around the
/// triangle, not a band in its plane: a box flat across the plane loses
/// some of its hits here, so its boxes keep the tube.
#[test]
fn rays_through_the_band_of_axis_square_triangles_agree_with_brute_force() {
    let mut rng = Pcg32::new(91);
    let axes = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (Vec3::Z, Vec3::X, Vec3::Y),
    ];
    let (mut positions, mut indices) = (Vec::new(), Vec::new());
    for i in 0..600 {
        let (_, e1, e2) = axes[i % 3];
        let shift = if i % 2 == 0 { 0.0 } else { 1.0 };
        let corner = rng.in_box(Vec3::ZERO, Vec3::ONE) + Vec3::splat(shift);
        let size = rng.range_f32(0.0005, 0.003);
        let base = positions.len() as u32;
        positions.extend([
            corner,
            corner + e1 * size,
            corner + e2 * size * rng.range_f32(0.02, 1.0),
        ]);
        indices.push([base, base + 1, base + 2]);
    }
    let large = soup::soup(12, 92, 0.2, 0.3, 1);
    let base = positions.len() as u32;
    positions.extend(&large.positions);
    indices.extend(large.indices.iter().map(|t| t.map(|i| i + base)));
    let mesh = TriangleMesh::new(positions, indices);
    let (mut rays, mut aimed) = (Vec::new(), Vec::new());
    let offsets = [1e-6f32, 1e-5, 1e-4, 1e-3, 3e-3];
    let distances = [0.01f32, 1.0, 100.0, 1e4];
    let grazes = [1e-5f32, 1e-4, 1e-3, 1e-2, 1e-1];
    for i in 0..6000 {
        let prim = rng.below(600) as usize;
        let (normal, e1, e2) = axes[prim % 3];
        let delta = offsets[i % offsets.len()];
        let target = beside_edge(&mesh, prim, delta, i % 4 == 0, &mut rng);
        let dir = if i % 3 == 0 {
            rng.unit_vector()
        } else {
            let angle = rng.range_f32(0.0, std::f32::consts::TAU);
            let along = e1 * angle.cos() + e2 * angle.sin();
            let side = if i % 2 == 0 { 1.0 } else { -1.0 };
            along + normal * side * grazes[(i / 3) % grazes.len()]
        };
        let dist = distances[(i / offsets.len()) % distances.len()];
        let origin = target - dir.normalize() * dist;
        rays.push(Ray::new(origin, target - origin));
        aimed.push(prim as u32);
    }
    let met = band_hits(&mesh, &rays, &aimed);
    assert!(met > 500, "only {met} rays hit inside the band");
    check_wide_builds(&mesh, &rays);
}

/// Coplanar faces square to an axis, as a CAD model's duplicated faces: two
/// flat grids in the plane y = 0.5, the second shifted by a third of a
/// cell, so that nearly every point of the plane lies on a triangle of each,
/// in different leaves. A ray meets the two at distances an ulp or a few
/// apart, and the wide BVHs must answer the nearer one exactly as brute
/// force does. A box flat in the plane would not always: its entry equals
/// those distances up to rounding, so a walk that had found the farther hit
/// first could prune it (`tri::reach`'s clearance).
#[test]
fn coplanar_faces_give_brute_forces_nearest_distance_exactly() {
    let n = 24;
    let mut rng = Pcg32::new(97);
    // Corners moved off the regular grid, so that each triangle's distances
    // round differently.
    let cell = 1.0 / n as f32;
    let mut jitter =
        |p: Vec3| p + Vec3::new(rng.range_f32(-0.3, 0.3), 0.0, rng.range_f32(-0.3, 0.3)) * cell;
    let first = soup::grid(n, || 0.37);
    let mut positions: Vec<Vec3> = first.positions.iter().map(|&p| jitter(p)).collect();
    let shift = Vec3::new(cell / 3.0, 0.0, cell / 3.0);
    positions.extend(first.positions.iter().map(|&p| jitter(p + shift)));
    let base = first.positions.len() as u32;
    let mut indices = first.indices.clone();
    indices.extend(first.indices.iter().map(|t| t.map(|i| i + base)));
    let mesh = TriangleMesh::new(positions, indices);
    // 40,000 rays: with boxes flat in the plane, 1 to 16 in 200,000 took
    // the farther hit.
    let rays: Vec<Ray> = (0..40_000)
        .map(|i| {
            let target = Vec3::new(rng.next_f32(), 0.37, rng.next_f32());
            let dir = if i % 2 == 0 {
                rng.unit_vector()
            } else {
                // Grazing the plane.
                let a = rng.range_f32(0.0, std::f32::consts::TAU);
                Vec3::new(a.cos(), rng.range_f32(-0.05, 0.05), a.sin())
            };
            let dist = [0.5f32, 2.0, 20.0][i % 3];
            let origin = target - dir.normalize() * dist;
            Ray::new(origin, target - origin)
        })
        .collect();
    for test in TestKind::ALL {
        let brute = build_accel(AccelKind::Brute, test, &mesh, &BuildOptions::default());
        let mut want = vec![None; rays.len()];
        brute.intersect_batch(&rays, &mut want);
        let hits = want.iter().flatten().count();
        assert!(hits > rays.len() / 2, "only {hits} rays hit the plane");
        for opts in wide_build_options() {
            for kind in [AccelKind::Bvh4, AccelKind::Bvh8] {
                let accel = build_accel(kind, test, &mesh, &opts);
                let mut got = vec![None; rays.len()];
                accel.intersect_batch(&rays, &mut got);
                let differ = (0..rays.len())
                    .filter(|&i| want[i].map(|h| h.t) != got[i].map(|h| h.t))
                    .count();
                assert_eq!(
                    differ,
                    0,
                    "{} × {} ({:?}, leaves of {}): {differ} of {} rays differ from brute force",
                    kind.name(),
                    test.name(),
                    opts.quality,
                    opts.max_leaf_size,
                    rays.len()
                );
            }
        }
    }
}
