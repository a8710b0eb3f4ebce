//! Kim's (2013) game queries (frustum culling, box and ball overlap) through
//! every acceleration structure give exactly the brute-force answers: the
//! same triangles and the same parts, on random soups, grids whose vertices
//! sit on the query boxes' faces, and meshes of several parts.

use raykit_core::accel::{build_accel, Accel, AccelKind, BuildOptions};
use raykit_core::query::{
    parts_in_box, parts_in_frustum, parts_in_sphere, parts_overlapping_brute, triangles_in_box,
    triangles_in_frustum, triangles_in_sphere, triangles_overlapping, triangles_overlapping_brute,
    Frustum, Plane, QueryShape, Sphere,
};
use raykit_core::rng::Pcg32;
use raykit_core::tri::TestKind;
use raykit_core::{Aabb, Camera, Part, TriangleMesh, Vec3};

mod soup;

/// A soup of `n` random triangles of varied size inside the unit cube.
fn random_soup(n: usize, seed: u64) -> TriangleMesh {
    soup::soup(n, seed, 0.002, 0.1, 3)
}

/// An `n` × `n` grid over [0, 1]² at height `y = h(x, z)`; with `flat` all
/// vertices lie on `y = 0.5` and on multiples of 1/n, where the query boxes
/// of [`grid_boxes`] put their faces.
fn grid(n: usize, flat: bool, seed: u64) -> TriangleMesh {
    let mut rng = Pcg32::new(seed);
    soup::grid(n, || if flat { 0.5 } else { 0.2 * rng.next_f32() })
}

/// Several soups, each a part, some far apart and some overlapping.
fn parts_mesh(seed: u64) -> TriangleMesh {
    let mut rng = Pcg32::new(seed);
    let mut mesh = TriangleMesh::default();
    for p in 0..12u32 {
        let mut soup = random_soup(20 + rng.below(200) as usize, seed * 100 + p as u64);
        let offset = rng.in_box(Vec3::splat(-1.5), Vec3::splat(1.5));
        let scale = rng.range_f32(0.1, 0.8);
        for v in &mut soup.positions {
            *v = *v * scale + offset;
        }
        soup.parts = vec![Part {
            name: format!("part{p}"),
            node: None,
        }];
        soup.tri_part = vec![0; soup.num_triangles()];
        mesh.append(&soup);
    }
    mesh
}

/// A random camera frustum around `mesh`: eyes inside and outside, narrow
/// and wide fields of view, thin and deep depth ranges.
fn random_frustum(rng: &mut Pcg32, mesh: &TriangleMesh) -> Frustum {
    let bounds = &mesh.bounds();
    let c = bounds.center();
    let r = bounds.diagonal().max(1e-3);
    let eye = if rng.next_f32() < 0.3 {
        rng.in_box(bounds.min, bounds.max)
    } else {
        c + rng.unit_vector() * r * rng.range_f32(0.6, 3.0)
    };
    let target = random_center(rng, mesh);
    let camera = Camera {
        eye,
        target,
        up: rng.unit_vector(),
        vfov_deg: [1.0, 20.0, 60.0, 120.0, 170.0][rng.below(5) as usize],
    };
    let aspect = rng.range_f32(0.3, 3.0);
    let near = r * [0.0, 1e-4, 0.01, 0.5][rng.below(4) as usize];
    let far = near + r * [1e-3, 0.05, 1.0, 100.0][rng.below(4) as usize];
    Frustum::from_camera(&camera, aspect, near, far)
}

/// A centre for a query shape: half the time a point of a random triangle
/// (so that tiny shapes find something), else anywhere around the mesh.
fn random_center(rng: &mut Pcg32, mesh: &TriangleMesh) -> Vec3 {
    let b = mesh.bounds();
    let r = b.diagonal().max(1e-3);
    if mesh.num_triangles() > 0 && rng.next_f32() < 0.5 {
        let [p, q, s] = mesh.triangle(rng.below(mesh.num_triangles() as u32) as usize);
        let (u, v) = (rng.next_f32(), rng.next_f32());
        let (u, v) = if u + v > 1.0 {
            (1.0 - u, 1.0 - v)
        } else {
            (u, v)
        };
        p + (q - p) * u + (s - p) * v
    } else {
        rng.in_box(b.min - r * 0.2, b.max + r * 0.2)
    }
}

/// A random box around `mesh`, from tiny to far larger than the mesh,
/// some flat (zero thickness on an axis).
fn random_box(rng: &mut Pcg32, mesh: &TriangleMesh) -> Aabb {
    let r = mesh.bounds().diagonal().max(1e-3);
    let c = random_center(rng, mesh);
    let size = r * [1e-5, 1e-3, 0.05, 0.3, 10.0][rng.below(5) as usize];
    let mut h = rng.in_box(Vec3::ZERO, Vec3::splat(size));
    if rng.next_f32() < 0.1 {
        h[rng.below(3) as usize] = 0.0;
    }
    Aabb::new(c - h, c + h)
}

