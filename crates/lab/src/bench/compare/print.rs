//! The tables of `raykit bench --compare`: per mesh its builds, Mrays/s
//! and agreement, then a summary of our best ratio per cell across meshes.

use super::report::{trace_quality, Cell, Comparison};
use raykit_embree::Quality;
use serde::Serialize;

/// Our best ratio for one cell on one mesh.
#[derive(Serialize)]
pub(crate) struct Best {
    mesh: String,
    /// Against Embree 4 (its fastest API) and Embree 3.
    ratio4: Option<f64>,
    ratio3: Option<f64>,
    structure: String,
}

/// One row of the summary: a cell across the meshes.
#[derive(Serialize)]
pub(crate) struct SummaryRow {
    what: String,
    threads: usize,
    best: Vec<Best>,
}

/// The ratio a cell is ranked by: against Embree 4 where it was measured,
/// else against Embree 3.
fn key(c: &Cell) -> f64 {
    c.ratio4.or(c.ratio3).unwrap_or(0.0)
}

/// Per cell (builds against Embree MEDIUM, every Mrays/s cell) and mesh,
/// our best ratio and the structure that reached it.
pub(crate) fn summarise(reports: &[Comparison]) -> Vec<SummaryRow> {
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
            let entry = Best {
                mesh: r.mesh.clone(),
                ratio4: c.ratio4,
                ratio3: c.ratio3,
                structure: c.structure.clone(),
            };
            match best.iter_mut().find(|b| b.mesh == r.mesh) {
                Some(b) if b.ratio4.or(b.ratio3).unwrap_or(0.0) >= key(c) => {}
                Some(b) => *b = entry,
                None => best.push(entry),
            }
        }
    }
    rows
}

/// `1.23×` or `-` where the version was not compared; `*` marks a ratio
/// below 1.
fn ratio(r: Option<f64>) -> String {
    match r {
        Some(r) => format!("{r:.2}×{}", if r < 1.0 { "*" } else { "" }),
        None => "-".to_string(),
    }
}

pub(crate) fn print_summary(rows: &[SummaryRow]) {
    let Some(first) = rows.first() else {
        return;
    };
    println!(
        "
summary: our best ratio per cell, against Embree 4 / Embree 3 (build: Embree MEDIUM ÷ ours; rays: ours ÷ Embree; Embree 4 at its fastest API); * below 1.0×"
    );
    let short = |m: &str| m.rsplit('/').next().unwrap_or(m).to_string();
    let widths: Vec<usize> = first
        .best
        .iter()
        .map(|b| short(&b.mesh).chars().count().max(22))
        .collect();
    print!("{:<48} {:>7}", "cell", "threads");
    for (b, w) in first.best.iter().zip(&widths) {
        print!("  {:>w$}", short(&b.mesh));
    }
    println!();
    for r in rows {
        print!("{:<48} {:>7}", r.what, r.threads);
        for (b, w) in r.best.iter().zip(&widths) {
            let s = b.structure.split(' ').next().unwrap_or("");
            let cell = format!("{s} {} / {}", ratio(b.ratio4), ratio(b.ratio3));
            print!("  {cell:>w$}");
        }
        println!();
    }
}

pub(crate) fn print_report(r: &Comparison, reps: usize) {
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
    let versions = [
        r.embree4.as_ref().map(|v| format!("Embree {v}")),
        r.embree3.then(|| "Embree 3".to_string()),
    ];
    let versions: Vec<String> = versions.into_iter().flatten().collect();
    println!(
        "{}: {} triangles; ours = {} traced as built with --bvh-build {}; against {} ({} build); Embree 4 at its fastest API per cell (named), Embree 3 through rtcIntersect1/rtcOccluded1 unless noted; median of {reps} runs, the engines timed in turn (traces after one untimed round)",
        r.mesh,
        r.triangles,
        ours.join(", "),
        r.traced_build,
        versions.join(" and "),
        match trace_quality() {
            Quality::High => "HIGH",
            Quality::Medium => "MEDIUM",
        },
    );
    let several = r.ours.len() > 1;
    print_cells("build (ms)", "E÷ours", 1, &r.builds_ms, several);
    print_cells("Mrays/s", "ours÷E", 2, &r.mrays, several);
    println!("\nanswers against Embree (every ray):");
    for a in &r.agreement {
        let v = &a.verdict;
        println!(
            "  {:<18} {} rays: {} hit/miss and {} distance differences, of which {} graze an edge (f64) or hit the same triangle; {} same-distance ties [{} vs {}]{}",
            a.set,
            v.checked,
            v.hit_miss,
            v.distance,
            v.edge_grazes,
            v.ties,
            a.structure,
            a.engine,
            if v.ok() { "" } else { "  <-- DISAGREE" }
        );
    }
}

/// One table of cells, values with `digits` decimals; with `several`
/// structures each row names its own. Columns: ours, Embree 4 (and the
/// API that gave its figure), Embree 3, our ratio to each, spread.
fn print_cells(title: &str, ratio_name: &str, digits: usize, cells: &[Cell], several: bool) {
    println!(
        "\n{title:<48} {:>7} {:>10} {:>10} {:>15} {:>10} {:>9} {:>9} {:>7}",
        "threads",
        "ours",
        "Embree 4",
        "E4 API",
        "Embree 3",
        format!("{ratio_name}4"),
        format!("{ratio_name}3"),
        "spread"
    );
    let fig = |x: Option<f64>| match x {
        Some(x) => format!("{x:.digits$}"),
        None => "-".to_string(),
    };
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
            "{:<48} {:>7} {:>10.digits$} {:>10} {:>15} {:>10} {:>9} {:>9} {:>6.0}%",
            what,
            c.threads,
            c.ours,
            fig(c.embree4),
            c.embree4_api.as_deref().unwrap_or("-"),
            fig(c.embree3),
            ratio(c.ratio4),
            ratio(c.ratio3),
            100.0 * c.spread
        );
    }
}
