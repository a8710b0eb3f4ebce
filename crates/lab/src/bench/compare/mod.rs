//! `raykit bench --compare embree`: our structures and Embree (version 4
//! loaded at run time, version 3 linked, or both) built on the same meshes,
//! tracing the same rays in the same process; every cell is printed as
//! ours, each Embree's and the ratios, and the answers are checked to agree
//! (hit/miss and distance; different triangles at the same distance, and
//! rays grazing a shared edge that one engine catches and the other slips
//! through, are ties). Embree 4 is timed through each of its query APIs
//! (single rays, packets of 4, 8 and 16) and its fastest counts; Embree 3
//! through its single-ray API, and its stream API on primaries. The one-ray
//! cells time our per-ray API (`Accel::intersect` / `occluded`, one call
//! per ray) against `rtcIntersect1` / `rtcOccluded1`. With several meshes
//! or structures a summary gives, per cell and mesh, our best ratio.

mod print;

use crate::measure::{median_min_max, pool, timed};
use crate::one_ray;
use anyhow::Result;
use print::{print_report, print_summary, summarise};
use raykit_core::accel::{build_accel, AccelKind, BuildOptions, BuildQuality};
use raykit_core::raysets::{self, RayKind};
use raykit_core::tri::TestKind;
use raykit_core::verify::{
    compare_hits, compare_occlusion, edge_grazes, occlusion_grazes, Verdict,
};
use raykit_core::{Accel, Hit, Ray, TriangleMesh};
use raykit_embree::{
    Embree3Device, Embree3Scene, Embree4, Embree4Device, Embree4Scene, Quality, QueryApi,
};
use rayon::prelude::*;
use rayon::ThreadPool;
use serde::Serialize;
use std::process::ExitCode;
use std::sync::Arc;

/// Rays per `rtcIntersect1M` call of the Embree 3 stream cell.
const STREAM_PACKET: usize = 256;

/// The Embree versions compared.
pub struct Yardsticks {
    /// Embree 3 (linked).
    pub embree3: bool,
    /// Embree 4, loaded.
    pub embree4: Option<Arc<Embree4>>,
}

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
    /// The Embree versions to compare with.
    pub yardsticks: Yardsticks,
}

/// One cell: our figure beside each Embree's. Builds in ms (a ratio above
/// 1 means our build is faster), traces in Mrays/s (ours ÷ Embree).
#[derive(Serialize)]
pub(crate) struct Cell {
    pub what: String,
    /// Our structure × test of this cell.
    pub structure: String,
    pub threads: usize,
    pub ours: f64,
    /// Embree 4's figure: its fastest API on trace cells.
    pub embree4: Option<f64>,
    /// The Embree 4 API that gave it (`rtcIntersect16`, …).
    pub embree4_api: Option<String>,
    pub ratio4: Option<f64>,
    pub embree3: Option<f64>,
    pub ratio3: Option<f64>,
    /// Largest (max−min)/median of the samples behind the figures.
    pub spread: f64,
}

#[derive(Serialize)]
pub(crate) struct Agreement {
    pub set: &'static str,
    /// Our structure × test compared, and its API (batch or one-ray).
    pub structure: String,
    /// The Embree and API whose answers ours are compared with.
    pub engine: String,
    /// Every ray of the set; `edge_grazes` counts the disagreements where
    /// the nearer answer's triangle is met within the edge band (f64): the
    /// ray grazes an edge, one engine catches it where the other slips past.
    pub verdict: Verdict,
}