/// A random ball around `mesh`, radius from 0 to far larger than the mesh.
fn random_sphere(rng: &mut Pcg32, mesh: &TriangleMesh) -> Sphere {
    let r = mesh.bounds().diagonal().max(1e-3);
    let c = random_center(rng, mesh);
    let radius = r * [0.0, 1e-5, 1e-3, 0.05, 0.3, 10.0][rng.below(6) as usize];
    Sphere::new(c, radius * rng.next_f32())
}

/// Boxes whose faces lie on the grid lines of [`grid`] (multiples of 1/n)
/// and on its plane, so that triangles touch them in edges and corners.
fn grid_boxes(rng: &mut Pcg32, n: usize) -> Vec<Aabb> {
    let at = |i: u32| i as f32 / n as f32;
    (0..60)
        .map(|_| {
            let (x0, z0) = (rng.below(n as u32 + 1), rng.below(n as u32 + 1));
            let (x1, z1) = (x0 + rng.below(4), z0 + rng.below(4));
            let (y0, y1) =
                [(0.5, 0.5), (0.0, 0.5), (0.5, 1.0), (0.6, 1.0), (0.0, 1.0)][rng.below(5) as usize];
            Aabb::new(Vec3::new(at(x0), y0, at(z0)), Vec3::new(at(x1), y1, at(z1)))
        })
        .collect()
}

fn accels(mesh: &TriangleMesh) -> Vec<(AccelKind, BuildOptions, Box<dyn Accel>)> {
    let mut out = Vec::new();
    for kind in AccelKind::ALL {
        for leaf in [1, 4] {
            let opts = BuildOptions {
                max_leaf_size: leaf,
                ..BuildOptions::default()
            };
            let accel = build_accel(kind, TestKind::Moller, mesh, &opts);
            out.push((kind, opts, accel));
        }
    }
    out
}

/// Every structure answers every shape as brute force does. Returns the
/// regions pruned over all trees (pruning must happen) and the number of
/// shapes that hold some but not all triangles (the cases worth testing).
fn check<S: QueryShape + std::fmt::Debug>(mesh: &TriangleMesh, shapes: &[S]) -> (usize, usize) {
    let mut pruned = 0;
    let wanted: Vec<Vec<u32>> = shapes
        .iter()
        .map(|s| triangles_overlapping_brute(mesh, s))
        .collect();
    let partial = wanted
        .iter()
        .filter(|w| !w.is_empty() && w.len() < mesh.num_triangles())
        .count();
    for (kind, opts, accel) in accels(mesh) {
        for (shape, want) in shapes.iter().zip(&wanted) {
            let got = triangles_overlapping(accel.as_ref(), mesh, shape);
            assert_eq!(
                &got.ids,
                want,
                "{} (leaf {}): {shape:?}",
                kind.name(),
                opts.max_leaf_size
            );
            assert!(got.stats.triangles_tested <= mesh.num_triangles());
            assert!(got.stats.triangles_tested <= got.stats.triangle_refs);
            pruned += got.stats.regions_pruned;
        }
    }
    (pruned, partial)
}

fn meshes() -> Vec<TriangleMesh> {
    vec![
        random_soup(1, 1),
        random_soup(5, 2),
        random_soup(300, 3),
        random_soup(3000, 4),
        grid(24, false, 5),
        grid(16, true, 6),
    ]
}

#[test]
fn frustum_queries_agree_with_brute_force() {
    let mut rng = Pcg32::new(21);
    for mesh in meshes() {
        let shapes: Vec<Frustum> = (0..150).map(|_| random_frustum(&mut rng, &mesh)).collect();
        let (pruned, partial) = check(&mesh, &shapes);
        if mesh.num_triangles() > 100 {
            assert!(
                pruned > 0 && partial > 30,
                "{pruned} pruned, {partial} partial"
            );
        }
    }
}

#[test]
fn box_queries_agree_with_brute_force() {
    let mut rng = Pcg32::new(22);
    for mesh in meshes() {
        let mut shapes: Vec<Aabb> = (0..200).map(|_| random_box(&mut rng, &mesh)).collect();
        shapes.push(mesh.bounds());
        shapes.push(Aabb::EMPTY);
        let (pruned, partial) = check(&mesh, &shapes);
        if mesh.num_triangles() > 100 {
            assert!(
                pruned > 0 && partial > 40,
                "{pruned} pruned, {partial} partial"
            );
        }
    }
}

#[test]
fn sphere_queries_agree_with_brute_force() {
    let mut rng = Pcg32::new(23);
    for mesh in meshes() {
        let shapes: Vec<Sphere> = (0..200).map(|_| random_sphere(&mut rng, &mesh)).collect();
        let (pruned, partial) = check(&mesh, &shapes);
        if mesh.num_triangles() > 100 {
            assert!(
                pruned > 0 && partial > 40,
                "{pruned} pruned, {partial} partial"
            );
        }
    }
}

