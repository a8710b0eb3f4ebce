//! Measuring a GPU structure × triangle test on ray sets, with every
//! answer checked against the CPU structure it mirrors: shared by `raykit
//! bench --backend gpu` and `raykit experiment gpu`.

use crate::args::backend::cpu_twin;
use crate::measure::median_min_max;
use anyhow::{anyhow, Result};
use raykit_core::accel::{build_accel, BuildOptions};
use raykit_core::tri::TestKind;
use raykit_core::verify::{self, Verdict};
use raykit_core::{Ray, TriangleMesh};
use raykit_gpu::{count_traversal, cwbvh, GpuAccelKind, GpuContext, GpuScene, GpuTracer, CHUNK};
use serde::Serialize;

/// Speed on one ray set.
#[derive(Serialize, Clone, Debug)]
pub struct GpuCell {
    /// `primary`, `shadow` or `incoherent`.
    pub set: &'static str,
    /// Rays traced.
    pub rays: usize,
    /// Mrays/s of the kernel (median run), timed with [`GpuRow::clock`].
    pub mrays: f64,
    /// Mrays/s of the slowest run.
    pub mrays_lo: f64,
    /// Mrays/s of the fastest run.
    pub mrays_hi: f64,
    /// (max − min) / median of the kernel times.
    pub spread: f64,
    /// A one-ray dispatch's time (median) as a share of a full dispatch's:
    /// the fixed cost of a launch that the batch carries.
    pub launch_share: f64,
    /// Nodes visited per ray (the counting kernel).
    pub nodes_per_ray: f64,
    /// Triangle records tested per ray.
    pub tris_per_ray: f64,
    /// Bytes of nodes, index entries and triangle records fetched per ray.
    pub bytes_per_ray: f64,
    /// GPU answers against the CPU twin's, every ray.
    pub verify: Verdict,
}

/// One structure × test on one mesh.
#[derive(Serialize, Clone, Debug)]
pub struct GpuRow {
    /// Structure name.
    pub accel: &'static str,
    /// Triangle test name.
    pub test: &'static str,
    /// CPU build of the structure (ms).
    pub build_ms: f64,
    /// Flattening and upload (ms).
    pub upload_ms: f64,
    /// Bytes on the device.
    pub bytes: usize,
    /// Bytes of the nodes alone.
    pub node_bytes: usize,
    /// Nodes.
    pub nodes: usize,
    /// How the kernels were timed ([`raykit_gpu::Clock::name`]).
    pub clock: &'static str,
    /// Per ray set.
    pub cells: Vec<GpuCell>,
}

/// The ray sets measured, in the order of [`raykit_core::raysets::standard_sets`]:
/// nearest hits for primary and incoherent rays, occlusion for shadow rays.
pub const SETS: [&str; 3] = ["primary", "shadow", "incoherent"];

/// What every structure × test is measured on.
pub struct Workload<'a> {
    /// The mesh.
    pub mesh: &'a TriangleMesh,
    /// Build options of the structures.
    pub opts: &'a BuildOptions,
    /// Primary, shadow and incoherent rays.
    pub sets: &'a [Vec<Ray>; 3],
    /// Timed runs per set (the median is reported).
    pub reps: usize,
}

