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

mod agreement;
mod print;
mod report;
mod timing;

use crate::measure::pool;
use agreement::agreement;
use anyhow::Result;
use print::{print_report, print_summary, summarise};
use raykit_core::accel::{build_accel, AccelKind, BuildOptions, BuildQuality};
use raykit_core::raysets::{self, RayKind};
use raykit_core::tri::TestKind;
use raykit_core::{Accel, Hit, TriangleMesh};
use raykit_embree::{
    Embree3Device, Embree3Scene, Embree4, Embree4Device, Embree4Scene, Quality, QueryApi,
};
use rayon::prelude::*;
use rayon::ThreadPool;
use report::{label, trace_quality, BuiltFigures, Comparison};
use std::process::ExitCode;
use std::sync::Arc;
use timing::{time_in_turn, trace, trace4, trace_one_ray, CellTimes, Run, STREAM_PACKET};

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
    // One thread, then all of them: the same cells once when all is one.
    let both = [(1, one), (n, all)];
    let pools_all: &[(usize, &ThreadPool)] = if n == 1 { &both[..1] } else { &both };
    for &(threads, p) in pools_all {
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
            let pools: &[(usize, &ThreadPool)] = if one_ray_api { &[(1, one)] } else { pools_all };
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
        for &(threads, p) in pools_all {
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
