//! Traversal counts measured by the kernels themselves: per ray, the nodes
//! visited, the triangle records tested and the bytes fetched from nodes,
//! index lists and triangle records. The counting kernels are the batch
//! kernels compiled with `shaders/count_on.wgsl` (each structure notes what
//! it fetches; the timed kernels compile the notes to nothing), so the
//! counts are those of the exact traversal that is timed. They do not
//! depend on the device: counted on lavapipe, they hold on any GPU.

use crate::buffers::{output, read_words};
use crate::context::GpuContext;
use crate::error::GpuResult;
use crate::kernel::{dispatch, wgsl, BindingKind, Kernel, SCENE_GROUP};
use crate::scene::GpuScene;
use crate::trace::{GpuTracer, TRACE_GROUP};
use raykit_core::Ray;

/// Totals over a batch of rays.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TraversalCounts {
    /// Rays traced.
    pub rays: u64,
    /// Nodes visited (fetched).
    pub nodes: u64,
    /// Triangle records tested.
    pub tris: u64,
    /// Bytes fetched: nodes, index-list entries and triangle records (the
    /// hit's triangle id and the ray itself not included).
    pub bytes: u64,
}

impl TraversalCounts {
    /// Nodes visited per ray.
    pub fn nodes_per_ray(&self) -> f64 {
        self.nodes as f64 / self.rays.max(1) as f64
    }

    /// Triangle records tested per ray.
    pub fn tris_per_ray(&self) -> f64 {
        self.tris as f64 / self.rays.max(1) as f64
    }

    /// Bytes fetched per ray.
    pub fn bytes_per_ray(&self) -> f64 {
        self.bytes as f64 / self.rays.max(1) as f64
    }
}

/// Count the traversal of `rays` (nearest hits, or occlusion when `any`)
/// over `scene`.
pub fn count_traversal(
    ctx: &GpuContext,
    scene: &GpuScene,
    rays: &[Ray],
    any: bool,
) -> GpuResult<TraversalCounts> {
    let mut src = scene.wgsl_counting();
    src.push(wgsl::TRACE);
    let groups: [&[BindingKind]; 3] = [&SCENE_GROUP, &TRACE_GROUP, &[BindingKind::StorageRw]];
    let entry = if any { "trace_any" } else { "trace_nearest" };
    let label = format!(
        "{} {} {entry} counting",
        scene.kind.name(),
        scene.test.name()
    );
    let kernel = Kernel::new(ctx, &label, &src, entry, &groups)?;
    let tracer = GpuTracer::new(ctx, scene)?;
    let mut total = TraversalCounts::default();
    for chunk in rays.chunks(crate::trace::CHUNK) {
        let up = tracer.upload(chunk)?;
        let counters = output(ctx, "traversal counters", 6)?;
        let g0 = scene.bind(ctx, &kernel);
        let g1 = kernel.bind(ctx, 1, &[&up.rays, &up.out, &up.params]);
        let g2 = kernel.bind(ctx, 2, &[&counters]);
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("count"),
            });
        dispatch(&mut enc, &kernel, &[&g0, &g1, &g2], up.groups);
        ctx.queue.submit([enc.finish()]);
        ctx.wait()?;
        ctx.take_error()?;
        up.check(ctx)?;
        let w = read_words(ctx, &counters, 6)?;
        let wide = |i: usize| w[i] as u64 | (w[i + 1] as u64) << 32;
        total.rays += chunk.len() as u64;
        total.nodes += wide(0);
        total.tris += wide(2);
        total.bytes += wide(4);
    }
    Ok(total)
}
