//! raykit's GPU backend on wgpu: WGSL compute kernels that trace
//! the same structures, with the same triangle records and arithmetic, as
//! the CPU engine, so that both give the same answers.
//!
//! - [`GpuContext`]: adapter and device (any Vulkan, Metal or DX12 GPU; in
//!   CI Mesa's lavapipe).
//! - [`GpuScene`]: a structure uploaded: the stack kd-tree GPU tracer's kd-tree with 8-byte
//!   nodes traversed with a fixed-size per-thread stack
//!   (`shaders/kd_stack.wgsl`), the threaded BVH (Smits 1998) with escape indices
//!   (`shaders/bvh_threaded.wgsl`), the compressed wide BVH (Ylitie, Karras
//!   and Laine 2017; [`cwbvh`], `shaders/cwbvh.wgsl`), or brute force;
//!   triangles precomputed for
//!   the stack kd-tree GPU tracer's Plücker test or Möller–Trumbore (1997).
//! - [`GpuTracer`]: batch nearest-hit and occlusion queries.
//! - [`GpuTerrain`]: height-field ray casting by per-ray maximum-mipmap
//!   traversal (Tevs et al. 2008) on the declared
//!   two-triangles-per-cell surface of `raykit-terrain`.
//! - [`render_whitted_gpu`]: the Whitted renderer, as the stack kd-tree GPU tracer's single
//!   kernel or a stream of kernels (after Purcell et al. 2002) over ray queues.
//!
//! Every kernel is WGSL assembled from small pieces (`shaders/`): the
//! common records, the scene bindings, one triangle test, one structure, one
//! entry file.

mod buffers;
mod context;
mod counts;
pub mod cwbvh;
mod error;
pub mod kernel;
pub mod render;
mod scene;
pub mod terrain;
mod trace;

pub use buffers::{check_binding, output, read_words, storage, uniform};
pub use context::GpuContext;
pub use counts::{count_traversal, TraversalCounts};
pub use error::{GpuError, GpuResult};
pub use render::{check_options, render_whitted_gpu, GpuFrame, ShadeScene, MAX_GPU_DEPTH};
pub use scene::{gpu_test_supported, GpuAccelKind, GpuScene};
pub use terrain::{time_terrain_boxes, time_terrain_casts, GpuCaster, GpuTerrain, TerrainTiming};
pub use trace::{Clock, GpuRays, GpuTracer, CHUNK};
