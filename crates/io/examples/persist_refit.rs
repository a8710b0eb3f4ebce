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

/// Seconds of CPU time of the whole process (every thread).
fn cpu_seconds() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: a valid clock id and a timespec to write.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

/// Timings of `rounds` runs: wall-clock median and minimum, and the
/// median CPU time of the process (every thread; on a loaded machine the
/// fairer figure for one thread), in seconds.
struct Timing {
    median: f64,
    min: f64,
    cpu: f64,
}

impl std::fmt::Display for Timing {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:7.2} ms (min {:.2}, cpu {:.2})",
            self.median * 1e3,
            self.min * 1e3,
            self.cpu * 1e3
        )
    }
}

/// Run `f` `rounds` times; its timing and last result.
fn time<R>(rounds: usize, mut f: impl FnMut() -> R) -> (Timing, R) {
    let (mut wall, mut cpu) = (Vec::new(), Vec::new());
    let mut last = None;
    for _ in 0..rounds {
        let (t0, c0) = (Instant::now(), cpu_seconds());
        let r = f();
        wall.push(t0.elapsed().as_secs_f64());
        cpu.push(cpu_seconds() - c0);
        last = Some(r);
    }
    wall.sort_by(f64::total_cmp);
    cpu.sort_by(f64::total_cmp);
    let t = Timing {
        median: wall[wall.len() / 2],
        min: wall[0],
        cpu: cpu[cpu.len() / 2],
    };
    (t, last.unwrap())
}

/// `a / b` by wall-clock median, minimum and CPU time.
fn ratios(what: &str, a: &Timing, b: &Timing) -> String {
    format!(
        "{what} {:.1}x (min {:.1}x, cpu {:.1}x)",
        a.median / b.median,
        a.min / b.min,
        a.cpu / b.cpu
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
    let (t, _) = time(3, || tree.intersect_batch(rays, &mut hits));
    rays.len() as f64 / t.median
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = std::path::Path::new(args.first().expect("usage: persist_refit MESH [rounds]"));
    let rounds: usize = args.get(1).map_or(5, |r| r.parse().expect("rounds"));
    let mesh = raykit_io::load(path).expect("mesh").mesh;
    let threads = std::env::var("RAYON_NUM_THREADS").unwrap_or_else(|_| "all".into());
    println!(
        "{}: {} triangles, {threads} threads, {rounds} rounds: wall median (min, cpu time median)",
        path.display(),
        mesh.num_triangles()
    );
    let opts = BuildOptions::default();
    let (build, tree) = time(rounds, || Bvh8::<Moller>::build(&mesh, &opts));
    println!("build   {build}, {} nodes", tree.stats().nodes);
    let file = std::env::temp_dir().join(format!("persist_refit_{}.bvh8", std::process::id()));
    let (save, _) = time(rounds, || tree.save(&file, &mesh).expect("save"));
    let bytes = std::fs::metadata(&file).map(|m| m.len()).unwrap_or(0);
    println!("save    {save}, {:.1} MB", bytes as f64 / 1e6);
    let (load, loaded) = time(rounds, || Bvh8::<Moller>::load(&file, &mesh).expect("load"));
    println!("load    {load}: {}", ratios("build/load", &build, &load));
    // SAFETY: the file is left alone until the mapped tree is dropped.
    let (mload, mapped) = time(rounds, || unsafe {
        Bvh8::<Moller>::load_mapped(&file, &mesh).expect("load")
    });
    println!("mapped  {mload}: {}", ratios("build/load", &build, &mload));
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
        let (refit, report) = time(rounds, || refit_tree.refit(&moved).expect("refit"));
        let (rebuild, rebuilt) = time(rounds, || Bvh8::<Moller>::build(&moved, &opts));
        let rays = rays(&moved, 500_000);
        let (rate_refit, rate_rebuilt) =
            (trace_rate(&refit_tree, &rays), trace_rate(&rebuilt, &rays));
        println!(
            "frame {frame}: refit {refit}, rebuild {rebuild}: {}; SAH degradation {:.3}; \
             trace refit/rebuilt tree {:.3}x",
            ratios("rebuild/refit", &rebuild, &refit),
            report.degradation(),
            rate_refit / rate_rebuilt
        );
    }
}