/// The build Embree traces: HIGH (with spatial splits), or MEDIUM where
/// RAYKIT_EMBREE_TRACE_MEDIUM is set (an experiment: on the scatter both
/// trace at the same speed, so the splits are not what Embree's lead on
/// shadow and incoherent rays comes from).
pub(crate) fn trace_quality() -> Quality {
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
pub(crate) struct BuiltFigures {
    pub structure: String,
    pub sah_cost: f64,
    pub bytes: usize,
    pub nodes: usize,
}

#[derive(Serialize)]
pub(crate) struct Comparison {
    pub mesh: String,
    pub triangles: usize,
    /// The builder of the structures traced (`--bvh-build`).
    pub traced_build: String,
    /// The Embree versions compared (`4.4.0 (path)`, `3`).
    pub embree4: Option<String>,
    pub embree3: bool,
    pub ours: Vec<BuiltFigures>,
    pub builds_ms: Vec<Cell>,
    pub mrays: Vec<Cell>,
    pub agreement: Vec<Agreement>,
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

/// Our one-ray API over the set.
fn trace_one_ray(accel: &dyn Accel, rays: &[Ray], shadow: bool) {
    if shadow {
        let mut o = vec![false; rays.len()];
        one_ray::occluded_each(accel, rays, &mut o);
    } else {
        let mut h = vec![None; rays.len()];
        one_ray::intersect_each(accel, rays, &mut h);
    }
}

/// Embree 4 through `api`; primaries and shadow rays (which leave from
/// the primaries' hit points in pixel order) carry the coherent hint.
fn trace4(em: &Embree4Scene, api: QueryApi, rays: &[Ray], set: RayKind) {
    let coherent = set != RayKind::Incoherent;
    if set == RayKind::Shadow {
        let mut o = vec![false; rays.len()];
        em.occluded_with(api, rays, &mut o, coherent);
    } else {
        let mut h = vec![None; rays.len()];
        em.intersect_with(api, rays, &mut h, coherent);
    }
}

/// The Embree 4 call of `api` for a set.
fn api_name(api: QueryApi, shadow: bool) -> String {
    let call = if shadow {
        "rtcOccluded"
    } else {
        "rtcIntersect"
    };
    format!("{call}{}", api.width())
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

/// Medians and spreads of one cell's runs, in the order pushed: ours
/// first (one per structure), then Embree 4's APIs, then Embree 3.
struct CellTimes {
    ours: Vec<(f64, f64)>,
    embree4: Vec<(QueryApi, f64, f64)>,
    embree3: Option<(f64, f64)>,
}

impl CellTimes {
    /// Split `times` (from `time_in_turn`) as the runs were pushed.
    fn split(mut times: Vec<(f64, f64)>, apis: &[QueryApi], embree3: bool) -> CellTimes {
        let embree3 = if embree3 { times.pop() } else { None };
        let e4 = times.split_off(times.len() - apis.len());
        CellTimes {
            ours: times,
            embree4: apis
                .iter()
                .zip(e4)
                .map(|(&a, (t, sp))| (a, t, sp))
                .collect(),
            embree3,
        }
    }

    /// Cells of `what`: each of ours against Embree 4's fastest API and
    /// Embree 3. `rate` turns seconds into the figure shown (ms or
    /// Mrays/s), `ratio` two times into ours' advantage.
    #[allow(clippy::too_many_arguments)]
    fn cells(
        &self,
        what: &str,
        threads: usize,
        ours: &[(AccelKind, TestKind)],
        shadow: bool,
        rate: impl Fn(f64) -> f64,
        out: &mut Vec<Cell>,
    ) {
        let best4 = self
            .embree4
            .iter()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .copied();
        for (&(kind, test), &(t, sp)) in ours.iter().zip(&self.ours) {
            let t = t.max(1e-12);
            out.push(Cell {
                what: what.to_string(),
                structure: label(kind, test),
                threads,
                ours: rate(t),
                embree4: best4.map(|b| rate(b.1)),
                embree4_api: best4
                    .filter(|_| self.embree4.len() > 1 || !what.starts_with("build"))
                    .map(|b| api_name(b.0, shadow)),
                ratio4: best4.map(|b| b.1 / t),
                embree3: self.embree3.map(|e| rate(e.0)),
                ratio3: self.embree3.map(|e| e.0 / t),
                spread: best4
                    .map(|b| b.2)
                    .into_iter()
                    .chain(self.embree3.map(|e| e.1))
                    .fold(sp, f64::max),
            });
        }
    }
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
    let (e3, e4lib) = (s.yardsticks.embree3, s.yardsticks.embree4.as_ref());
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
    let build_apis: &[QueryApi] = if e4lib.is_some() {
        &[QueryApi::Single]
    } else {
        &[]
    };
    for (threads, p) in [(1, one), (n, all)] {
        // The devices (Embree's thread pools) are made outside the timing.
        let device3 = if e3 {
            Some(Embree3Device::new(threads)?)
        } else {
            None
        };
        let device4 = e4lib
            .map(|lib| Embree4Device::new(lib, threads))
            .transpose()?;
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
            let (mut err4, mut err3) = (None, None);
            let times = {
                let mut runs: Vec<Run> = built
                    .iter_mut()
                    .zip(&s.ours)
                    .map(|(slot, &(kind, test))| -> Run {
                        Box::new(move || {
                            *slot = Some(p.install(|| build_accel(kind, test, mesh, opts)))
                        })
                    })
                    .collect();
                if let Some(d) = &device4 {
                    let err = &mut err4;
                    runs.push(Box::new(move || {
                        if let Err(e) = Embree4Scene::build(d, mesh, quality) {
                            *err = Some(e);
                        }
                    }));
                }
                if let Some(d) = &device3 {
                    let err = &mut err3;
                    runs.push(Box::new(move || {
                        if let Err(e) = Embree3Scene::build(d, mesh, quality) {
                            *err = Some(e);
                        }
                    }));
                }
                time_in_turn(s.reps, false, &mut runs)
            };
            if let Some(e) = err4.or(err3) {
                return Err(e);
            }
            if quality == Quality::High {
                ours = built
                    .into_iter()
                    .map(|b| b.expect("built at least once"))
                    .collect();
            }
            CellTimes::split(times, build_apis, e3).cells(
                &format!("build vs Embree {quality:?}"),
                threads,
                &s.ours,
                false,
                |t| t * 1e3,
                &mut builds,
            );
        }
    }
    let embree3 = if e3 {
        Some(Embree3Scene::build(
            &Embree3Device::new(0)?,
            mesh,
            trace_quality(),
        )?)
    } else {
        None
    };
    let embree4 = e4lib
        .map(|lib| Embree4Scene::build(&Embree4Device::new(lib, 0)?, mesh, trace_quality()))
        .transpose()?;
    let all_apis: &[QueryApi] = if embree4.is_some() {
        &QueryApi::ALL
    } else {
        &[]
    };
    let single: &[QueryApi] = if embree4.is_some() {
        &[QueryApi::Single]
    } else {
        &[]
    };
    let mut cells = Vec::new();
    // Batch cells: our batch path against Embree 4's fastest API and
    // Embree 3's single rays; one-ray cells: our per-ray API against
    // Embree's single-ray calls, on one thread (a library user's loop).
    for one_ray_api in [false, true] {
        for (si, set) in RayKind::ALL.into_iter().enumerate() {
            let rays = &sets[si];
            let shadow = set == RayKind::Shadow;
            let m = rays.len() as f64 / 1e6;
            let pools: &[(usize, &ThreadPool)] = if one_ray_api {
                &[(1, one)]
            } else {
                &[(1, one), (n, all)]
            };
            let apis = if one_ray_api { single } else { all_apis };
            for &(threads, p) in pools {
                let mut runs: Vec<Run> = ours
                    .iter()
                    .map(|o| -> Run {
                        Box::new(move || {
                            p.install(|| {
                                if one_ray_api {
                                    trace_one_ray(o.as_ref(), rays, shadow)
                                } else {
                                    trace(o.as_ref(), rays, shadow)
                                }
                            })
                        })
                    })
                    .collect();
                if let Some(em) = &embree4 {
                    for &api in apis {
                        runs.push(Box::new(move || p.install(|| trace4(em, api, rays, set))));
                    }
                }
                if let Some(em) = &embree3 {
                    runs.push(Box::new(move || {
                        p.install(|| trace_one_ray(em, rays, shadow))
                    }));
                }
                let times = time_in_turn(s.reps, true, &mut runs);
                let what = if one_ray_api {
                    format!("{}, one ray", set.name())
                } else {
                    set.name().to_string()
                };
                CellTimes::split(times, apis, embree3.is_some()).cells(
                    &what,
                    threads,
                    &s.ours,
                    shadow,
                    |t| m / t,
                    &mut cells,
                );
            }
        }
    }
    // Coherent primaries: Embree 3's stream API against our batch path.
    if let Some(em) = &embree3 {
        let primary = &sets[0];
        let m = primary.len() as f64 / 1e6;
        for (threads, p) in [(1, one), (n, all)] {
            let mut runs: Vec<Run> = ours
                .iter()
                .map(|o| -> Run {
                    Box::new(move || p.install(|| trace(o.as_ref(), primary, false)))
                })
                .collect();
            runs.push(Box::new(|| {
                p.install(|| {
                    let mut hits: Vec<Option<Hit>> = vec![None; primary.len()];
                    primary
                        .par_chunks(STREAM_PACKET * 16)
                        .zip(hits.par_chunks_mut(STREAM_PACKET * 16))
                        .for_each(|(r, h)| em.intersect_stream(r, h, STREAM_PACKET));
                })
            }));
            let times = time_in_turn(s.reps, true, &mut runs);
            CellTimes::split(times, &[], true).cells(
                "primary, Embree 3 stream (rtcIntersect1M)",
                threads,
                &s.ours,
                false,
                |t| m / t,
                &mut cells,
            );
        }
    }
    let agreement = all.install(|| {
        agreement(
            mesh,
            &sets,
            embree3.as_ref(),
            embree4.as_ref(),
            &ours,
            &s.ours,
        )
    });
    Ok(Comparison {
        mesh: name.to_string(),
        triangles: mesh.num_triangles(),
        traced_build: format!("{:?}", high.quality).to_lowercase(),
        embree4: e4lib.map(|l| format!("{} ({})", l.version, l.path.display())),
        embree3: e3,
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

/// Answers of one engine and API on a set.
enum Answers {
    Hits(Vec<Option<Hit>>),
    Occluded(Vec<bool>),
}

/// An engine's nearest hits of some rays, into a slice.
type HitsInto<'a> = dyn Fn(&[Ray], &mut [Option<Hit>]) + 'a;
/// An engine's occlusion answers of some rays, into a slice.
type OcclusionInto<'a> = dyn Fn(&[Ray], &mut [bool]) + 'a;

/// An engine's nearest hits of some rays.
type NearestHits<'a> = Box<dyn Fn(&[Ray]) -> Vec<Option<Hit>> + 'a>;

/// Every ray of every set: ours (batch and one-ray) against Embree 3's
/// single rays and stream, and against each Embree 4 API.
fn agreement(
    mesh: &TriangleMesh,
    sets: &[Vec<Ray>; 3],
    embree3: Option<&Embree3Scene>,
    embree4: Option<&Embree4Scene>,
    ours: &[Box<dyn Accel>],
    names: &[(AccelKind, TestKind)],
) -> Vec<Agreement> {
    let mut out = Vec::new();
    for (si, set) in RayKind::ALL.into_iter().enumerate() {
        let rays = &sets[si];
        let shadow = set == RayKind::Shadow;
        let coherent = set != RayKind::Incoherent;
        // (engine label, its answers, and a nearest-hit oracle of the same
        // engine for telling edge grazes apart on shadow rays)
        let mut theirs: Vec<(String, Answers, NearestHits)> = Vec::new();
        let answers = |f: &HitsInto, g: &OcclusionInto| {
            if shadow {
                let mut o = vec![false; rays.len()];
                g(rays, &mut o);
                Answers::Occluded(o)
            } else {
                let mut h = vec![None; rays.len()];
                f(rays, &mut h);
                Answers::Hits(h)
            }
        };
        if let Some(em) = embree3 {
            theirs.push((
                format!(
                    "Embree 3 {}",
                    if shadow {
                        "rtcOccluded1"
                    } else {
                        "rtcIntersect1"
                    }
                ),
                answers(&|r, h| em.intersect_batch(r, h), &|r, o| {
                    em.occluded_batch(r, o)
                }),
                Box::new(move |r: &[Ray]| {
                    let mut h = vec![None; r.len()];
                    em.intersect_batch(r, &mut h);
                    h
                }),
            ));
            if set == RayKind::Primary {
                let mut h = vec![None; rays.len()];
                em.intersect_stream(rays, &mut h, STREAM_PACKET);
                theirs.push((
                    "Embree 3 rtcIntersect1M".to_string(),
                    Answers::Hits(h),
                    Box::new(|_: &[Ray]| Vec::new()),
                ));
            }
        }
        if let Some(em) = embree4 {
            for api in QueryApi::ALL {
                theirs.push((
                    format!("Embree 4 {}", api_name(api, shadow)),
                    answers(&|r, h| em.intersect_with(api, r, h, coherent), &|r, o| {
                        em.occluded_with(api, r, o, coherent)
                    }),
                    Box::new(move |r: &[Ray]| {
                        let mut h = vec![None; r.len()];
                        em.intersect_with(api, r, &mut h, coherent);
                        h
                    }),
                ));
            }
        }
        for (o, &(kind, test)) in ours.iter().zip(names) {
            for one_ray_api in [false, true] {
                let mine = answers(
                    &|r, h| {
                        if one_ray_api {
                            one_ray::intersect_each(o.as_ref(), r, h)
                        } else {
                            o.intersect_batch(r, h)
                        }
                    },
                    &|r, v| {
                        if one_ray_api {
                            one_ray::occluded_each(o.as_ref(), r, v)
                        } else {
                            o.occluded_batch(r, v)
                        }
                    },
                );
                let structure = format!(
                    "{}{}",
                    label(kind, test),
                    if one_ray_api { ", one ray" } else { "" }
                );
                for (engine, theirs, nearest) in &theirs {
                    // The one-ray answers against the single-ray calls only.
                    if one_ray_api && !engine.ends_with('1') {
                        continue;
                    }
                    let verdict = match (theirs, &mine) {
                        (Answers::Hits(a), Answers::Hits(b)) => {
                            let mut v = compare_hits(a, b);
                            v.edge_grazes = edge_grazes(mesh, rays, a, b);
                            v
                        }
                        (Answers::Occluded(a), Answers::Occluded(b)) => {
                            let mut v = compare_occlusion(a, b);
                            (v.edge_grazes, _) = occlusion_grazes(mesh, rays, a, b, |r| {
                                let mut hb = vec![None; r.len()];
                                o.intersect_batch(r, &mut hb);
                                (nearest(r), hb)
                            });
                            v
                        }
                        _ => unreachable!("both answer the same kind of query"),
                    };
                    out.push(Agreement {
                        set: set.name(),
                        structure: structure.clone(),
                        engine: engine.clone(),
                        verdict,
                    });
                }
            }
        }
    }
    out
}
