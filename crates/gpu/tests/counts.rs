//! The counting kernels count what the traversal fetches: brute force
//! tests every triangle record of every ray, so its counts are known
//! exactly; the structures visit fewer nodes than they hold and at least
//! one per ray.

mod support;

use raykit_core::accel::{BruteForce, BuildOptions};
use raykit_core::raysets::standard_sets;
use raykit_core::tri::{Moller, TestKind};
use raykit_gpu::{count_traversal, GpuAccelKind, GpuScene};
use support::{gpu, shared_data};

#[test]
fn brute_force_counts_every_record_of_every_ray() {
    let mesh = raykit_io::load_mesh(&shared_data().join("meshes/bunny_3674.obj")).unwrap();
    let reference = BruteForce::<Moller>::new(&mesh);
    let sets = standard_sets(&mesh, &reference, 128, 5);
    let n = mesh.num_triangles() as u64;
    for (test, record) in [(TestKind::Plucker, 112u64), (TestKind::Moller, 44)] {
        let scene = GpuScene::build(
            gpu(),
            &mesh,
            GpuAccelKind::Brute,
            test,
            &BuildOptions::default(),
        )
        .unwrap();
        // 16,384 rays × 3,674 records × 112 bytes passes 2^32: the
        // counters carry into their high words.
        let c = count_traversal(gpu(), &scene, &sets[0], false).unwrap();
        let rays = sets[0].len() as u64;
        assert_eq!(c.rays, rays);
        assert_eq!(c.nodes, 0);
        assert_eq!(c.tris, rays * n, "{}", test.name());
        assert_eq!(c.bytes, rays * n * record, "{}", test.name());
    }
}

#[test]
fn structures_count_a_few_nodes_per_ray() {
    let mesh = raykit_io::load_mesh(&shared_data().join("meshes/dragon_vrip_res4.ply.gz")).unwrap();
    let reference = BruteForce::<Moller>::new(&mesh);
    let sets = standard_sets(&mesh, &reference, 48, 5);
    for kind in [
        GpuAccelKind::KdStack,
        GpuAccelKind::KdRopes,
        GpuAccelKind::BvhThreaded,
        GpuAccelKind::Cwbvh,
    ] {
        let scene = GpuScene::build(
            gpu(),
            &mesh,
            kind,
            TestKind::Moller,
            &BuildOptions::default(),
        )
        .unwrap();
        for (set, any) in [(0, false), (1, true), (2, false)] {
            let c = count_traversal(gpu(), &scene, &sets[set], any).unwrap();
            eprintln!(
                "{} set {set}: {:.1} nodes, {:.1} triangles, {:.0} bytes per ray",
                kind.name(),
                c.nodes_per_ray(),
                c.tris_per_ray(),
                c.bytes_per_ray()
            );
            // Every ray fetches the root; none visits the whole tree.
            assert!(c.nodes >= c.rays, "{}", kind.name());
            assert!(c.nodes_per_ray() < scene.num_nodes as f64 / 4.0);
            assert!(c.tris_per_ray() < mesh.num_triangles() as f64 / 4.0);
            assert!(c.bytes as f64 >= 44.0 * c.tris as f64);
        }
    }
}

/// The counts on a mesh named by `RAYKIT_COUNT_MESH` (the full dragon for
/// the GPU prediction in BENCHMARKS.md), every structure × test, printed;
/// `cargo test -p raykit-gpu --test counts -- --ignored --nocapture`.
#[test]
#[ignore = "needs RAYKIT_COUNT_MESH; minutes on lavapipe"]
fn counts_on_a_large_mesh() {
    let path = std::env::var("RAYKIT_COUNT_MESH").expect("set RAYKIT_COUNT_MESH to a mesh file");
    let size: u32 = std::env::var("RAYKIT_COUNT_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(128);
    let mesh = raykit_io::load_mesh(std::path::Path::new(&path)).unwrap();
    let helper = raykit_core::accel::Bvh2::<Moller>::build(&mesh, &BuildOptions::default());
    let sets = standard_sets(&mesh, &helper, size, 1);
    for test in [TestKind::Plucker, TestKind::Moller] {
        for kind in [
            GpuAccelKind::KdStack,
            GpuAccelKind::KdRopes,
            GpuAccelKind::BvhThreaded,
            GpuAccelKind::Cwbvh,
        ] {
            let scene =
                GpuScene::build(gpu(), &mesh, kind, test, &BuildOptions::default()).unwrap();
            for (set, any) in [("primary", false), ("shadow", true), ("incoherent", false)] {
                let i = ["primary", "shadow", "incoherent"]
                    .iter()
                    .position(|s| *s == set)
                    .unwrap();
                let c = count_traversal(gpu(), &scene, &sets[i], any).unwrap();
                let n = c.nodes as f64 / c.rays.max(1) as f64;
                assert!(c.nodes >= c.rays);
                println!(
                    "COUNT {} {} {} {set}: {} rays, {n:.1} nodes, {:.1} tris, {:.0} bytes per ray; node bytes {}",
                    mesh.num_triangles(),
                    kind.name(),
                    test.name(),
                    c.rays,
                    c.tris_per_ray(),
                    c.bytes_per_ray(),
                    scene.node_bytes
                );
            }
        }
    }
}
