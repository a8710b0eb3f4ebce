//! The structures of Kim et al.'s GPU stream ray tracer — the run-of-eight
//! [`LinearBoxes`] and the complete threaded BVH in mesh order
//! ([`ThreadedBvh::complete`]) — agree with brute force on the shared
//! meshes and random rays (nearest hit up to ties, occlusion exactly), and
//! the complete tree visits its one-triangle leaves in index order.

mod shared_meshes;

use raykit_core::accel::{Accel, BruteForce, LinearBoxes, ThreadedBvh, LINEAR_BOX_SIZE};
use raykit_core::rng::Pcg32;
use raykit_core::tri::Moller;
use raykit_core::{Aabb, TriangleMesh, Vec3};
use shared_meshes::{agree, rays, shared_obj};

/// The shared meshes, and a random soup (incoherent mesh order: loose
/// boxes) with a count that is neither a power of two nor a multiple of 8.
fn meshes() -> Vec<(String, TriangleMesh)> {
    let mut rng = Pcg32::new(41);
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for i in 0..1001u32 {
        let c = rng.in_box(Vec3::ZERO, Vec3::ONE);
        for _ in 0..3 {
            positions.push(c + rng.unit_vector() * 0.05);
        }
        indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    vec![
        ("teapot_992.obj".into(), shared_obj("teapot_992.obj")),
        ("bunny_3674.obj".into(), shared_obj("bunny_3674.obj")),
        ("soup 1001".into(), TriangleMesh::new(positions, indices)),
    ]
}

fn check_against_brute(name: &str, mesh: &TriangleMesh, accel: &dyn Accel) {
    let brute = BruteForce::<Moller>::new(mesh);
    let rays = rays(mesh, 3000, 7);
    let mut hits = 0;
    for (i, r) in rays.iter().enumerate() {
        let (a, b) = (accel.intersect(r), brute.intersect(r));
        assert!(
            agree(a, b),
            "{name}: ray {i}: {a:?} against brute force {b:?}"
        );
        assert_eq!(accel.occluded(r), brute.occluded(r), "{name}: ray {i}");
        hits += b.is_some() as usize;
    }
    assert!(hits > 300, "{name}: only {hits} of 3000 rays hit");
}

#[test]
fn linear_boxes_agree_with_brute_force() {
    for (name, mesh) in meshes() {
        let boxes = LinearBoxes::<Moller>::new(&mesh);
        assert_eq!(
            boxes.num_boxes(),
            mesh.num_triangles().div_ceil(LINEAR_BOX_SIZE)
        );
        check_against_brute(&name, &mesh, &boxes);
    }
}

#[test]
fn complete_threaded_bvh_agrees_with_brute_force() {
    for (name, mesh) in meshes() {
        check_against_brute(&name, &mesh, &ThreadedBvh::<Moller>::complete(&mesh));
    }
}

#[test]
fn complete_threaded_bvh_is_a_complete_tree_in_index_order() {
    for (name, mesh) in meshes() {
        let n = mesh.num_triangles();
        let bvh = ThreadedBvh::<Moller>::complete(&mesh);
        let mut leaves = Vec::new();
        let mut regions: Vec<Aabb> = Vec::new();
        bvh.visit_regions(
            &mut |b| {
                regions.push(*b);
                true
            },
            &mut |prims| leaves.push(prims.to_vec()),
        );
        // Pre-order with every region accepted reaches each one-triangle leaf
        // once, in mesh index order.
        let expected: Vec<Vec<u32>> = (0..n as u32).map(|i| vec![i]).collect();
        assert_eq!(leaves, expected, "{name}");
        // A binary tree with n leaves has 2n - 1 nodes; a complete one has
        // depth ⌈log2 n⌉.
        let stats = bvh.stats();
        assert_eq!(stats.nodes, 2 * n - 1, "{name}");
        assert_eq!(stats.leaves, n, "{name}");
        assert_eq!(
            stats.depth,
            n.next_power_of_two().trailing_zeros(),
            "{name}"
        );
        assert_eq!(regions.len(), 2 * n - 1, "{name}");
        // The root region holds every triangle.
        for i in 0..n {
            let t = mesh.triangle_bounds(i);
            assert!(
                regions[0].contains(t.min) && regions[0].contains(t.max),
                "{name}: triangle {i}"
            );
        }
    }
}

#[test]
fn empty_mesh_gives_no_hits() {
    let mesh = TriangleMesh::new(Vec::new(), Vec::new());
    let r = raykit_core::Ray::new(Vec3::ZERO, Vec3::X);
    for accel in [
        &LinearBoxes::<Moller>::new(&mesh) as &dyn Accel,
        &ThreadedBvh::<Moller>::complete(&mesh),
    ] {
        assert!(accel.intersect(&r).is_none());
        assert!(!accel.occluded(&r));
    }
}
