//! The GPU kernels give the CPU's answers: every structure × test on the
//! built-in scenes and the test meshes, the standard primary, shadow and
//! incoherent ray sets, nearest hits and occlusion.

mod support;

use raykit_core::accel::{
    Accel, BruteForce, BuildOptions, Bvh8, KdOptions, KdRopes, KdStack, ThreadedBvh,
};
use raykit_core::raysets::standard_sets;
use raykit_core::tri::{Moller, Plucker, TestKind, TriangleTest};
use raykit_core::TriangleMesh;
use raykit_gpu::cwbvh::cwbvh_build_options;
use raykit_gpu::{GpuAccelKind, GpuScene, GpuTracer};
use support::{compare, describe, gpu, shared_data};

fn cpu_accel<T: TriangleTest>(mesh: &TriangleMesh, kind: GpuAccelKind) -> Box<dyn Accel> {
    match kind {
        GpuAccelKind::KdStack => Box::new(KdStack::<T>::build(mesh, &KdOptions::default())),
        GpuAccelKind::KdRopes => Box::new(KdRopes::<T>::build(mesh, &KdOptions::default())),
        GpuAccelKind::BvhThreaded => {
            Box::new(ThreadedBvh::<T>::build(mesh, &BuildOptions::default()))
        }
        GpuAccelKind::Cwbvh => Box::new(Bvh8::<T>::build(
            mesh,
            &cwbvh_build_options(&BuildOptions::default()),
        )),
        GpuAccelKind::Brute => Box::new(BruteForce::<T>::new(mesh)),
    }
}

/// Trace the standard sets on CPU and GPU for every structure × test and
/// require the same answers: hit/miss equal on every ray, `t` within 1e-4
/// relative, differing triangles only at equal `t` (shared edges); at most
/// `grazing` hit/miss differences per set are allowed for rays that the two
/// f32 pipelines round differently at a silhouette, and each of those must
/// be a ray whose CPU answer is within the triangle tests' edge band.
fn agree(name: &str, mesh: &TriangleMesh, size: u32, kinds: &[GpuAccelKind]) {
    let ctx = gpu();
    let reference = BruteForce::<Moller>::new(mesh);
    let sets = standard_sets(mesh, &reference, size, 7);
    for &kind in kinds {
        for test in [TestKind::Plucker, TestKind::Moller] {
            let cpu: Box<dyn Accel> = match test {
                TestKind::Plucker => cpu_accel::<Plucker>(mesh, kind),
                _ => cpu_accel::<Moller>(mesh, kind),
            };
            let scene = GpuScene::build(ctx, mesh, kind, test, &BuildOptions::default()).unwrap();
            let tracer = GpuTracer::new(ctx, &scene).unwrap();
            for (set, rays) in ["primary", "shadow", "incoherent"].iter().zip(&sets) {
                let mut want = vec![None; rays.len()];
                cpu.intersect_batch(rays, &mut want);
                let got = tracer.intersect_batch(rays).unwrap();
                let d = compare(&want, &got);
                let label = format!("{name} {} {} {set}", kind.name(), test.name());
                eprintln!(
                    "{label}: {} rays, {} hit/miss, {} distance, {} ties, {} barycentrics",
                    rays.len(),
                    d.hit_miss.len(),
                    d.distance.len(),
                    d.ties,
                    d.bary
                );
                assert!(
                    d.hit_miss.is_empty() && d.distance.is_empty(),
                    "{label}: GPU and CPU disagree\n{}\n{}",
                    describe(rays, &d.hit_miss, &want, &got),
                    describe(rays, &d.distance, &want, &got)
                );
                // A different triangle only at exactly the same distance
                // (a shared edge or vertex, or coincident triangles): the
                // structures test a node's triangles in different orders.
                let near: Vec<usize> = (0..rays.len())
                    .filter(|&i| match (want[i], got[i]) {
                        (Some(c), Some(g)) => c.prim != g.prim && c.t != g.t,
                        _ => false,
                    })
                    .collect();
                assert!(
                    near.is_empty(),
                    "{label}: other triangle at another distance\n{}",
                    describe(rays, &near, &want, &got)
                );
                let mut occ = vec![false; rays.len()];
                cpu.occluded_batch(rays, &mut occ);
                let gocc = tracer.occluded_batch(rays).unwrap();
                let bad: Vec<usize> = (0..rays.len()).filter(|&i| occ[i] != gocc[i]).collect();
                assert!(
                    bad.is_empty(),
                    "{label}: occlusion differs on {} rays, first {:?}",
                    bad.len(),
                    &bad[..bad.len().min(5)]
                );
                // Occlusion agrees with the nearest hit on both sides.
                assert!(
                    (0..rays.len()).all(|i| gocc[i] == got[i].is_some()),
                    "{label}: GPU occlusion != GPU hit"
                );
            }
        }
    }
}

