//! `raykit cull --save-truth` and `--truth`: the ground truth's labels in a
//! JSON file ([`raykit_cull::SavedTruth`]).

use super::args::CullArgs;
use anyhow::{Context, Result};
use raykit_core::TriangleMesh;
use raykit_cull::{GroundTruth, SavedTruth, SavedTruthMismatch};
use std::path::Path;

/// Write the labels of `truth` to `path`, among the run's `outputs`.
pub fn save_truth(
    outputs: &mut raykit_io::OutputSet,
    path: &Path,
    args: &CullArgs,
    mesh: &TriangleMesh,
    truth: &GroundTruth,
) -> Result<()> {
    let saved = SavedTruth::new(
        &args.input.display().to_string(),
        mesh,
        truth,
        args.eval_min_opening,
    );
    let json = serde_json::to_string(&saved)?;
    outputs
        .write(path, |w| {
            w.write_all(json.as_bytes())?;
            w.write_all(b"\n")
        })
        .with_context(|| format!("cannot write {}", path.display()))
}

/// Labels saved by --save-truth, checked against the input's triangles.
pub fn load_truth(path: &Path, input: &Path, mesh: &TriangleMesh) -> Result<GroundTruth> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let saved: SavedTruth = serde_json::from_str(&text).with_context(|| {
        format!(
            "{}: not a ground truth saved by --save-truth",
            path.display()
        )
    })?;
    saved.to_truth(mesh).map_err(|e| match e {
        SavedTruthMismatch::Mesh { saved, mesh } => anyhow::anyhow!(
            "{}: field mesh_digest is {saved}, but the triangles of {} give {mesh}: the labels \
             were saved for another mesh (or this one was changed since)",
            path.display(),
            input.display()
        ),
        SavedTruthMismatch::Triangles { saved, mesh } => anyhow::anyhow!(
            "{}: field triangles is {saved}, but {} has {mesh} triangles",
            path.display(),
            input.display()
        ),
        SavedTruthMismatch::IdBeyond { index, id, mesh } => anyhow::anyhow!(
            "{}: visible_ids[{index}] is {id}, beyond the {mesh} triangles",
            path.display()
        ),
    })
}
