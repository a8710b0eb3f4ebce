//! `raykit bench --compare embree`: our structures and Embree 3 built on
//! the same meshes, tracing the same rays in the same process; every cell is
//! printed as ours, Embree's and the ratio, and the answers are checked to
//! agree (hit/miss and distance; different triangles at the same distance,
//! and rays grazing a shared edge that one engine catches and the other
//! slips through, are ties). With several meshes or structures a summary
//! gives, per cell and mesh, our best ratio.

use crate::embree::{EmbreeDevice, EmbreeScene, Quality};
use crate::measure::{median_min_max, pool, timed};
use crate::verify::{compare_hits, compare_occlusion, edge_grazes, occlusion_grazes, Verdict};
use anyhow::Result;
use raykit_core::accel::{build_accel, AccelKind, BuildOptions, BuildQuality};
use raykit_core::raysets::{self, RayKind};
use raykit_core::tri::TestKind;
use raykit_core::{Accel, Hit, Ray, TriangleMesh};
use rayon::prelude::*;
use rayon::ThreadPool;
use serde::Serialize;
use std::process::ExitCode;

/// Rays per `rtcIntersect1M` call of the stream cell.
const STREAM_PACKET: usize = 256;

/// What to compare.
pub struct CompareSetup<'a> {
    /// The meshes, each with its name for the report.
    pub meshes: &'a [(String, TriangleMesh)],
    /// Our structures × triangle tests, each measured against the same
    /// Embree figures.
    pub ours: Vec<(AccelKind, TestKind)>,
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
    /// Our structure × test of this cell.
    structure: String,
    threads: usize,
    ours: f64,
    embree: f64,
    ratio: f64,
    spread: f64,
}

#[derive(Serialize)]
struct Agreement {
    set: &'static str,
    /// Our structure × test compared.
    structure: String,
    /// Every ray of the set; `edge_grazes` counts the disagreements where
    /// the nearer answer's triangle is met within the edge band (f64): the
    /// ray grazes an edge, one engine catches it where the other slips past.
    verdict: Verdict,
}

/// The build Embree traces: HIGH (with spatial splits), or MEDIUM where
/// RAYKIT_EMBREE_TRACE_MEDIUM is set (an experiment: on the scatter both
/// trace at the same speed, so the splits are not what Embree's lead on
/// shadow and incoherent rays comes from).
fn trace_quality() -> Quality {
    match std::env::var_os("RAYKIT_EMBREE_TRACE_MEDIUM") {
        Some(_) => Quality::Medium,
        None => Quality::High,
    }
}

/// The options of the structures we trace: the given ones, with the
/// default binned SAH raised to [`BuildQuality::High`], since Embree traces
/// its HIGH build (the build cells time each of ours against the Embree
/// build of the same rung: these against HIGH, the given ones against
/// MEDIUM).
fn traced_options(options: &BuildOptions) -> BuildOptions {
    let quality = match options.quality {
        BuildQuality::Sah => BuildQuality::High,
        q => q,
    };
    BuildOptions {
        quality,
        ..options.clone()
    }
}

/// Our build's size and quality, shown beside its build time.
#[derive(Serialize)]
struct BuiltFigures {
    structure: String,
    sah_cost: f64,
    bytes: usize,
    nodes: usize,
}

#[derive(Serialize)]
struct Comparison {
    mesh: String,
    triangles: usize,
    /// The builder of the structures traced (`--bvh-build`).
    traced_build: String,
    ours: Vec<BuiltFigures>,
    builds_ms: Vec<Cell>,
    mrays: Vec<Cell>,
    agreement: Vec<Agreement>,
}

/// Our best ratio for one cell on one mesh.
#[derive(Serialize)]
struct Best {
    mesh: String,
    ratio: f64,
    structure: String,
}

/// One row of the summary: a cell across the meshes.
#[derive(Serialize)]
struct SummaryRow {
    what: String,
    threads: usize,
    best: Vec<Best>,
}

