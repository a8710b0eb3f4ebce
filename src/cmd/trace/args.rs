//! The arguments of `raykit trace`.

use clap::Args;
use raykit_lab::args::backend::Backend;
use std::path::PathBuf;

/// Arguments of `raykit trace`.
#[derive(Args)]
#[command(after_help = "Prints one JSON line of statistics on stderr:\n\
{\"accel\", \"bvh_build\", \"test\", \"api\", \"load_ms\", \"build_ms\", \"trace_ms\", \"rays\", \"mrays\", \"per_s\" (rays per second), \"threads\"}\n\
(trace_ms excludes loading and building; api, on the CPU without instances: batch, or one-ray with --one-ray).\n\
A kd-tree adds \"kd_split\", its --kd-split rule (sah, median or game:H). Hit file: per ray f32 t, u32 prim\n\
(8 bytes; a miss is t = +inf, prim = 4294967295). Occlusion file: one byte per ray (1 = occluded).\n\n\
Several --mesh (or --instanced): an instanced scene under a two-level BVH, each file a geometry\n\
placed once, a glTF file one geometry per mesh and one instance per node. Its hit file: per ray\n\
f32 t, u32 prim, u32 geometry, u32 instance (16 bytes; a miss is t = +inf and all ids 4294967295;\n\
prim indexes the geometry's mesh). The JSON line adds \"geometries\", \"instances\",\n\
\"stored_triangles\", \"instanced_triangles\", \"scene_bytes\" and per --mesh its ids as [first, count]\n\
(\"inputs\").")]
pub struct TraceArgs {
    /// Mesh file or builtin:NAME; give several (--mesh A --mesh B) for an
    /// instanced scene whose hits name geometry and instance.
    #[arg(long, required = true)]
    pub(super) mesh: Vec<String>,
    /// Trace as an instanced scene even with one --mesh (a glTF file keeps
    /// its instancing: one geometry per mesh, one instance per node); the
    /// hit file then has the geometry and instance ids.
    #[arg(long)]
    pub(super) instanced: bool,
    /// Ray file (from `raykit rays` or another engine).
    #[arg(long)]
    pub(super) rays: PathBuf,
    /// Output hit file (or occlusion file with --occlusion).
    #[arg(long)]
    pub(super) out: PathBuf,
    /// Acceleration structure (`raykit info accels`; default bvh8, the
    /// fastest, or kd-stack with --backend gpu, which also takes kd-ropes,
    /// bvh-threaded, cwbvh and brute). The JSON line names the one used.
    #[arg(long)]
    pub(super) accel: Option<String>,
    /// Ray/triangle test (`raykit info tests`).
    #[arg(long, default_value = "moller")]
    pub(super) test: String,
    /// Answer "is anything hit" (shadow rays) instead of the nearest hit.
    #[arg(long)]
    pub(super) occlusion: bool,
    /// Worker threads (0 = one per core; at most 4096).
    #[arg(long, default_value_t = 0)]
    pub(super) threads: usize,
    /// Trace each ray through the one-ray API (`Accel::intersect` /
    /// `Accel::occluded`, one call per ray, as a library user looping over
    /// rays does) instead of the batch path with its ray packets; the
    /// answers are the same. CPU only.
    #[arg(long)]
    pub(super) one_ray: bool,
    /// Also trace this many rays (spread over the file) with brute force and
    /// the same triangle test, report disagreements and fail if any.
    #[arg(long, value_name = "N")]
    pub(super) verify: Option<usize>,
    /// Trace on the CPU (all cores) or on the GPU (wgpu compute kernels;
    /// the JSON line then names the adapter and adds the kernel time).
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    pub(super) backend: Backend,
    #[command(flatten)]
    pub(super) build: raykit_lab::args::build_args::BuildArgs,
}
