//! `raykit trace`: trace a ray file and write hits or occlusion bytes.

mod args;
mod brute_check;
mod gpu;
mod instanced;

pub use args::TraceArgs;
use brute_check::check_against_brute;
use gpu::run_gpu;
use instanced::run_instanced;

use anyhow::{anyhow, bail, Result};
use raykit_core::accel::{build_accel, AccelKind};
use raykit_core::tri::TestKind;
use raykit_lab::args::backend::Backend;
use raykit_lab::args::build_args::BuildArgs;
use raykit_lab::args::scene_arg;
use raykit_lab::measure::{per_second, pool, timed};
use serde_json::json;
use std::process::ExitCode;

/// Parse `--accel` and `--test`.
pub fn parse_names(accel: &str, test: &str) -> Result<(AccelKind, TestKind)> {
    let a = AccelKind::from_name(accel).ok_or_else(|| {
        if accel == "cwbvh" {
            return anyhow!(
                "--accel cwbvh is a GPU structure: give --backend gpu, or a CPU structure ({})",
                AccelKind::ALL.map(|k| k.name()).join(", ")
            );
        }
        let names: Vec<_> = AccelKind::ALL.iter().map(|k| k.name()).collect();
        anyhow!(
            "unknown --accel '{accel}'; expected one of: {}",
            names.join(", ")
        )
    })?;
    let t = TestKind::from_name(test).ok_or_else(|| {
        let names: Vec<_> = TestKind::ALL.iter().map(|k| k.name()).collect();
        anyhow!(
            "unknown --test '{test}'; expected one of: {}",
            names.join(", ")
        )
    })?;
    Ok((a, t))
}

/// Say on stderr that `--kd-split` goes unused: the structure `accel`
/// traced is no kd-tree.
fn warn_unused_kd_split(build: &BuildArgs, accel: &str) {
    if let Some(split) = build.kd_split_given() {
        eprintln!(
            "raykit: warning: --kd-split {} is ignored: --accel {accel} is not a kd-tree",
            split.name()
        );
    }
}

/// Trace the file.
pub fn run(args: TraceArgs) -> Result<ExitCode> {
    if args.instanced || args.mesh.len() > 1 {
        return run_instanced(args);
    }
    if args.backend == Backend::Gpu {
        if args.one_ray {
            bail!("--one-ray traces on the CPU; drop it or --backend gpu");
        }
        return run_gpu(args);
    }
    let (kind, test) = parse_names(
        args.accel
            .as_deref()
            .unwrap_or(raykit_lab::args::build_args::DEFAULT_ACCEL),
        &args.test,
    )?;
    crate::paths::ensure_output(
        &args.out,
        &[&args.rays, std::path::Path::new(&args.mesh[0])],
    )?;
    let pool = pool(args.threads)?;
    let threads = pool.current_num_threads();
    let (scene, load_s) = timed(|| scene_arg::load(&args.mesh[0]));
    let mesh = scene?.mesh;
    let rays = raykit_io::read_rays(&args.rays)?;
    let opts = args.build.options();
    let is_kd = AccelKind::KD.contains(&kind);
    if !is_kd {
        warn_unused_kd_split(&args.build, kind.name());
    }
    let (accel, build_s) = pool.install(|| timed(|| build_accel(kind, test, &mesh, &opts)));
    let (hits, occluded);
    let trace_s;
    if args.occlusion {
        let mut out = vec![false; rays.len()];
        trace_s = pool.install(|| {
            timed(|| {
                if args.one_ray {
                    raykit_lab::one_ray::occluded_each(accel.as_ref(), &rays, &mut out)
                } else {
                    accel.occluded_batch(&rays, &mut out)
                }
            })
            .1
        });
        raykit_io::write_occlusion(&args.out, &out)?;
        occluded = Some(out);
        hits = None;
    } else {
        let mut out = vec![None; rays.len()];
        trace_s = pool.install(|| {
            timed(|| {
                if args.one_ray {
                    raykit_lab::one_ray::intersect_each(accel.as_ref(), &rays, &mut out)
                } else {
                    accel.intersect_batch(&rays, &mut out)
                }
            })
            .1
        });
        raykit_io::write_hits(&args.out, &out)?;
        hits = Some(out);
        occluded = None;
    }
    let mut stats = json!({
        "accel": kind.name(),
        "bvh_build": opts.quality.name(),
        "test": test.name(),
        "api": if args.one_ray { "one-ray" } else { "batch" },
        "load_ms": load_s * 1e3,
        "build_ms": build_s * 1e3,
        "trace_ms": trace_s * 1e3,
        "rays": rays.len(),
        "mrays": per_second(rays.len(), trace_s) / 1e6,
        "per_s": per_second(rays.len(), trace_s),
        "threads": threads,
    });
    if is_kd {
        stats["kd_split"] = json!(opts.kd.split.name());
    }
    eprintln!("{stats}");
    let Some(k) = args.verify else {
        return Ok(ExitCode::SUCCESS);
    };
    check_against_brute(
        false,
        &mesh,
        &rays,
        test,
        &opts,
        k,
        &pool,
        hits.as_deref(),
        occluded.as_deref(),
    )
}
