//! `raykit experiment cull`: culling measured on this machine — the
//! ray-traced mode (`cull_by_rays`) and Min's (2008) grid method (grid
//! resolution, parts and triangles hidden, removal rate, distance-field and
//! propagation times) for Min's rule and our conservative mode — with false
//! and missed removals against the ray-traced ground truth.

use super::{shared_mesh, write_csv, write_text};
use crate::measure::{median_min_max, timed};
use crate::plot::{write_svg, LineChart, Series};
use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::tri::TestKind;
use raykit_core::{Aabb, TriangleMesh, Vec3};
use raykit_cull::synthetic::{
    assembly, box_of_spheres, closed_box, copies, shell_around, slit_box,
};
use raykit_cull::{
    compare, cull, cull_by_rays, evaluate_with_progress, CullOptions, CullResult, EvalOptions,
    Grid, RayOptions,
};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Where `scripts/fetch-assimp-testmodels.sh` unpacks Debian's
/// assimp-testmodels.
const ASSIMP_DIR: &str = "data-cache/assimp-testmodels/usr/share/assimp/models";

/// The assemblies of assimp-testmodels this experiment reads (formats raykit
/// loads; the rest of the package is single objects or other formats).
const ASSIMP_MODELS: [&str; 3] = ["OBJ/spider.obj", "OBJ/regr01.obj", "STL/sphereWithHole.stl"];

/// Arguments of `raykit experiment cull`.
#[derive(Args)]
#[command(
    after_help = "Models: the shared 2CylinderEngine.glb and bearing.stl, three assemblies of\n\
Debian's assimp-testmodels (run scripts/fetch-assimp-testmodels.sh first, else they are\n\
reported as skipped), synthetic assemblies with known answers (a box of 64 spheres, nested\n\
shells, a box with a slit 1/500 of its size wide, a box of 1,000 spheres with 1,280,192\n\
triangles, eight engines in a closed shell of 100 x 100 squares per face: 1,091,968 triangles),\n\
the same shell with a 20 x 20-square hole and the engine instanced 3 x 3 (1,093,464\n\
triangles): these two have no ground truth (too slow to evaluate), so no false removals.\n\
Each model is culled by rays (`raykit cull --mode rays`), and at every resolution by Min's\n\
(2008) rule (`--mode paper`) and by the conservative grid mode (`--mode conservative`, the\n\
default of `raykit cull`); times are medians of --reps runs. The ground truth is `raykit cull --evaluate`'s\n\
(rays from the surface and renders from 10,000+ viewpoints, doubled until stable) or the\n\
known answer. Writes results.csv, results.md and SVG plots into --out; exit status 1 when\n\
the conservative mode (the default of `raykit cull`) removed a truly visible triangle; the\n\
rays mode's false removals are reported, not failed on."
)]
pub struct CullExperimentArgs {
    /// Grid resolutions (points along the longest axis), each in 5..=1024
    /// as `raykit cull --resolution` takes it.
    #[arg(long, value_delimiter = ',', default_value = "64,128,256",
          value_parser = clap::value_parser!(u32).range(Grid::MIN_RESOLUTION as i64..=Grid::MAX_RESOLUTION as i64))]
    resolutions: Vec<u32>,
    /// Repetitions of every timing (the median is reported); 1 to 1000.
    #[arg(long, default_value_t = 3)]
    reps: usize,
    /// Most rounds of the ground truth (see `raykit cull --eval-rounds`).
    #[arg(long, default_value_t = EvalOptions::default().max_rounds as u32,
          value_parser = clap::value_parser!(u32).range(2..=raykit_cull::evaluate::MAX_ROUNDS as i64))]
    eval_rounds: u32,
    /// Leave out the 1M-triangle assemblies (still minutes: the ground truth
    /// of each model is searched to convergence).
    #[arg(long)]
    small: bool,
    /// Output folder.
    #[arg(long, default_value = "experiments/cull")]
    out: PathBuf,
}

/// What the removals are checked against.
enum Truth {
    /// Per triangle visible, with a note on how it was found.
    Labels(Vec<bool>, String),
    /// No ground truth, and why.
    Missing(String),
}

/// One model of the table.
struct Model {
    name: String,
    mesh: TriangleMesh,
    /// Known per-triangle visibility, else evaluate by rays.
    known: Option<Vec<bool>>,
    /// Evaluate by rays when nothing is known (false: too big).
    evaluate: bool,
}