/// Build `kind` × `test` on the GPU and its CPU twin, trace every set
/// `reps` times on the GPU after two warm-up runs (the first one's answers
/// checked against the CPU twin's on every ray), each run timed with the
/// GPU's timestamps where the device has them, else the wall clock; time a
/// one-ray dispatch the same way for the launch cost, and count the
/// traversal's nodes and bytes per ray with the counting kernel.
pub fn measure(
    ctx: &GpuContext,
    work: &Workload,
    kind: GpuAccelKind,
    test: TestKind,
    mut progress: impl FnMut(&str),
) -> Result<GpuRow> {
    let Workload {
        mesh,
        opts,
        sets,
        reps,
    } = *work;
    progress(&format!(
        "{} × {}: build and upload",
        kind.name(),
        test.name()
    ));
    let scene = GpuScene::build(ctx, mesh, kind, test, opts).map_err(|e| anyhow!("{e}"))?;
    let tracer = GpuTracer::new(ctx, &scene).map_err(|e| anyhow!("{e}"))?;
    let clock = tracer.clock();
    // The compressed wide BVH is made from the 8-wide BVH with leaves of
    // at most three triangles: its twin is that tree.
    let twin_opts = match kind {
        GpuAccelKind::Cwbvh => cwbvh::cwbvh_build_options(opts),
        _ => opts.clone(),
    };
    let twin = build_accel(cpu_twin(kind), test, mesh, &twin_opts);
    let mut cells = Vec::new();
    for (si, set) in SETS.iter().enumerate() {
        progress(&format!("{} × {}: {set} rays", kind.name(), test.name()));
        let any = *set == "shadow";
        let mut times = Vec::new();
        let mut verdict = Verdict::default();
        for chunk in sets[si].chunks(CHUNK) {
            let up = tracer.upload(chunk).map_err(|e| anyhow!("{e}"))?;
            tracer.run(&up, any).map_err(|e| anyhow!("{e}"))?;
            let v = if any {
                let got = tracer.occlusion(&up).map_err(|e| anyhow!("{e}"))?;
                let mut want = vec![false; chunk.len()];
                twin.occluded_batch(chunk, &mut want);
                let mut v = verify::compare_occlusion(&want, &got);
                // The nearest hits along the differing rays tell edge
                // grazes apart (a GPU may round division and fused
                // multiply-adds differently from the CPU).
                let mut gpu_err = None;
                let (grazes, differ) = verify::occlusion_grazes(mesh, chunk, &want, &got, |r| {
                    let mut cpu = vec![None; r.len()];
                    twin.intersect_batch(r, &mut cpu);
                    let gpu = tracer
                        .upload(r)
                        .and_then(|u| tracer.run(&u, false).and_then(|_| tracer.hits(&u)));
                    let gpu = gpu.unwrap_or_else(|e| {
                        gpu_err = Some(e);
                        vec![None; r.len()]
                    });
                    (cpu, gpu)
                });
                if let Some(e) = gpu_err {
                    return Err(anyhow!("{e}"));
                }
                v.edge_grazes = grazes;
                report_unexplained(&v, &differ, chunk, |i| {
                    format!("CPU occluded {} GPU occluded {}", want[i], got[i])
                });
                v
            } else {
                let got = tracer.hits(&up).map_err(|e| anyhow!("{e}"))?;
                let mut want = vec![None; chunk.len()];
                twin.intersect_batch(chunk, &mut want);
                let mut v = verify::compare_hits(&want, &got);
                v.edge_grazes = verify::edge_grazes(mesh, chunk, &want, &got);
                let differ: Vec<usize> = (0..chunk.len())
                    .filter(|&i| {
                        verify::compare_hits(&want[i..=i], &got[i..=i]).disagreements() > 0
                    })
                    .collect();
                report_unexplained(&v, &differ, chunk, |i| {
                    format!("CPU {:?} GPU {:?}", want[i], got[i])
                });
                v
            };
            verdict.checked += v.checked;
            verdict.hit_miss += v.hit_miss;
            verdict.distance += v.distance;
            verdict.ties += v.ties;
            verdict.edge_grazes += v.edge_grazes;
            tracer
                .run_clocked(&up, any, clock)
                .map_err(|e| anyhow!("{e}"))?;
            for r in 0..reps.max(1) {
                let secs = tracer
                    .run_clocked(&up, any, clock)
                    .map_err(|e| anyhow!("{e}"))?;
                if times.len() <= r {
                    times.push(0.0);
                }
                times[r] += secs;
            }
        }
        let (med, lo, hi) = median_min_max(&times);
        let one = tracer
            .upload(&sets[si][..sets[si].len().min(1)])
            .map_err(|e| anyhow!("{e}"))?;
        let launch: Vec<f64> = (0..reps.max(1) + 1)
            .map(|_| tracer.run_clocked(&one, any, clock))
            .collect::<Result<_, _>>()
            .map_err(|e| anyhow!("{e}"))?;
        let dispatches = sets[si].len().div_ceil(CHUNK).max(1) as f64;
        let counts = count_traversal(ctx, &scene, &sets[si], any).map_err(|e| anyhow!("{e}"))?;
        let n = sets[si].len() as f64;
        cells.push(GpuCell {
            set,
            rays: sets[si].len(),
            mrays: n / med / 1e6,
            mrays_lo: n / hi / 1e6,
            mrays_hi: n / lo / 1e6,
            spread: (hi - lo) / med,
            launch_share: median_min_max(&launch[1..]).0 * dispatches / med,
            nodes_per_ray: counts.nodes_per_ray(),
            tris_per_ray: counts.tris_per_ray(),
            bytes_per_ray: counts.bytes_per_ray(),
            verify: verdict,
        });
    }
    Ok(GpuRow {
        accel: kind.name(),
        test: test.name(),
        build_ms: scene.build_seconds * 1e3,
        upload_ms: scene.upload_seconds * 1e3,
        bytes: scene.bytes,
        node_bytes: scene.node_bytes,
        nodes: scene.num_nodes,
        clock: clock.name(),
        cells,
    })
}

/// Print the disagreeing rays of a chunk (at most a few) when some of the
/// disagreements are not edge grazes, so that a real kernel bug shows its
/// rays.
fn report_unexplained(
    v: &Verdict,
    differ: &[usize],
    rays: &[Ray],
    answers: impl Fn(usize) -> String,
) {
    if v.unexplained() == 0 {
        return;
    }
    for &i in differ.iter().take(8) {
        eprintln!(
            "disagreement (not all edge grazes): {:?}: {}",
            rays[i],
            answers(i)
        );
    }
}
