//! `raykit bench --compare embree`: our structure and Embree 3 built on the
//! same mesh, tracing the same rays in the same process; every cell is
//! printed as ours, Embree's and the ratio, and the answers are checked to
//! agree (hit/miss and distance; different triangles at the same distance,
//! and rays grazing a shared edge that one engine catches and the other
//! slips through, are ties).

use crate::embree::{EmbreeDevice, EmbreeScene, Quality};
use crate::measure::{median_min_max, pool, timed};
use crate::verify::{compare_hits, compare_occlusion, edge_margin, Verdict, T_TOLERANCE};
use anyhow::Result;
use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::raysets::{self, RayKind};
use raykit_core::tri::{TestKind, MAX_EDGE_TOLERANCE};
use raykit_core::{Accel, Hit, Ray, TriangleMesh};
use rayon::prelude::*;
use serde::Serialize;
use std::process::ExitCode;

/// Half-width of the band around a triangle's edges, in barycentric units,
/// within which the two engines may legitimately disagree: our triangle
/// tests widen their edges by a bound on their own rounding error, capped at
/// [`MAX_EDGE_TOLERANCE`] per test and staying within 2√3 times that of the
/// triangle (see `raykit_core::tri`), so that no ray slips between
/// triangles sharing an edge; Embree's test does not widen them.
const EDGE_BAND: f64 = 2.0 * 1.732_050_8 * MAX_EDGE_TOLERANCE as f64;

/// Rays per `rtcIntersect1M` call of the stream cell.
const STREAM_PACKET: usize = 256;

/// What to compare.
pub struct CompareSetup<'a> {
    /// The mesh.
    pub mesh: &'a TriangleMesh,
    /// Its name for the report.
    pub name: &'a str,
    /// Our structure and triangle test.
    pub ours: (AccelKind, TestKind),
    /// Our build options.
    pub options: BuildOptions,
    /// Image side of the ray sets.
    pub size: u32,
    /// Repetitions (medians are reported).
    pub reps: usize,
    /// Threads of the parallel cells (0 = one per core).
    pub threads: usize,
    /// Print JSON instead of tables.
    pub json: bool,
}

#[derive(Serialize)]
struct Cell {
    what: String,
    threads: usize,
    ours: f64,
    embree: f64,
    ratio: f64,
    spread: f64,
}

#[derive(Serialize)]
struct Agreement {
    set: &'static str,
    verdict: Verdict,
    /// Disagreements (hit/miss or distance) where the nearer answer's
    /// triangle is met within [`EDGE_BAND`] (barycentric, f64) of its edge:
    /// the ray grazes an edge, and one engine catches it where the other
    /// slips past. Counted as ties.
    edge_grazes: usize,
}

impl Agreement {
    /// True when every disagreement is a shared-edge graze.
    fn ok(&self) -> bool {
        self.verdict.hit_miss + self.verdict.distance == self.edge_grazes
    }
}

/// How many of the disagreements between `a` and `b` are edge grazes or
/// same-triangle distance differences.
fn edge_grazes(mesh: &TriangleMesh, rays: &[Ray], a: &[Option<Hit>], b: &[Option<Hit>]) -> usize {
    rays.iter()
        .zip(a.iter().zip(b))
        .filter(|(ray, (x, y))| {
            let near = match (x, y) {
                (Some(x), Some(y)) => {
                    // The same distance tolerance as `compare_hits`.
                    let tol = T_TOLERANCE * x.t.abs().max(y.t.abs()).max(f32::MIN_POSITIVE);
                    if (x.t - y.t).abs() <= tol {
                        return false;
                    }
                    if x.prim == y.prim {
                        // The same triangle at two distances: a ray nearly in
                        // the triangle's plane, where t is ill-conditioned.
                        return true;
                    }
                    if x.t < y.t {
                        x
                    } else {
                        y
                    }
                }
                (Some(x), None) | (None, Some(x)) => x,
                (None, None) => return false,
            };
            edge_margin(mesh, ray, near.prim).abs() < EDGE_BAND
        })
        .count()
}

#[derive(Serialize)]
struct Comparison {
    mesh: String,
    triangles: usize,
    ours: String,
    builds_ms: Vec<Cell>,
    mrays: Vec<Cell>,
    agreement: Vec<Agreement>,
}

