//! Traversals longer than a driver's loop limit: Mesa's lavapipe ends every
//! loop of an invocation once it has made 65,535 loop passes in all, so a
//! long traversal would silently return a wrong answer. The kernels detect
//! a loop that ended with its condition still true, and the host refuses
//! the results with [`GpuError::LoopLimit`]; everywhere else the GPU gives
//! the CPU's answers, and ordinary scenes are never refused.

mod support;

use glam::Vec3;
use raykit_core::accel::{Accel, BruteForce, BuildOptions};
use raykit_core::raysets::standard_sets;
use raykit_core::tri::{Moller, TestKind};
use raykit_core::{Hit, Ray, TriangleMesh};
use raykit_gpu::{GpuAccelKind, GpuError, GpuScene, GpuTracer};
use support::{compare, gpu, shared_data};

/// `n` equal triangles stacked along z, triangle k at z = -k: a ray along
/// z crosses every one, and the threaded BVH's pre-order walk visits most
/// of its nodes whichever way the ray goes.
fn stack(n: usize) -> TriangleMesh {
    let mut v = Vec::with_capacity(3 * n);
    for k in 0..n {
        let z = -(k as f32);
        v.push(Vec3::new(-1.0, -1.0, z));
        v.push(Vec3::new(1.0, -1.0, z));
        v.push(Vec3::new(0.0, 1.0, z));
    }
    let idx = (0..n as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    TriangleMesh::new(v, idx)
}

fn is_lavapipe() -> bool {
    gpu().info.name.contains("llvmpipe")
}

/// Nearest hits and occlusion on `kind`: the CPU's answers, or the loop
/// limit error; returns whether the nearest hits were refused.
fn exact_or_refused(
    mesh: &TriangleMesh,
    kind: GpuAccelKind,
    rays: &[Ray],
    want: &[Option<Hit>],
    occluded: &[bool],
) -> bool {
    let ctx = gpu();
    let scene =
        GpuScene::build(ctx, mesh, kind, TestKind::Moller, &BuildOptions::default()).unwrap();
    let tracer = GpuTracer::new(ctx, &scene).unwrap();
    let refused = |e: GpuError| {
        assert!(
            matches!(e, GpuError::LoopLimit { .. }),
            "{}: unexpected error {e}",
            kind.name()
        );
        let msg = e.to_string();
        assert!(
            msg.contains("loop") && msg.contains("--backend cpu"),
            "{msg}"
        );
        eprintln!("{}: refused: {msg}", kind.name());
    };
    let near = match tracer.intersect_batch(rays) {
        Ok(got) => {
            assert_eq!(
                got,
                want,
                "{}: nearest hits differ from the CPU's",
                kind.name()
            );
            false
        }
        Err(e) => {
            refused(e);
            true
        }
    };
    match tracer.occluded_batch(rays) {
        Ok(got) => assert_eq!(got, occluded, "{}: occlusion differs", kind.name()),
        Err(e) => refused(e),
    }
    near
}

#[test]
fn traversals_past_the_loop_limit_are_exact_or_refused() {
    // 100,000 triangles: the upward ray's nearest hit is triangle 99,999,
    // found by brute force only after 99,999 passes of its loop.
    let mesh = stack(100_000);
    let rays = [
        Ray::new(Vec3::new(0.01, 0.02, 10.0), Vec3::new(0.0, 0.0, -1.0)),
        Ray::new(Vec3::new(0.01, 0.02, -200_000.0), Vec3::new(0.0, 0.0, 1.0)),
    ];
    let cpu = BruteForce::<Moller>::new(&mesh);
    let mut want = vec![None; rays.len()];
    cpu.intersect_batch(&rays, &mut want);
    assert_eq!(want[0].map(|h| h.prim), Some(0));
    assert_eq!(want[1].map(|h| h.prim), Some(99_999));
    let mut occluded = vec![false; rays.len()];
    cpu.occluded_batch(&rays, &mut occluded);
    for kind in GpuAccelKind::ALL {
        let refused = exact_or_refused(&mesh, kind, &rays, &want, &occluded);
        if is_lavapipe() && matches!(kind, GpuAccelKind::Brute | GpuAccelKind::BvhThreaded) {
            assert!(
                refused,
                "{}: lavapipe's loop limit went unnoticed",
                kind.name()
            );
        }
    }
}

#[test]
fn ordinary_scenes_are_not_refused() {
    let ctx = gpu();
    let mesh = raykit_io::load_mesh(&shared_data().join("meshes/bunny_3674.obj")).unwrap();
    let reference = BruteForce::<Moller>::new(&mesh);
    let sets = standard_sets(&mesh, &reference, 32, 5);
    for kind in GpuAccelKind::ALL {
        let scene =
            GpuScene::build(ctx, &mesh, kind, TestKind::Moller, &BuildOptions::default()).unwrap();
        let tracer = GpuTracer::new(ctx, &scene).unwrap();
        for rays in &sets {
            let mut want = vec![None; rays.len()];
            reference.intersect_batch(rays, &mut want);
            let got = tracer
                .intersect_batch(rays)
                .unwrap_or_else(|e| panic!("{}: {e}", kind.name()));
            let d = compare(&want, &got);
            assert!(
                d.hit_miss.is_empty() && d.distance.is_empty(),
                "{}: {d:?}",
                kind.name()
            );
            tracer
                .occluded_batch(rays)
                .unwrap_or_else(|e| panic!("{}: {e}", kind.name()));
        }
    }
}