#[test]
fn builtin_scenes_agree_with_cpu() {
    for spec in ["cornell", "shirley6", "scatter:triangles=20000"] {
        let scene = raykit_scene::builtin(spec).unwrap();
        agree(spec, &scene.mesh, 64, &GpuAccelKind::ALL);
    }
}

#[test]
fn shared_meshes_agree_with_cpu() {
    let dir = shared_data().join("meshes");
    for file in ["bunny_3674.obj", "teapot_992.obj", "bearing.stl"] {
        let mesh = raykit_io::load_mesh(&dir.join(file)).unwrap();
        agree(
            file,
            &mesh,
            96,
            &[
                GpuAccelKind::KdStack,
                GpuAccelKind::KdRopes,
                GpuAccelKind::BvhThreaded,
                GpuAccelKind::Cwbvh,
            ],
        );
    }
    let dragon = raykit_io::load_mesh(&dir.join("dragon_vrip_res4.ply.gz")).unwrap();
    agree(
        "dragon_res4",
        &dragon,
        96,
        &[
            GpuAccelKind::KdStack,
            GpuAccelKind::KdRopes,
            GpuAccelKind::BvhThreaded,
            GpuAccelKind::Cwbvh,
        ],
    );
}

#[test]
fn scenes_beyond_a_device_limit_fail_naming_the_limit() {
    let mut small = gpu().clone();
    eprintln!(
        "adapter limits: max_storage_buffer_binding_size {}, max_buffer_size {}",
        small.limits.max_storage_buffer_binding_size, small.limits.max_buffer_size
    );
    // A device that allows 4 KiB per binding cannot hold the bunny's
    // 3,674 triangle records.
    small.limits.max_storage_buffer_binding_size = 4096;
    let mesh = raykit_io::load_mesh(&shared_data().join("meshes/bunny_3674.obj")).unwrap();
    let err = GpuScene::build(
        &small,
        &mesh,
        GpuAccelKind::KdStack,
        TestKind::Plucker,
        &BuildOptions::default(),
    )
    .err()
    .expect("the scene does not fit");
    let msg = err.to_string();
    assert!(
        msg.contains("max_storage_buffer_binding_size") && msg.contains("4096"),
        "{msg}"
    );
    // Projection has no kernel: a clear error, not a wrong answer.
    let err = GpuScene::build(
        gpu(),
        &mesh,
        GpuAccelKind::KdStack,
        TestKind::Projection,
        &BuildOptions::default(),
    )
    .err()
    .expect("projection is refused");
    assert!(err.to_string().contains("projection"), "{err}");
}

#[test]
fn triangle_records_split_across_bindings_give_the_same_answers() {
    // A device allowing 160 KiB per binding holds the bunny's nodes but
    // needs three bindings for its 411 KB of Plücker records.
    let mut small = gpu().clone();
    small.limits.max_storage_buffer_binding_size = 160 * 1024;
    let mesh = raykit_io::load_mesh(&shared_data().join("meshes/bunny_3674.obj")).unwrap();
    let reference = BruteForce::<Moller>::new(&mesh);
    let sets = standard_sets(&mesh, &reference, 64, 3);
    for kind in [GpuAccelKind::KdStack, GpuAccelKind::BvhThreaded] {
        for test in [TestKind::Plucker, TestKind::Moller] {
            let scene =
                GpuScene::build(&small, &mesh, kind, test, &BuildOptions::default()).unwrap();
            let whole =
                GpuScene::build(gpu(), &mesh, kind, test, &BuildOptions::default()).unwrap();
            let split = GpuTracer::new(&small, &scene).unwrap();
            let one = GpuTracer::new(gpu(), &whole).unwrap();
            for rays in [&sets[0], &sets[2]] {
                let a = split.intersect_batch(rays).unwrap();
                let b = one.intersect_batch(rays).unwrap();
                assert!(a.iter().any(|h| h.is_some()));
                assert_eq!(
                    a,
                    b,
                    "{} × {}: split records change the answers",
                    kind.name(),
                    test.name()
                );
            }
        }
    }
    // Beyond four bindings the error names the limit.
    small.limits.max_storage_buffer_binding_size = 64 * 1024;
    let err = GpuScene::build(
        &small,
        &mesh,
        GpuAccelKind::BvhThreaded,
        TestKind::Plucker,
        &BuildOptions::default(),
    )
    .err()
    .expect("does not fit four bindings");
    assert!(err.to_string().contains("in 4 bindings"), "{err}");
}

