//! Time the saved and refit 8-wide BVH on a mesh file against building it:
//! build, save, load (the file in the page cache), and, over a smoothly
//! deforming copy of the mesh, refit against rebuild, with the refit
//! tree's SAH degradation and its trace rate against the rebuilt tree's.
//! Set `RAYON_NUM_THREADS` for the thread count.
//!
//! `cargo run --release -p raykit-io --example persist_refit -- dragon_vrip.ply [rounds]`

use raykit_core::accel::{Accel, BuildOptions, Bvh8};
use raykit_core::rng::Pcg32;
use raykit_core::tri::Moller;
use raykit_core::{Ray, TriangleMesh, Vec3};
use std::time::Instant;

/// Seconds of `f`, the median of `rounds` runs, and the spread (min, max).
fn time<R>(rounds: usize, mut f: impl FnMut() -> R) -> (f64, f64, f64, R) {
    let mut secs = Vec::new();
    let mut last = None;
    for _ in 0..rounds {
        let t0 = Instant::now();
        let r = f();
        secs.push(t0.elapsed().as_secs_f64());
        last = Some(r);
    }
    secs.sort_by(f64::total_cmp);
    (
        secs[secs.len() / 2],
        secs[0],
        secs[secs.len() - 1],
        last.unwrap(),
    )
}

/// `mesh` under a smooth displacement (a travelling wave and a twist) of
/// phase `phase` and amplitude `amp` of its size.
fn deformed(mesh: &TriangleMesh, phase: f32, amp: f32) -> TriangleMesh {
    let b = mesh.bounds();
    let (c, size) = (b.center(), b.extent().max_element());
    let mut out = mesh.clone();
    for p in &mut out.positions {
        let q = (*p - c) / size;
        let wave = amp * (6.0 * q.y + phase).sin() * (5.0 * q.x - phase).cos();
        let twist = amp * 2.0 * q.y * phase.sin();
        let (s, co) = twist.sin_cos();
        let r = Vec3::new(co * q.x + s * q.z, q.y, -s * q.x + co * q.z);
        *p = c + (r + q.normalize_or_zero() * wave) * size;
    }
    out
}

/// Rays from a sphere around the mesh through points of its box.
fn rays(mesh: &TriangleMesh, n: usize) -> Vec<Ray> {
    let b = mesh.bounds();
    let (c, r) = (b.center(), b.extent().length());
    let mut rng = Pcg32::new(1);
    (0..n)
        .map(|_| {
            let o = c + rng.unit_vector() * r;
            Ray::new(o, rng.in_box(b.min, b.max) - o)
        })
        .collect()
}

fn trace_rate(tree: &dyn Accel, rays: &[Ray]) -> f64 {
    let mut hits = vec![None; rays.len()];
    let (s, _, _, _) = time(3, || tree.intersect_batch(rays, &mut hits));
    rays.len() as f64 / s
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = std::path::Path::new(args.first().expect("usage: persist_refit MESH [rounds]"));
    let rounds: usize = args.get(1).map_or(5, |r| r.parse().expect("rounds"));
    let mesh = raykit_io::load(path).expect("mesh").mesh;
    let threads = std::env::var("RAYON_NUM_THREADS").unwrap_or_else(|_| "all".into());
    println!(
        "{}: {} triangles, {threads} threads, median of {rounds} (min-max)",
        path.display(),
        mesh.num_triangles()
    );
    let opts = BuildOptions::default();
    let (build, b0, b1, tree) = time(rounds, || Bvh8::<Moller>::build(&mesh, &opts));
    println!(
        "build   {:8.2} ms ({:.2}-{:.2})",
        build * 1e3,
        b0 * 1e3,
        b1 * 1e3
    );
    let file = std::env::temp_dir().join(format!("persist_refit_{}.bvh8", std::process::id()));
    let (save, s0, s1, _) = time(rounds, || tree.save(&file, &mesh).expect("save"));
    let bytes = std::fs::metadata(&file).map(|m| m.len()).unwrap_or(0);
    println!(
        "save    {:8.2} ms ({:.2}-{:.2}), {:.1} MB",
        save * 1e3,
        s0 * 1e3,
        s1 * 1e3,
        bytes as f64 / 1e6
    );
    let (load, l0, l1, loaded) = time(rounds, || Bvh8::<Moller>::load(&file, &mesh).expect("load"));
    println!(
        "load    {:8.2} ms ({:.2}-{:.2}): build/load {:.1}x",
        load * 1e3,
        l0 * 1e3,
        l1 * 1e3,
        build / load
    );
    // SAFETY: the file is left alone until the mapped tree is dropped.
    let (mload, m0, m1, mapped) = time(rounds, || unsafe {
        Bvh8::<Moller>::load_mapped(&file, &mesh).expect("load")
    });
    println!(
        "mapped  {:8.2} ms ({:.2}-{:.2}): build/load {:.1}x",
        mload * 1e3,
        m0 * 1e3,
        m1 * 1e3,
        build / mload
    );
    let check = rays(&mesh, 500_000);
    let (mut a, mut b, mut c) = (
        vec![None; check.len()],
        vec![None; check.len()],
        vec![None; check.len()],
    );
    tree.intersect_batch(&check, &mut a);
    loaded.intersect_batch(&check, &mut b);
    mapped.intersect_batch(&check, &mut c);
    assert!(a == b && a == c, "the loaded trees answer as the built one");
    let built_rate = trace_rate(&tree, &check);
    println!(
        "trace (500k incoherent rays): built {:.2} Mrays/s, loaded/built {:.3}x, mapped/built {:.3}x",
        built_rate / 1e6,
        trace_rate(&loaded, &check) / built_rate,
        trace_rate(&mapped, &check) / built_rate
    );
    drop(mapped);
    let _ = std::fs::remove_file(&file);

    let mut refit_tree = Bvh8::<Moller>::build(&mesh, &opts);
    for (frame, phase) in [0.5f32, 1.5, 3.0].into_iter().enumerate() {
        let moved = deformed(&mesh, phase, 0.04);
        let (refit, r0, r1, report) = time(rounds, || refit_tree.refit(&moved).expect("refit"));
        let (rebuild, q0, q1, rebuilt) = time(rounds, || Bvh8::<Moller>::build(&moved, &opts));
        let rays = rays(&moved, 500_000);
        let (rate_refit, rate_rebuilt) =
            (trace_rate(&refit_tree, &rays), trace_rate(&rebuilt, &rays));
        println!(
            "frame {frame}: refit {:.2} ms ({:.2}-{:.2}), rebuild {:.2} ms ({:.2}-{:.2}): \
             rebuild/refit {:.1}x; SAH degradation {:.3}; trace refit/rebuilt tree {:.3}x",
            refit * 1e3,
            r0 * 1e3,
            r1 * 1e3,
            rebuild * 1e3,
            q0 * 1e3,
            q1 * 1e3,
            rebuild / refit,
            report.degradation(),
            rate_refit / rate_rebuilt
        );
    }
}