/// One timed thing of a cell: an engine's build or trace.
type Run<'a> = Box<dyn FnMut() + 'a>;

/// Median seconds and spread (max−min)/median of each of `runs`, timed in
/// turn: each of `reps` rounds times every run once, in order, after one
/// untimed round where `warm_up` is set. Host noise comes in bursts of a
/// second or more; timed one engine after the other, a burst could fall on
/// all of one engine's samples and move its median alone (one 2-thread cell
/// read 0.93× where five other runs read 1.20–1.30×, BENCHMARKS.md, step
/// 4b). In turn, a burst falls on both engines' samples alike. The warm-up
/// round is for the trace cells: without it the first cells after the
/// builds showed spreads of 75–90% in some runs where every later cell
/// showed under 10%; the medians are then the steady state, as a
/// renderer tracing frame after frame sees it.
fn time_in_turn(reps: usize, warm_up: bool, runs: &mut [Run]) -> Vec<(f64, f64)> {
    if warm_up {
        runs.iter_mut().for_each(|f| f());
    }
    let mut samples = vec![Vec::new(); runs.len()];
    for _ in 0..reps.max(1) {
        for (f, t) in runs.iter_mut().zip(&mut samples) {
            t.push(timed(&mut *f).1);
        }
    }
    samples
        .iter()
        .map(|t| {
            let (m, lo, hi) = median_min_max(t);
            (m, if m > 0.0 { (hi - lo) / m } else { 0.0 })
        })
        .collect()
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

/// Run the comparison on every mesh and print it.
pub fn run(s: CompareSetup) -> Result<ExitCode> {
    let one = pool(1)?;
    let all = pool(s.threads)?;
    let mut reports = Vec::new();
    for (name, mesh) in s.meshes {
        let r = compare_mesh(&s, name, mesh, &one, &all)?;
        if !s.json {
            print_report(&r, s.reps);
        }
        reports.push(r);
    }
    let summary = summarise(&reports);
    if s.json {
        let doc = serde_json::json!({ "comparisons": reports, "summary": summary });
        println!("{}", serde_json::to_string_pretty(&doc)?);
    } else if reports.len() > 1 || s.ours.len() > 1 {
        print_summary(&summary);
    }
    let failed = reports
        .iter()
        .any(|r| r.agreement.iter().any(|a| !a.verdict.ok()));
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

fn label(kind: AccelKind, test: TestKind) -> String {
    format!("{} × {}", kind.name(), test.name())
}

/// Every cell of one mesh: builds, Mrays/s and agreement.
fn compare_mesh(
    s: &CompareSetup,
    name: &str,
    mesh: &TriangleMesh,
    one: &ThreadPool,
    all: &ThreadPool,
) -> Result<Comparison> {
    let n = all.current_num_threads();
    eprintln!(
        "{name}: {} triangles; ray sets {}²…",
        mesh.num_triangles(),
        s.size
    );
    let sets = all.install(|| {
        let helper = build_accel(AccelKind::Bvh2, TestKind::Moller, mesh, &s.options);
        raysets::standard_sets(mesh, helper.as_ref(), s.size, 1)
    });
    let mut builds = Vec::new();
    let mut ours: Vec<Box<dyn Accel>> = Vec::new();
    let high = traced_options(&s.options);
    for (threads, p) in [(1, one), (n, all)] {
        // The device (Embree's thread pool) is made outside the timing.
        let device = EmbreeDevice::new(threads)?;
        for quality in [Quality::High, Quality::Medium] {
            // Our build at the same rung of the ladder: the traced (high)
            // options against Embree HIGH, the given ones against MEDIUM.
            let opts = match quality {
                Quality::High => &high,
                Quality::Medium => &s.options,
            };
            // Ours and Embree's in turn (`time_in_turn`); each rep's tree
            // replaces (frees) the previous one inside the timing, as
            // Embree's scene is released inside its own.
            let mut built: Vec<Option<Box<dyn Accel>>> = s.ours.iter().map(|_| None).collect();
            let mut err = None;
            let mut timings = {
                let mut runs: Vec<Run> = built
                    .iter_mut()
                    .zip(&s.ours)
                    .map(|(slot, &(kind, test))| -> Run {
                        Box::new(move || {
                            *slot = Some(p.install(|| build_accel(kind, test, mesh, opts)))
                        })
                    })
                    .collect();
                runs.push(Box::new(|| {
                    if let Err(e) = EmbreeScene::build(&device, mesh, quality) {
                        err = Some(e);
                    }
                }));
                time_in_turn(s.reps, false, &mut runs)
            };
            if let Some(e) = err {
                return Err(e);
            }
            let (t_em, sp2) = timings.pop().expect("Embree's build was timed");
            if quality == Quality::High {
                ours = built
                    .into_iter()
                    .map(|b| b.expect("built at least once"))
                    .collect();
            }
            for (&(kind, test), &(t_ours, sp)) in s.ours.iter().zip(&timings) {
                builds.push(Cell {
                    what: format!("build vs Embree {quality:?}"),
                    structure: label(kind, test),
                    threads,
                    ours: t_ours * 1e3,
                    embree: t_em * 1e3,
                    // Build: a ratio above 1 means ours is faster.
                    ratio: t_em / t_ours.max(1e-12),
                    spread: sp.max(sp2),
                });
            }
        }
    }
    let embree = EmbreeScene::build(&EmbreeDevice::new(0)?, mesh, trace_quality())?;
    let mut cells = Vec::new();
    let mut push = |what: &str, threads, i: usize, a: f64, sa: f64, b: f64, sb: f64, m: f64| {
        let (kind, test) = s.ours[i];
        cells.push(Cell {
            what: what.to_string(),
            structure: label(kind, test),
            threads,
            ours: m / a,
            embree: m / b,
            ratio: b / a.max(1e-12),
            spread: sa.max(sb),
        });
    };
    for (si, set) in RayKind::ALL.into_iter().enumerate() {
        let rays = &sets[si];
        let shadow = set == RayKind::Shadow;
        let m = rays.len() as f64 / 1e6;
        for (threads, p) in [(1, one), (n, all)] {
            let mut runs: Vec<Run> = ours
                .iter()
                .map(|o| -> Run { Box::new(move || p.install(|| trace(o.as_ref(), rays, shadow))) })
                .collect();
            runs.push(Box::new(|| p.install(|| trace(&embree, rays, shadow))));
            let mut times = time_in_turn(s.reps, true, &mut runs);
            let (b, sb) = times.pop().expect("Embree's cell was timed");
            for (i, &(a, sa)) in times.iter().enumerate() {
                push(set.name(), threads, i, a, sa, b, sb, m);
            }
        }
    }
    // Coherent primaries: Embree's stream API against our batch path.
    let primary = &sets[0];
    let m = primary.len() as f64 / 1e6;
    for (threads, p) in [(1, one), (n, all)] {
        let mut runs: Vec<Run> = ours
            .iter()
            .map(|o| -> Run { Box::new(move || p.install(|| trace(o.as_ref(), primary, false))) })
            .collect();
        runs.push(Box::new(|| {
            p.install(|| {
                let mut hits: Vec<Option<Hit>> = vec![None; primary.len()];
                primary
                    .par_chunks(STREAM_PACKET * 16)
                    .zip(hits.par_chunks_mut(STREAM_PACKET * 16))
                    .for_each(|(r, h)| embree.intersect_stream(r, h, STREAM_PACKET));
            })
        }));
        let mut times = time_in_turn(s.reps, true, &mut runs);
        let (b, sb) = times.pop().expect("Embree's cell was timed");
        for (i, &(a, sa)) in times.iter().enumerate() {
            push(
                "primary, Embree stream (rtcIntersect1M)",
                threads,
                i,
                a,
                sa,
                b,
                sb,
                m,
            );
        }
    }
    let agreement = all.install(|| agreement(mesh, &sets, &embree, &ours, &s.ours));
    Ok(Comparison {
        mesh: name.to_string(),
        triangles: mesh.num_triangles(),
        traced_build: format!("{:?}", high.quality).to_lowercase(),
        ours: s
            .ours
            .iter()
            .zip(&ours)
            .map(|(&(kind, test), o)| {
                let st = o.stats();
                BuiltFigures {
                    structure: label(kind, test),
                    sah_cost: st.sah_cost,
                    bytes: st.bytes,
                    nodes: st.nodes,
                }
            })
            .collect(),
        builds_ms: builds,
        mrays: cells,
        agreement,
    })
}

/// Every ray of every set, Embree's answers against each of ours.
fn agreement(
    mesh: &TriangleMesh,
    sets: &[Vec<Ray>; 3],
    embree: &EmbreeScene,
    ours: &[Box<dyn Accel>],
    names: &[(AccelKind, TestKind)],
) -> Vec<Agreement> {
    let mut out = Vec::new();
    for (si, set) in RayKind::ALL.into_iter().enumerate() {
        let rays = &sets[si];
        if set == RayKind::Shadow {
            // Occlusion answers, and the nearest hits along the segments
            // whose occlusion differs to tell edge grazes apart: is the
            // blocker the one engine found met at an edge?
            let mut x = vec![false; rays.len()];
            embree.occluded_batch(rays, &mut x);
            for (o, &(kind, test)) in ours.iter().zip(names) {
                let mut y = vec![false; rays.len()];
                o.occluded_batch(rays, &mut y);
                let mut verdict = compare_occlusion(&x, &y);
                (verdict.edge_grazes, _) = occlusion_grazes(mesh, rays, &x, &y, |r| {
                    let (mut ha, mut hb) = (vec![None; r.len()], vec![None; r.len()]);
                    embree.intersect_batch(r, &mut ha);
                    o.intersect_batch(r, &mut hb);
                    (ha, hb)
                });
                out.push(Agreement {
                    set: set.name(),
                    structure: label(kind, test),
                    verdict,
                });
            }
        } else {
            let mut a = vec![None; rays.len()];
            embree.intersect_batch(rays, &mut a);
            for (o, &(kind, test)) in ours.iter().zip(names) {
                let mut b = vec![None; rays.len()];
                o.intersect_batch(rays, &mut b);
                let mut verdict = compare_hits(&a, &b);
                verdict.edge_grazes = edge_grazes(mesh, rays, &a, &b);
                out.push(Agreement {
                    set: set.name(),
                    structure: label(kind, test),
                    verdict,
                });
            }
        }
    }
    let primary = &sets[0];
    let mut a = vec![None; primary.len()];
    embree.intersect_stream(primary, &mut a, STREAM_PACKET);
    for (o, &(kind, test)) in ours.iter().zip(names) {
        let mut b = vec![None; primary.len()];
        o.intersect_batch(primary, &mut b);
        let mut verdict = compare_hits(&a, &b);
        verdict.edge_grazes = edge_grazes(mesh, primary, &a, &b);
        out.push(Agreement {
            set: "primary (stream)",
            structure: label(kind, test),
            verdict,
        });
    }
    out
}

/// Per cell (builds against Embree MEDIUM, every Mrays/s cell) and mesh,
/// our best ratio and the structure that reached it.
fn summarise(reports: &[Comparison]) -> Vec<SummaryRow> {
    let mut rows: Vec<SummaryRow> = Vec::new();
    for r in reports {
        let cells = r
            .builds_ms
            .iter()
            .filter(|c| c.what.ends_with("Medium"))
            .chain(&r.mrays);
        for c in cells {
            let i = match rows
                .iter()
                .position(|x| x.what == c.what && x.threads == c.threads)
            {
                Some(i) => i,
                None => {
                    rows.push(SummaryRow {
                        what: c.what.clone(),
                        threads: c.threads,
                        best: Vec::new(),
                    });
                    rows.len() - 1
                }
            };
            let best = &mut rows[i].best;
            match best.iter_mut().find(|b| b.mesh == r.mesh) {
                Some(b) if b.ratio >= c.ratio => {}
                Some(b) => {
                    b.ratio = c.ratio;
                    b.structure = c.structure.clone();
                }
                None => best.push(Best {
                    mesh: r.mesh.clone(),
                    ratio: c.ratio,
                    structure: c.structure.clone(),
                }),
            }
        }
    }
    rows
}

fn print_summary(rows: &[SummaryRow]) {
    let Some(first) = rows.first() else {
        return;
    };
    println!(
        "
summary: our best ratio per cell (build: Embree MEDIUM ÷ ours; rays: ours ÷ Embree); * below 1.0×"
    );
    let short = |m: &str| m.rsplit('/').next().unwrap_or(m).to_string();
    let widths: Vec<usize> = first
        .best
        .iter()
        .map(|b| short(&b.mesh).chars().count().max(16))
        .collect();
    print!("{:<48} {:>7}", "cell", "threads");
    for (b, w) in first.best.iter().zip(&widths) {
        print!("  {:>w$}", short(&b.mesh));
    }
    println!();
    for r in rows {
        print!("{:<48} {:>7}", r.what, r.threads);
        for (b, w) in r.best.iter().zip(&widths) {
            let mark = if b.ratio < 1.0 { "*" } else { " " };
            let s = b.structure.split(' ').next().unwrap_or("");
            let cell = format!("{s} {:.2}×{mark}", b.ratio);
            print!("  {cell:>w$}");
        }
        println!();
    }
}

fn print_report(r: &Comparison, reps: usize) {
    let ours: Vec<String> = r
        .ours
        .iter()
        .map(|q| {
            format!(
                "{} (SAH cost {:.1}, {} nodes, {:.1} MB)",
                q.structure,
                q.sah_cost,
                q.nodes,
                q.bytes as f64 / 1e6
            )
        })
        .collect();
    println!(
        "{}: {} triangles; ours = {} traced as built with --bvh-build {}; Embree 3 single-ray API ({} build) unless noted; median of {reps} runs, the engines timed in turn (traces after one untimed round)",
        r.mesh,
        r.triangles,
        ours.join(", "),
        r.traced_build,
        match trace_quality() {
            Quality::High => "HIGH",
            Quality::Medium => "MEDIUM",
        },
    );
    let several = r.ours.len() > 1;
    print_cells("build (ms)", "Embree÷ours", 1, &r.builds_ms, several);
    print_cells("Mrays/s", "ours÷Embree", 2, &r.mrays, several);
    println!("\nanswers against Embree (every ray):");
    for a in &r.agreement {
        let v = &a.verdict;
        println!(
            "  {:<18} {} rays: {} hit/miss and {} distance differences, of which {} graze an edge (f64) or hit the same triangle; {} same-distance ties{}{}",
            a.set,
            v.checked,
            v.hit_miss,
            v.distance,
            v.edge_grazes,
            v.ties,
            if several { format!(" [{}]", a.structure) } else { String::new() },
            if v.ok() { "" } else { "  <-- DISAGREE" }
        );
    }
}

/// One table of cells, values with `digits` decimals; with `several`
/// structures each row names its own.
fn print_cells(title: &str, ratio: &str, digits: usize, cells: &[Cell], several: bool) {
    println!(
        "\n{title:<48} {:>7} {:>10} {:>10} {ratio:>8} {:>7}",
        "threads", "ours", "Embree", "spread"
    );
    for c in cells {
        let what = if several {
            format!(
                "{} [{}]",
                c.what,
                c.structure.split(' ').next().unwrap_or("")
            )
        } else {
            c.what.clone()
        };
        println!(
            "{:<48} {:>7} {:>10.digits$} {:>10.digits$} {:>10.2}× {:>6.0}%",
            what,
            c.threads,
            c.ours,
            c.embree,
            c.ratio,
            100.0 * c.spread
        );
    }
}