/// A soup of random triangles of mixed sizes and orientations (slivers
/// included), seeded, with overlaps and intersections everywhere.
fn triangle_soup(n: usize, seed: u64) -> TriangleMesh {
    let mut s = seed;
    let mut r = move || {
        // SplitMix64.
        s = s.wrapping_add(0x9e3779b97f4a7c15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut v = Vec::with_capacity(3 * n);
    for i in 0..n {
        let c = glam::Vec3::new(r(), r(), r()) * 20.0;
        let size = [2.0, 0.5, 0.05][i % 3];
        for _ in 0..3 {
            v.push(c + (glam::Vec3::new(r(), r(), r()) - 0.5) * size);
        }
    }
    let idx = (0..n as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    TriangleMesh::new(v, idx)
}

#[test]
fn random_triangle_soup_agrees_with_cpu() {
    let mesh = triangle_soup(30_000, 40);
    agree(
        "soup",
        &mesh,
        64,
        &[
            GpuAccelKind::Cwbvh,
            GpuAccelKind::BvhThreaded,
            GpuAccelKind::KdRopes,
        ],
    );
}

#[test]
fn timed_runs_give_the_same_answers_on_either_clock() {
    let mesh = raykit_io::load_mesh(&shared_data().join("meshes/bunny_3674.obj")).unwrap();
    let reference = BruteForce::<Moller>::new(&mesh);
    let rays = &standard_sets(&mesh, &reference, 32, 3)[0];
    let scene = GpuScene::build(
        gpu(),
        &mesh,
        GpuAccelKind::Cwbvh,
        TestKind::Moller,
        &BuildOptions::default(),
    )
    .unwrap();
    let tracer = GpuTracer::new(gpu(), &scene).unwrap();
    eprintln!("clock on this adapter: {}", tracer.clock().name());
    let up = tracer.upload(rays).unwrap();
    let mut answers = Vec::new();
    for clock in [tracer.clock(), raykit_gpu::Clock::WallClock] {
        let secs = tracer.run_clocked(&up, false, clock).unwrap();
        assert!(secs.is_finite() && secs >= 0.0, "{}: {secs}", clock.name());
        answers.push(tracer.hits(&up).unwrap());
    }
    let mut want = vec![None; rays.len()];
    reference.intersect_batch(rays, &mut want);
    assert!(answers[0].iter().any(|h| h.is_some()));
    assert_eq!(answers[0], answers[1]);
    let d = compare(&want, &answers[0]);
    assert!(d.hit_miss.is_empty() && d.distance.is_empty());
}

/// Segments that start behind their origin (negative `tnear`, down to the
/// whole line) find the hits there on the GPU too, in every structure;
/// the kd-stack kernel once clipped them to `t >= 0`.
#[test]
fn segments_reaching_behind_the_origin_agree_with_brute_force() {
    use raykit_core::rng::Pcg32;
    use raykit_core::Ray;
    let mesh = triangle_soup(5_000, 41);
    let b = mesh.bounds();
    let mut rng = Pcg32::new(42);
    let rays: Vec<Ray> = (0..4096)
        .map(|i| {
            let target = rng.in_box(b.min, b.max);
            let dir = rng.unit_vector();
            // The origin lies past the target, looking on.
            let origin = target + dir * (b.diagonal() * (0.5 + rng.next_f32()));
            let tnear = if i % 2 == 0 {
                f32::NEG_INFINITY
            } else {
                -b.diagonal() * 2.0
            };
            Ray::segment(origin, dir, tnear, f32::INFINITY)
        })
        .collect();
    let brute = BruteForce::<Moller>::new(&mesh);
    let mut want = vec![None; rays.len()];
    brute.intersect_batch(&rays, &mut want);
    assert!(want.iter().filter(|h| h.is_some()).count() > 1000);
    let ctx = gpu();
    for kind in GpuAccelKind::ALL {
        let scene =
            GpuScene::build(ctx, &mesh, kind, TestKind::Moller, &BuildOptions::default()).unwrap();
        let got = GpuTracer::new(ctx, &scene)
            .unwrap()
            .intersect_batch(&rays)
            .unwrap();
        let d = compare(&want, &got);
        assert!(
            d.hit_miss.is_empty() && d.distance.is_empty(),
            "{}: {} hit/miss and {} distance differences\n{}",
            kind.name(),
            d.hit_miss.len(),
            d.distance.len(),
            describe(&rays, &d.hit_miss, &want, &got)
        );
    }
}