/// One row of the table: a model at one resolution in one mode.
#[derive(Serialize, Clone)]
struct Row {
    model: String,
    triangles: usize,
    parts: usize,
    resolution: usize,
    mode: &'static str,
    grid: String,
    distance_field_s: f64,
    propagation_s: f64,
    visible_s: f64,
    total_s: f64,
    total_min_s: f64,
    total_max_s: f64,
    triangles_removed: usize,
    removed_triangles_pct: f64,
    removed_area_pct: f64,
    parts_removed: usize,
    truly_hidden: Option<usize>,
    false_removals: Option<usize>,
    missed_removals_pct: Option<f64>,
    truth: String,
}

/// Run the experiment.
pub fn run(args: CullExperimentArgs) -> Result<ExitCode> {
    crate::args::ranges::reps(args.reps)?;
    let head = super::provenance();
    let models = models(&args)?;
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    for m in models {
        let m = match m {
            Ok(m) => m,
            Err(why) => {
                eprintln!("skipped: {why}");
                skipped.push(why);
                continue;
            }
        };
        eprintln!(
            "{}: {} triangles, {} parts",
            m.name,
            m.mesh.num_triangles(),
            m.mesh.parts.len().max(1)
        );
        let truth = truth_of(&m, args.eval_rounds as usize);
        rows.push(measure_rays(&m, &truth, args.reps)?);
        for res in args.resolutions.iter().map(|&r| r as usize) {
            let mut modes = vec![
                ("paper", CullOptions::paper(res)),
                ("conservative", CullOptions::conservative(res)),
            ];
            if m.evaluate {
                modes.push((
                    "conservative + confirm",
                    CullOptions {
                        confirm: Some(EvalOptions::confirmation()),
                        ..CullOptions::conservative(res)
                    },
                ));
            }
            for (mode, options) in modes {
                rows.push(measure(&m, &truth, res, mode, &options, args.reps)?);
            }
        }
    }
    write_csv(&args.out, "results.csv", &rows)?;
    let md = markdown(&rows, &skipped, &head);
    write_text(&args.out, "results.md", &md)?;
    print!("{md}");
    plots(&rows, &args.out)?;
    eprintln!(
        "wrote {}/results.csv, results.md, removal-*.svg, time.svg",
        args.out.display()
    );
    let false_removals: usize = rows
        .iter()
        .filter(|r| r.mode == "conservative")
        .filter_map(|r| r.false_removals)
        .sum();
    Ok(if false_removals == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// The models, in table order; `Err` names a model that could not be had.
fn models(args: &CullExperimentArgs) -> Result<Vec<Result<Model, String>>> {
    let mut out = Vec::new();
    for name in ["2CylinderEngine.glb", "bearing.stl"] {
        out.push(file_model(Path::new(&shared_mesh(name)), name));
    }
    let assimp = super::repository().join(ASSIMP_DIR);
    for rel in ASSIMP_MODELS {
        let path = assimp.join(rel);
        out.push(if path.is_file() {
            file_model(&path, &format!("assimp {rel}"))
        } else {
            Err(format!(
                "assimp {rel}: {} is missing; run scripts/fetch-assimp-testmodels.sh",
                path.display()
            ))
        });
    }
    let only_first = |mesh: &TriangleMesh| -> Vec<bool> {
        (0..mesh.num_triangles())
            .map(|t| mesh.part_of(t) == 0)
            .collect()
    };
    let spheres = box_of_spheres(4, 4, 2);
    out.push(Ok(Model {
        name: "box of 64 spheres".into(),
        known: Some(only_first(&spheres)),
        mesh: spheres,
        evaluate: false,
    }));
    let shells = assembly((0..4).map(|i| {
        let r = 1.0 - 0.2 * i as f32;
        closed_box(&Aabb::new(Vec3::splat(-r), Vec3::splat(r)), 8)
    }));
    out.push(Ok(Model {
        name: "4 nested shells".into(),
        known: Some(only_first(&shells)),
        mesh: shells,
        evaluate: false,
    }));
    out.push(Ok(Model {
        name: "box with a 1/500 slit".into(),
        known: None,
        mesh: slit_box(8, 0.002, 3),
        evaluate: true,
    }));
    if !args.small {
        let big = box_of_spheres(4, 10, 3);
        out.push(Ok(Model {
            name: "box of 1,000 spheres".into(),
            known: Some(only_first(&big)),
            mesh: big,
            evaluate: false,
        }));
        if let Ok(engine) = raykit_io::load_mesh(Path::new(&shared_mesh("2CylinderEngine.glb"))) {
            let eight = copies(&engine, [2, 2, 2], 0.1);
            let closed = shell_around(&eight, 0.05, 100, None);
            out.push(Ok(Model {
                name: "8 engines in a closed shell".into(),
                known: Some(only_first(&closed)),
                mesh: closed,
                evaluate: false,
            }));
            out.push(Ok(Model {
                name: "8 engines in a shell with a hole".into(),
                mesh: shell_around(&eight, 0.05, 100, Some(20)),
                known: None,
                evaluate: false,
            }));
            let mesh = copies(&engine, [3, 3, 1], 0.1);
            // Saved, so that `raykit cull` can be timed on it as a user runs it.
            std::fs::create_dir_all(&args.out)?;
            let path = args.out.join("engine-x9.glb");
            raykit_io::save_mesh(&path, &mesh)
                .with_context(|| format!("cannot write {}", path.display()))?;
            out.push(Ok(Model {
                name: "engine x 9 (instanced)".into(),
                mesh,
                known: None,
                evaluate: false,
            }));
        }
    }
    Ok(out)
}

fn file_model(path: &Path, name: &str) -> Result<Model, String> {
    raykit_io::load_mesh(path)
        .map(|mesh| Model {
            name: name.to_string(),
            mesh,
            known: None,
            evaluate: true,
        })
        .map_err(|e| format!("{name}: {e}"))
}

fn truth_of(m: &Model, rounds: usize) -> Truth {
    if let Some(k) = &m.known {
        return Truth::Labels(k.clone(), "known".into());
    }
    if !m.evaluate {
        return Truth::Missing("none (too large to evaluate)".into());
    }
    let accel = build_accel(
        AccelKind::Bvh2,
        TestKind::Plucker,
        &m.mesh,
        &BuildOptions::default(),
    );
    let options = EvalOptions {
        max_rounds: rounds,
        ..Default::default()
    };
    let bar = ProgressBar::new(1).with_style(
        ProgressStyle::with_template("ground truth, round {msg} {bar:30} {pos}/{len} [{elapsed}]")
            .expect("valid template"),
    );
    let g = evaluate_with_progress(&m.mesh, accel.as_ref(), &options, &|p| {
        if p.done == 1 {
            bar.set_length(p.total);
            bar.set_message(format!("{} of {rounds}", p.round + 1));
        }
        bar.set_position(p.done);
    });
    bar.finish_and_clear();
    let note = format!(
        "rays: {} rounds{}, {:.0} s",
        g.rounds,
        if g.converged {
            ", converged".to_string()
        } else {
            format!(", last added {}", g.last_change)
        },
        g.seconds
    );
    eprintln!(
        "  ground truth: {} of {} visible ({note})",
        g.visible_count,
        m.mesh.num_triangles()
    );
    Truth::Labels(g.visible, note)
}

/// One row for the ray-traced mode (no grid: resolution 0).
fn measure_rays(m: &Model, truth: &Truth, reps: usize) -> Result<Row> {
    let mut totals = Vec::new();
    let mut result: Option<CullResult> = None;
    for _ in 0..reps.max(1) {
        let (r, s) = timed(|| cull_by_rays(&m.mesh, &RayOptions::default()));
        totals.push(s);
        result = Some(r.with_context(|| m.name.clone())?);
    }
    let r = result.expect("at least one repetition");
    let x = r.stats.rays.clone().unwrap_or_default();
    let mut row = row_of(m, truth, 0, "rays", &r, &totals);
    row.grid = format!(
        "{} rounds{}, {:.0} rays/triangle, removed survived {}",
        x.rounds,
        if x.converged { ", converged" } else { "" },
        x.rays_per_triangle,
        x.rays_per_removed
    );
    Ok(row)
}

fn measure(
    m: &Model,
    truth: &Truth,
    resolution: usize,
    mode: &'static str,
    options: &CullOptions,
    reps: usize,
) -> Result<Row> {
    let mut totals = Vec::new();
    let mut result: Option<CullResult> = None;
    for _ in 0..reps.max(1) {
        let (r, s) = timed(|| cull(&m.mesh, options));
        totals.push(s);
        result = Some(r.with_context(|| m.name.clone())?);
    }
    let r = result.expect("at least one repetition");
    Ok(row_of(m, truth, resolution, mode, &r, &totals))
}

/// The row of result `r` of `m` in `mode`, timed by `totals`.
fn row_of(
    m: &Model,
    truth: &Truth,
    resolution: usize,
    mode: &'static str,
    r: &CullResult,
    totals: &[f64],
) -> Row {
    let s = &r.stats;
    let (total_s, total_min_s, total_max_s) = median_min_max(totals);
    // The removal fractions need no truth: without one, compare against
    // "nothing visible" and keep only them.
    let (labels, note, known) = match truth {
        Truth::Labels(labels, note) => (labels.clone(), note.clone(), true),
        Truth::Missing(why) => (vec![false; m.mesh.num_triangles()], why.clone(), false),
    };
    let g = raykit_cull::GroundTruth {
        visible: labels,
        ..Default::default()
    };
    let e = compare(&g, &r.visible, &m.mesh);
    let removed_area = 100.0 * e.removed_fraction_area;
    let (truly_hidden, false_removals, missed) = if known {
        (
            Some(e.truly_hidden),
            Some(e.false_removals),
            Some(100.0 * e.missed_fraction),
        )
    } else {
        (None, None, None)
    };
    Row {
        model: m.name.clone(),
        triangles: s.triangles,
        parts: s.parts,
        resolution,
        mode,
        grid: format!("{}x{}x{}", s.grid[0], s.grid[1], s.grid[2]),
        distance_field_s: s.distance_field_seconds,
        propagation_s: s.propagation_seconds,
        visible_s: s.visible_seconds,
        total_s,
        total_min_s,
        total_max_s,
        triangles_removed: s.triangles_removed,
        removed_triangles_pct: 100.0 * s.triangles_removed as f64 / s.triangles.max(1) as f64,
        removed_area_pct: removed_area,
        parts_removed: s.parts_removed,
        truly_hidden,
        false_removals,
        missed_removals_pct: missed,
        truth: note,
    }
}

fn markdown(rows: &[Row], skipped: &[String], head: &str) -> String {
    let opt = |v: Option<usize>| v.map_or("–".to_string(), |v| v.to_string());
    let optf = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.1}"));
    let mut md = format!(
        "# Culling experiment: ray-traced visibility and Min (2008)'s global visibility culling\n\n{head}\n"
    );
    md.push_str(
        "| model | triangles | parts | resolution | grid / rays | mode | distance field s | propagation s | \
         visible set s | total s (median) | triangles removed | removed % (triangles / area) | \
         parts removed | truly hidden | false removals | missed % of hidden | ground truth |\n\
         |---|---:|---:|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n",
    );
    for r in rows {
        md += &format!(
            "| {} | {} | {} | {} | {} | {} | {:.3} | {:.3} | {:.3} | {:.3} ({:.3}–{:.3}) | {} | {:.1} / {:.1} | {} | {} | {} | {} | {} |\n",
            r.model,
            r.triangles,
            r.parts,
            if r.resolution == 0 {
                "–".to_string()
            } else {
                r.resolution.to_string()
            },
            r.grid,
            r.mode,
            r.distance_field_s,
            r.propagation_s,
            r.visible_s,
            r.total_s,
            r.total_min_s,
            r.total_max_s,
            r.triangles_removed,
            r.removed_triangles_pct,
            r.removed_area_pct,
            r.parts_removed,
            opt(r.truly_hidden),
            opt(r.false_removals),
            optf(r.missed_removals_pct),
            r.truth
        );
    }
    for s in skipped {
        md += &format!("\nSkipped: {s}\n");
    }
    md
}

fn plots(rows: &[Row], out: &Path) -> Result<()> {
    let mut names: Vec<&str> = rows.iter().map(|r| r.model.as_str()).collect();
    names.dedup();
    let series = |mode: &str, y: &dyn Fn(&Row) -> f64| -> Vec<Series> {
        names
            .iter()
            .map(|n| Series {
                name: n.to_string(),
                points: rows
                    .iter()
                    .filter(|r| r.model == *n && r.mode == mode)
                    .map(|r| (r.resolution as f64, y(r)))
                    .collect(),
            })
            .collect()
    };
    for mode in ["paper", "conservative"] {
        write_svg(
            &LineChart {
                title: format!("Triangles removed, {mode} mode (Min 2008)"),
                x_label: "grid resolution",
                y_label: "% of triangles removed",
                series: series(mode, &|r| r.removed_triangles_pct),
                reference: Vec::new(),
            },
            &out.join(format!("removal-{mode}.svg")),
        )?;
    }
    write_svg(
        &LineChart {
            title: "Culling time, conservative mode (distance field + propagation + visible set)"
                .into(),
            x_label: "grid resolution",
            y_label: "seconds (median)",
            series: series("conservative", &|r| r.total_s),
            reference: Vec::new(),
        },
        &out.join("time.svg"),
    )
}
