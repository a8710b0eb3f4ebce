//! `raykit trace --verify N`: a sample of the traced rays rechecked by
//! brute force with the same triangle test.

use anyhow::Result;
use raykit_core::accel::{build_accel, AccelKind};
use raykit_core::tri::TestKind;
use raykit_core::verify;
use raykit_core::Ray;
use serde_json::json;
use std::process::ExitCode;

/// `--verify N`: recheck N rays spread over the file with brute force and
/// the same triangle test; fail on any disagreement. On the GPU
/// (`gpu_rounding`), whose division and fused multiply-adds may round
/// differently from the CPU, disagreements where the ray grazes a triangle
/// edge (f64, see [`verify::edge_grazes`]) are counted apart and allowed;
/// for occlusion only the blockers brute force finds can be checked, so a
/// GPU that catches an edge brute force misses still fails.
#[allow(clippy::too_many_arguments)]
pub fn check_against_brute(
    gpu_rounding: bool,
    mesh: &raykit_core::TriangleMesh,
    rays: &[Ray],
    test: TestKind,
    opts: &raykit_core::accel::BuildOptions,
    k: usize,
    pool: &rayon::ThreadPool,
    hits: Option<&[Option<raykit_core::Hit>]>,
    occluded: Option<&[bool]>,
) -> Result<ExitCode> {
    let idx = verify::sample(rays.len(), k);
    let sample: Vec<Ray> = idx.iter().map(|&i| rays[i]).collect();
    let brute = build_accel(AccelKind::Brute, test, mesh, opts);
    let verdict = pool.install(|| {
        if let Some(h) = hits {
            let mut want = vec![None; sample.len()];
            brute.intersect_batch(&sample, &mut want);
            let got: Vec<_> = idx.iter().map(|&i| h[i]).collect();
            let mut v = verify::compare_hits(&want, &got);
            if gpu_rounding {
                v.edge_grazes = verify::edge_grazes(mesh, &sample, &want, &got);
            }
            v
        } else {
            let o = occluded.expect("one of the two is set");
            let mut want = vec![false; sample.len()];
            brute.occluded_batch(&sample, &mut want);
            let got: Vec<_> = idx.iter().map(|&i| o[i]).collect();
            let mut v = verify::compare_occlusion(&want, &got);
            if gpu_rounding {
                (v.edge_grazes, _) = verify::occlusion_grazes(mesh, &sample, &want, &got, |r| {
                    let mut near = vec![None; r.len()];
                    brute.intersect_batch(r, &mut near);
                    (near.clone(), near)
                });
            }
            v
        }
    });
    eprintln!(
        "{}",
        json!({ "verify": "brute", "test": test.name(), "result": verdict, "ok": verdict.ok() })
    );
    Ok(if verdict.ok() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