#[test]
fn boxes_touching_grid_edges_and_corners_agree() {
    let n = 16;
    let mesh = grid(n, true, 7);
    let mut rng = Pcg32::new(24);
    let boxes = grid_boxes(&mut rng, n);
    let (_, partial) = check(&mesh, &boxes);
    assert!(partial > 30, "{partial} partial");
    // A box on the grid plane covering one cell touches that cell's two
    // triangles and every triangle with a corner or edge on its border.
    let cell = Aabb::new(Vec3::new(0.25, 0.5, 0.25), Vec3::new(0.3125, 0.5, 0.3125));
    let found = triangles_overlapping_brute(&mesh, &cell);
    assert!(found.len() >= 2 + 6, "found only {found:?}");
    // A box above the plane, touching it only from above, still overlaps.
    let above = Aabb::new(Vec3::new(0.2, 0.5, 0.2), Vec3::new(0.4, 0.7, 0.4));
    assert!(!triangles_overlapping_brute(&mesh, &above).is_empty());
    let lifted = Aabb::new(Vec3::new(0.2, 0.5001, 0.2), Vec3::new(0.4, 0.7, 0.4));
    assert!(triangles_overlapping_brute(&mesh, &lifted).is_empty());
}

#[test]
fn frustum_from_explicit_planes_agrees() {
    // Axis-aligned slabs written as planes: the same answers as the box.
    let mesh = random_soup(500, 8);
    let mut rng = Pcg32::new(25);
    for _ in 0..50 {
        let q = random_box(&mut rng, &mesh);
        let (lo, hi) = (q.min.as_dvec3(), q.max.as_dvec3());
        let e = raykit_core::glam::DVec3::AXES;
        let f = Frustum::from_planes([
            Plane::new(e[0], -lo.x),
            Plane::new(-e[0], hi.x),
            Plane::new(e[1], -lo.y),
            Plane::new(-e[1], hi.y),
            Plane::new(e[2], -lo.z),
            Plane::new(-e[2], hi.z),
        ]);
        let want = triangles_overlapping_brute(&mesh, &q);
        assert_eq!(triangles_overlapping_brute(&mesh, &f), want);
        for (kind, _, accel) in accels(&mesh) {
            assert_eq!(
                triangles_in_frustum(accel.as_ref(), &mesh, &f),
                want,
                "{}",
                kind.name()
            );
        }
    }
}

#[test]
fn part_queries_agree_with_brute_force() {
    let mut rng = Pcg32::new(26);
    for seed in [1, 2] {
        let mesh = parts_mesh(seed);
        assert!(mesh.validate().is_ok());
        let built = accels(&mesh);
        let mut nonempty = 0;
        for _ in 0..100 {
            let f = random_frustum(&mut rng, &mesh);
            let q = random_box(&mut rng, &mesh);
            let s = random_sphere(&mut rng, &mesh);
            let want = [
                parts_overlapping_brute(&mesh, &f),
                parts_overlapping_brute(&mesh, &q),
                parts_overlapping_brute(&mesh, &s),
            ];
            nonempty += want.iter().filter(|w| !w.is_empty()).count();
            for (kind, _, accel) in &built {
                let a = accel.as_ref();
                let got = [
                    parts_in_frustum(a, &mesh, &f),
                    parts_in_box(a, &mesh, &q),
                    parts_in_sphere(a, &mesh, &s),
                ];
                assert_eq!(got, want, "{}", kind.name());
                // The triangle forms agree with their parts.
                let mut from_tris: Vec<u32> = triangles_in_box(a, &mesh, &q)
                    .iter()
                    .map(|&t| mesh.part_of(t as usize))
                    .collect();
                from_tris.sort_unstable();
                from_tris.dedup();
                assert_eq!(from_tris, want[1]);
                let _ = triangles_in_sphere(a, &mesh, &s);
            }
        }
        assert!(nonempty > 50, "too few queries found anything");
    }
}

#[test]
fn empty_mesh_and_degenerate_shapes_find_nothing() {
    let empty = TriangleMesh::default();
    let mesh = random_soup(50, 9);
    for (kind, _, accel) in accels(&empty) {
        let q = Aabb::new(Vec3::splat(-1e9), Vec3::splat(1e9));
        assert!(triangles_in_box(accel.as_ref(), &empty, &q).is_empty());
        let _ = kind;
    }
    for (kind, _, accel) in accels(&mesh) {
        let a = accel.as_ref();
        let nan = Sphere::new(Vec3::splat(0.5), f32::NAN);
        assert!(
            triangles_in_sphere(a, &mesh, &nan).is_empty(),
            "{}",
            kind.name()
        );
        let neg = Sphere::new(Vec3::splat(0.5), -1.0);
        assert!(triangles_in_sphere(a, &mesh, &neg).is_empty());
        assert!(triangles_in_box(a, &mesh, &Aabb::EMPTY).is_empty());
        let all = Aabb::new(Vec3::splat(-1.0), Vec3::splat(2.0));
        assert_eq!(triangles_in_box(a, &mesh, &all).len(), mesh.num_triangles());
    }
}
