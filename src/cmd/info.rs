//! `raykit info`: the names the other commands accept.

use anyhow::Result;
use clap::{Args, ValueEnum};
use raykit_core::accel::AccelKind;
use raykit_core::tri::TestKind;
use std::process::ExitCode;

/// What to list.
#[derive(Clone, Copy, ValueEnum)]
pub enum Topic {
    /// Acceleration structures (--accel).
    Accels,
    /// Ray/triangle tests (--test).
    Tests,
    /// Built-in scenes (--scene builtin:NAME, --mesh builtin:NAME).
    Scenes,
}

/// Arguments of `raykit info`.
#[derive(Args)]
pub struct InfoArgs {
    /// What to list.
    topic: Topic,
}

/// Print the list.
pub fn run(args: InfoArgs) -> Result<ExitCode> {
    match args.topic {
        Topic::Accels => {
            for k in AccelKind::ALL {
                println!("{:<14} {}", k.name(), accel_description(k));
            }
            let gpu = raykit_gpu::GpuAccelKind::ALL.map(|k| k.name()).join(", ");
            let cwbvh = "compressed 8-wide BVH (Ylitie et al. 2017), GPU only";
            println!("{:<14} {cwbvh}", "cwbvh");
            println!("{:<14} --backend gpu takes {gpu}", "");
        }
        Topic::Tests => {
            for k in TestKind::ALL {
                println!("{:<14} {}", k.name(), test_description(k));
            }
            println!(
                "\nAll three are watertight on shared edges and corners by a conservative \
                 tolerance: a ray passing just outside a triangle, within a band of at most \
                 1/256 of its edges (barycentric), may hit it too, so a crack narrower than \
                 the band does not let rays through."
            );
        }
        Topic::Scenes => {
            for info in raykit_scene::BUILTINS {
                println!(
                    "builtin:{:<10} {} (keys: {})",
                    info.name,
                    info.description,
                    info.keys.join(", ")
                );
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// One line on a structure, for `raykit info accels`.
fn accel_description(kind: AccelKind) -> &'static str {
    match kind {
        AccelKind::Brute => {
            "every ray against every triangle; the reference (slow: O(rays x triangles))"
        }
        AccelKind::Bvh2 => {
            "binary BVH, parallel binned-SAH build, stack traversal nearest child first"
        }
        AccelKind::Bvh4 => {
            "4-wide BVH, binned-SAH build making wide nodes directly, SSE box tests, ordered stack traversal"
        }
        AccelKind::Bvh8 => {
            "8-wide BVH, binned-SAH build making wide nodes directly, AVX box tests (SSE/scalar fallback), ordered stack traversal"
        }
        AccelKind::ThreadedBvh => {
            "BVH nodes in pre-order with escape indices, stackless traversal (Smits 1998)"
        }
        AccelKind::KdStack => "kd-tree (--kd-split), 8-byte nodes, per-ray stack traversal",
        AccelKind::KdRopes => "kd-tree with ropes and leaf boxes, stackless (Popov et al. 2007)",
        AccelKind::KdRestart => {
            "kd-tree, kd-restart: stackless, descends from the root per leaf (Foley & Sugerman 2005)"
        }
        AccelKind::KdBacktrack => {
            "kd-tree, kd-backtrack: stackless, climbs parent links (Foley & Sugerman 2005)"
        }
    }
}

/// One line on a triangle test, for `raykit info tests`.
fn test_description(kind: TestKind) -> &'static str {
    match kind {
        TestKind::Moller => {
            "Möller–Trumbore 1997: edge vectors, determinant and barycentrics per ray"
        }
        TestKind::Plucker => {
            "Plücker coordinates (Jones 2000): sign test on precomputed edge lines, then distance"
        }
        TestKind::Projection => {
            "Wald's projection test (2004): precomputed projection onto the dominant axis plane"
        }
    }
}
