//! `raykit bench --backend gpu`: build, upload, memory and Mrays/s of the
//! GPU kernels (the kd-tree with a per-ray stack, the threaded BVH (Smits 1998)) × the
//! Plücker and Möller tests, every answer checked against the CPU twin.

use crate::args::backend::{gpu_accel, open_gpu};
use crate::args::scene_arg;
use crate::gpu_measure::{measure, GpuRow, Workload};
use crate::measure::pool;
use anyhow::{anyhow, Result};
use indicatif::{ProgressBar, ProgressStyle};
use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::raysets;
use raykit_core::tri::TestKind;
use raykit_gpu::{gpu_test_supported, GpuAccelKind};
use serde::Serialize;
use std::process::ExitCode;

/// What `bench --backend gpu` needs from the command line.
pub struct GpuBenchSetup<'a> {
    /// `--mesh`.
    pub mesh: &'a str,
    /// `--accel` (`all` = kd-stack, kd-ropes, bvh-threaded and cwbvh).
    pub accel: &'a str,
    /// `--test` (`all` = plucker and moller).
    pub test: &'a str,
    /// `--size`.
    pub size: u32,
    /// `--reps`.
    pub reps: usize,
    /// `--json`.
    pub json: bool,
    /// Build options.
    pub options: BuildOptions,
}

#[derive(Serialize)]
struct GpuReport {
    mesh: String,
    triangles: usize,
    adapter: String,
    reps: usize,
    rows: Vec<GpuRow>,
}

/// The structures and tests named, GPU-capable ones only.
pub fn gpu_lists(accel: &str, test: &str) -> Result<(Vec<GpuAccelKind>, Vec<TestKind>)> {
    let accels = if accel == "all" {
        vec![
            GpuAccelKind::KdStack,
            GpuAccelKind::KdRopes,
            GpuAccelKind::BvhThreaded,
            GpuAccelKind::Cwbvh,
        ]
    } else {
        accel
            .split(',')
            .map(|n| gpu_accel(n.trim()))
            .collect::<Result<_>>()?
    };
    let tests = if test == "all" {
        vec![TestKind::Plucker, TestKind::Moller]
    } else {
        test.split(',')
            .map(|n| {
                TestKind::from_name(n.trim())
                    .filter(|t| gpu_test_supported(*t))
                    .ok_or_else(|| anyhow!("--test '{n}' has no GPU kernel; with --backend gpu use plucker or moller"))
            })
            .collect::<Result<_>>()?
    };
    Ok((accels, tests))
}

/// Run the GPU benchmark.
pub fn run(s: GpuBenchSetup) -> Result<ExitCode> {
    let (accels, tests) = gpu_lists(s.accel, s.test)?;
    let ctx = open_gpu()?;
    let mesh = scene_arg::load(s.mesh)?.mesh;
    eprintln!(
        "{}: {} triangles; generating ray sets ({}²)…",
        s.mesh,
        mesh.num_triangles(),
        s.size
    );
    let sets = pool(0)?.install(|| {
        let helper = build_accel(AccelKind::Bvh2, TestKind::Moller, &mesh, &s.options);
        raysets::standard_sets(&mesh, helper.as_ref(), s.size, 1)
    });
    let bar = ProgressBar::new((accels.len() * tests.len() * 4) as u64).with_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} {msg} [{elapsed}<{eta}]")
            .expect("valid template"),
    );
    let mut rows = Vec::new();
    let work = Workload {
        mesh: &mesh,
        opts: &s.options,
        sets: &sets,
        reps: s.reps,
    };
    for &test in &tests {
        for &kind in &accels {
            let row = measure(&ctx, &work, kind, test, |m| {
                bar.set_message(m.to_string());
                bar.inc(1);
            })?;
            rows.push(row);
        }
    }
    bar.finish_and_clear();
    let report = GpuReport {
        mesh: s.mesh.to_string(),
        triangles: mesh.num_triangles(),
        adapter: ctx.describe(),
        reps: s.reps,
        rows,
    };
    if s.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_table(&report);
    }
    let ok = report
        .rows
        .iter()
        .all(|r| r.cells.iter().all(|c| c.verify.ok()));
    Ok(if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

fn print_table(r: &GpuReport) {
    println!(
        "{}: {} triangles on {}, median of {} runs",
        r.mesh, r.triangles, r.adapter, r.reps
    );
    println!(
        "{:<13} {:<8} {:>9} {:>9} {:>8} | {:>8} {:>8} {:>8} | {:>6} | agreement with the CPU twin",
        "accel", "test", "build ms", "upload ms", "MB", "primary", "shadow", "incoh.", "noise"
    );
    for row in &r.rows {
        let c = &row.cells;
        let noise = c.iter().map(|x| x.spread).fold(0.0, f64::max);
        let checked: usize = c.iter().map(|x| x.verify.checked).sum();
        let bad: usize = c.iter().map(|x| x.verify.disagreements()).sum();
        let ties: usize = c.iter().map(|x| x.verify.ties).sum();
        let grazes: usize = c.iter().map(|x| x.verify.edge_grazes).sum();
        println!(
            "{:<13} {:<8} {:>9.1} {:>9.1} {:>8.1} | {:>8.2} {:>8.2} {:>8.2} | {:>5.0}% | {checked} rays, {bad} differ ({grazes} edge grazes), {ties} ties",
            row.accel,
            row.test,
            row.build_ms,
            row.upload_ms,
            row.bytes as f64 / 1e6,
            c[0].mrays,
            c[1].mrays,
            c[2].mrays,
            noise * 100.0
        );
    }
    println!("Mrays/s of the kernel from submission to completion (uploads and read-back excluded); shadow = occlusion.");
}