/// Median seconds of `reps` runs of `f`, and the spread (max−min)/median.
fn time_median(reps: usize, mut f: impl FnMut()) -> (f64, f64) {
    let t: Vec<f64> = (0..reps.max(1)).map(|_| timed(&mut f).1).collect();
    let (m, lo, hi) = median_min_max(&t);
    (m, if m > 0.0 { (hi - lo) / m } else { 0.0 })
}

fn trace(accel: &dyn Accel, rays: &[Ray], shadow: bool) {
    if shadow {
        let mut o = vec![false; rays.len()];
        accel.occluded_batch(rays, &mut o);
    } else {
        let mut h = vec![None; rays.len()];
        accel.intersect_batch(rays, &mut h);
    }
}

/// Run the comparison and print it.
pub fn run(s: CompareSetup) -> Result<ExitCode> {
    let one = pool(1)?;
    let all = pool(s.threads)?;
    let n = all.current_num_threads();
    let (kind, test) = s.ours;
    let mesh = s.mesh;
    eprintln!(
        "{}: {} triangles; ray sets {}²…",
        s.name,
        mesh.num_triangles(),
        s.size
    );
    let sets = all.install(|| {
        let helper = build_accel(AccelKind::Bvh2, TestKind::Moller, mesh, &s.options);
        raysets::standard_sets(mesh, helper.as_ref(), s.size, 1)
    });
    let mut builds = Vec::new();
    let mut ours = None;
    for (threads, p) in [(1, &one), (n, &all)] {
        let (t_ours, sp) = time_median(s.reps, || {
            ours = Some(p.install(|| build_accel(kind, test, mesh, &s.options)));
        });
        // The device (Embree's thread pool) is made outside the timing.
        let device = EmbreeDevice::new(threads)?;
        for quality in [Quality::High, Quality::Medium] {
            let mut err = None;
            let (t_em, sp2) = time_median(s.reps, || {
                if let Err(e) = EmbreeScene::build(&device, mesh, quality) {
                    err = Some(e);
                }
            });
            if let Some(e) = err {
                return Err(e);
            }
            builds.push(Cell {
                what: format!("build vs Embree {quality:?}"),
                threads,
                ours: t_ours * 1e3,
                embree: t_em * 1e3,
                // Build: a ratio above 1 means ours is faster.
                ratio: t_em / t_ours.max(1e-12),
                spread: sp.max(sp2),
            });
        }
    }
    let ours = ours.expect("built");
    let embree = EmbreeScene::build(&EmbreeDevice::new(0)?, mesh, Quality::High)?;
    let mut cells = Vec::new();
    for (si, set) in RayKind::ALL.into_iter().enumerate() {
        let rays = &sets[si];
        let shadow = set == RayKind::Shadow;
        for (threads, p) in [(1, &one), (n, &all)] {
            let (a, sa) = time_median(s.reps, || p.install(|| trace(ours.as_ref(), rays, shadow)));
            let (b, sb) = time_median(s.reps, || p.install(|| trace(&embree, rays, shadow)));
            let m = rays.len() as f64 / 1e6;
            cells.push(Cell {
                what: set.name().to_string(),
                threads,
                ours: m / a,
                embree: m / b,
                ratio: b / a.max(1e-12),
                spread: sa.max(sb),
            });
        }
    }
    // Coherent primaries: Embree's stream API against our batch path.
    let primary = &sets[0];
    for (threads, p) in [(1, &one), (n, &all)] {
        let (a, sa) = time_median(s.reps, || {
            p.install(|| trace(ours.as_ref(), primary, false))
        });
        let (b, sb) = time_median(s.reps, || {
            p.install(|| {
                let mut hits: Vec<Option<Hit>> = vec![None; primary.len()];
                primary
                    .par_chunks(STREAM_PACKET * 16)
                    .zip(hits.par_chunks_mut(STREAM_PACKET * 16))
                    .for_each(|(r, h)| embree.intersect_stream(r, h, STREAM_PACKET));
            })
        });
        let m = primary.len() as f64 / 1e6;
        cells.push(Cell {
            what: "primary, Embree stream (rtcIntersect1M)".into(),
            threads,
            ours: m / a,
            embree: m / b,
            ratio: b / a.max(1e-12),
            spread: sa.max(sb),
        });
    }
    // Agreement on every ray of every set.
    let mut agreement = Vec::new();
    for (si, set) in RayKind::ALL.into_iter().enumerate() {
        let rays = &sets[si];
        let (verdict, edge_grazes) = all.install(|| {
            // Shadow rays: occlusion answers, and the nearest hits along the
            // same segments to tell edge grazes apart.
            let (mut a, mut b) = (vec![None; rays.len()], vec![None; rays.len()]);
            embree.intersect_batch(rays, &mut a);
            ours.intersect_batch(rays, &mut b);
            if set == RayKind::Shadow {
                let (mut x, mut y) = (vec![false; rays.len()], vec![false; rays.len()]);
                embree.occluded_batch(rays, &mut x);
                ours.occluded_batch(rays, &mut y);
                // Only the rays whose occlusion differs: is the blocker the
                // one engine found met at an edge?
                let differ: Vec<usize> = (0..rays.len()).filter(|&i| x[i] != y[i]).collect();
                let pick = |h: &[Option<Hit>], occ: &[bool]| -> Vec<Option<Hit>> {
                    differ.iter().map(|&i| h[i].filter(|_| occ[i])).collect()
                };
                let r: Vec<Ray> = differ.iter().map(|&i| rays[i]).collect();
                let grazes = edge_grazes(mesh, &r, &pick(&a, &x), &pick(&b, &y));
                (compare_occlusion(&x, &y), grazes)
            } else {
                (compare_hits(&a, &b), edge_grazes(mesh, rays, &a, &b))
            }
        });
        agreement.push(Agreement {
            set: set.name(),
            verdict,
            edge_grazes,
        });
    }
    let (mut a, mut b) = (vec![None; primary.len()], vec![None; primary.len()]);
    embree.intersect_stream(primary, &mut a, STREAM_PACKET);
    all.install(|| ours.intersect_batch(primary, &mut b));
    agreement.push(Agreement {
        set: "primary (stream)",
        verdict: compare_hits(&a, &b),
        edge_grazes: edge_grazes(mesh, primary, &a, &b),
    });
    let report = Comparison {
        mesh: s.name.to_string(),
        triangles: mesh.num_triangles(),
        ours: format!("{} × {}", kind.name(), test.name()),
        builds_ms: builds,
        mrays: cells,
        agreement,
    };
    if s.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_report(&report, s.reps);
    }
    let failed = report.agreement.iter().any(|a| !a.ok());
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

