//! `SurfaceBvh::single_task`: a batch it names starts no parallel work, so
//! that it may run alone on a thread outside every pool (as the Python
//! binding runs calls on a few rays or points). Checked with rayon's global
//! pool held busy: parallel work started from outside it would wait for it,
//! and the batches must answer all the same, as they do with the pool free.

mod query_support;

use query_support::sphere;
use raykit_core::query::{QueryKind, SurfaceBvh};
use raykit_core::rng::Pcg32;
use raykit_core::{Hit, Ray, Vec3};
use std::sync::mpsc;
use std::sync::{Arc, Barrier};
use std::time::Duration;

/// Every answer of the batches asked, in one comparable value.
#[derive(Debug, PartialEq)]
struct Answers {
    counts: Vec<u32>,
    lists: Vec<Vec<Hit>>,
    distances: Vec<f32>,
    closest: Vec<Option<(u32, [f32; 3])>>,
    inside: Vec<bool>,
    signed: Vec<f32>,
}

fn answer(bvh: &SurfaceBvh, rays: &[Ray], points: &[Vec3]) -> Answers {
    let mut counts = vec![0; rays.len()];
    bvh.count_hits_batch(rays, &mut counts);
    let mut distances = vec![0.0; points.len()];
    bvh.distances(points, &mut distances);
    let mut closest = vec![None; points.len()];
    bvh.closest_points(points, f32::INFINITY, &mut closest);
    let mut inside = vec![false; points.len()];
    bvh.inside_batch(points, &mut inside);
    let mut signed = vec![0.0; points.len()];
    bvh.signed_distances(points, &mut signed);
    Answers {
        counts,
        lists: bvh.ray_hits_batch(rays, usize::MAX),
        distances,
        closest: closest
            .iter()
            .map(|c| c.map(|c| (c.prim, c.point.to_array())))
            .collect(),
        inside,
        signed,
    }
}

/// Runs `f` on a new thread outside every pool while each of the global
/// pool's threads waits; `None` when it has not returned after `wait`
/// (the thread is left to finish once the pool is free).
fn with_the_pool_busy<R: Send + 'static>(
    wait: Duration,
    f: impl FnOnce() -> R + Send + 'static,
) -> Option<R> {
    let threads = rayon::current_num_threads();
    let (started, all_started) = mpsc::channel();
    let release = Arc::new(Barrier::new(threads + 1));
    let hold = release.clone();
    rayon::spawn_broadcast(move |_| {
        started.send(()).unwrap();
        hold.wait();
    });
    for _ in 0..threads {
        all_started.recv().unwrap();
    }
    let (done, finished) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = done.send(f());
    });
    let got = finished.recv_timeout(wait).ok();
    release.wait();
    got
}

#[test]
fn batches_named_single_tasks_answer_without_the_pool() {
    let mesh = sphere(4);
    let bvh = Arc::new(SurfaceBvh::build(&mesh));
    let kinds = [
        QueryKind::Count,
        QueryKind::AllHits,
        QueryKind::Distance,
        QueryKind::Closest,
        QueryKind::Inside,
        QueryKind::SignedDistance,
    ];
    // Nothing made yet: no kind is a single task, however small.
    for kind in kinds {
        assert!(!bvh.single_task(kind, 1), "{kind:?} before its trees");
    }
    let mut rng = Pcg32::new(7);
    let points: Vec<Vec3> = (0..100)
        .map(|_| rng.in_box(Vec3::splat(-1.5), Vec3::splat(1.5)))
        .collect();
    // From a sphere around the mesh towards points of its box.
    let rays: Vec<Ray> = (0..100)
        .map(|_| {
            let o = rng.unit_vector() * 3.0;
            Ray::new(o, rng.in_box(Vec3::splat(-1.0), Vec3::splat(1.0)) - o)
        })
        .collect();
    for kind in kinds {
        bvh.prepare(kind);
    }
    // Occupancy and signed distance also need the winding-number moments.
    assert!(!bvh.single_task(QueryKind::Inside, 1));
    bvh.winding_numbers(&points[..1], &mut [0.0]);
    for kind in kinds {
        assert!(bvh.single_task(kind, 100), "{kind:?} on 100");
    }
    assert!(!bvh.single_task(QueryKind::Count, 257));
    assert!(!bvh.single_task(QueryKind::Distance, 1025));
    let want = answer(&bvh, &rays, &points);
    assert!(want.counts.iter().filter(|&&c| c == 2).count() > 50);
    assert!(want.inside.iter().any(|&i| i) && want.inside.iter().any(|&i| !i));

    // The check itself: parallel work from outside the busy pool waits.
    let control = with_the_pool_busy(Duration::from_millis(300), || rayon::join(|| 1, || 2));
    assert_eq!(control, None, "the busy pool ran a join");

    let shared = bvh.clone();
    let got = with_the_pool_busy(Duration::from_secs(30), move || {
        answer(&shared, &rays, &points)
    });
    let got = got.expect("a single-task batch waited for the busy pool");
    assert!(got == want, "answers differ with the pool busy");
}