fn print_report(r: &Comparison, reps: usize) {
    println!(
        "{}: {} triangles; ours = {}, Embree 3 single-ray API (HIGH build) unless noted; median of {reps} runs",
        r.mesh, r.triangles, r.ours
    );
    print_cells("build (ms)", "Embree÷ours", 1, &r.builds_ms);
    print_cells("Mrays/s", "ours÷Embree", 2, &r.mrays);
    println!("\nanswers against Embree (every ray):");
    for a in &r.agreement {
        let v = &a.verdict;
        println!(
            "  {:<18} {} rays: {} hit/miss and {} distance differences, of which {} graze an edge (f64) or hit the same triangle; {} same-distance ties{}",
            a.set,
            v.checked,
            v.hit_miss,
            v.distance,
            a.edge_grazes,
            v.ties,
            if a.ok() { "" } else { "  <-- DISAGREE" }
        );
    }
}

/// One table of cells, values with `digits` decimals.
fn print_cells(title: &str, ratio: &str, digits: usize, cells: &[Cell]) {
    println!(
        "\n{title:<42} {:>7} {:>10} {:>10} {ratio:>8} {:>7}",
        "threads", "ours", "Embree", "spread"
    );
    for c in cells {
        println!(
            "{:<42} {:>7} {:>10.digits$} {:>10.digits$} {:>10.2}× {:>6.0}%",
            c.what,
            c.threads,
            c.ours,
            c.embree,
            c.ratio,
            100.0 * c.spread
        );
    }
}
