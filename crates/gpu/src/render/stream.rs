//! The Purcell-style stream tracer's stream organisation on the GPU: per camera sample, `raygen`
//! fills a ray queue; per bounce, `intersect`, `miss` (environment) and
//! `shade` run over the queue, and shading appends the next bounce's rays
//! to a second queue through an atomic counter (`shaders/render/stream.wgsl`).
//! The queues swap until one is empty. The next queue always has room for
//! two rays per shaded ray, so no ray is ever dropped.

use super::upload::ShadeBuffers;
use super::{counted, kernel, positions, RunReport, StageParams};
use crate::buffers::{output, read_words, storage, uniform};
use crate::context::GpuContext;
use crate::error::{GpuError, GpuResult};
use crate::kernel::{dispatch, grid, wgsl, BindingKind, Kernel};
use crate::scene::GpuScene;
use raykit_render::whitted::WhittedOptions;

const STAGE_GROUP: [BindingKind; 5] = [
    BindingKind::StorageRw,
    BindingKind::StorageRw,
    BindingKind::StorageRw,
    BindingKind::Storage,
    BindingKind::Uniform,
];

/// Words per queued ray (`QueuedRay`) and per hit.
const RAY_WORDS: usize = 12;
const HIT_WORDS: usize = 4;

/// A storage buffer that grows to hold at least a number of records.
struct Growing {
    what: &'static str,
    words_per: usize,
    capacity: usize,
    buffer: wgpu::Buffer,
}

impl Growing {
    fn new(
        ctx: &GpuContext,
        what: &'static str,
        words_per: usize,
        capacity: usize,
    ) -> GpuResult<Growing> {
        let capacity = capacity.max(1);
        Ok(Growing {
            what,
            words_per,
            capacity,
            buffer: output(ctx, what, capacity * words_per)?,
        })
    }

    fn reserve(&mut self, ctx: &GpuContext, records: usize) -> GpuResult<()> {
        if records > self.capacity {
            *self = Growing::new(ctx, self.what, self.words_per, records)?;
        }
        Ok(())
    }
}

struct Kernels {
    raygen: Kernel,
    intersect: Kernel,
    miss: Kernel,
    shade: Kernel,
}

/// Run the stream for every camera sample; reports the next-bounce rays
/// queued (the secondary rays) and the first sample's camera-ray hits.
pub(super) fn run(
    ctx: &GpuContext,
    gpu: &GpuScene,
    shade: &ShadeBuffers,
    opts: &WhittedOptions,
    progress: &dyn Fn(u64, u64),
) -> GpuResult<RunReport> {
    let compile = std::time::Instant::now();
    let kernels = Kernels {
        raygen: kernel(ctx, gpu, wgsl::STREAM, "raygen", &STAGE_GROUP)?,
        intersect: kernel(ctx, gpu, wgsl::STREAM, "intersect", &STAGE_GROUP)?,
        miss: kernel(ctx, gpu, wgsl::STREAM, "miss", &STAGE_GROUP)?,
        shade: kernel(ctx, gpu, wgsl::STREAM, "shade", &STAGE_GROUP)?,
    };
    let compile_seconds = compile.elapsed().as_secs_f64();
    let n = opts.width as usize * opts.height as usize;
    let mut first_hits = Vec::new();
    let mut current = Growing::new(ctx, "ray queue", RAY_WORDS, n)?;
    let mut next = Growing::new(ctx, "next ray queue", RAY_WORDS, 2 * n)?;
    let mut hits = Growing::new(ctx, "queue hits", HIT_WORDS, n)?;
    let params = uniform(
        ctx,
        "stream parameters",
        &StageParams {
            count: 0,
            row: 0,
            capacity: 0,
            record_first: 0,
        },
    );
    let mut secondary = 0u64;
    for sample in 0..opts.samples_per_pixel.max(1) {
        let pos = storage(ctx, "sample positions", &positions(opts, sample))?;
        let mut count = n;
        let mut first = true;
        while count > 0 {
            next.reserve(ctx, 2 * count)?;
            hits.reserve(ctx, count)?;
            let (x, y, row) = grid(ctx, count)?;
            let stage = StageParams {
                count: count as u32,
                row,
                capacity: next.capacity as u32,
                record_first: 0,
            };
            ctx.queue
                .write_buffer(&params, 0, bytemuck::bytes_of(&stage));
            ctx.queue.write_buffer(&shade.counters, 12, &[0; 4]);
            let buffers = [&current.buffer, &next.buffer, &hits.buffer, &pos, &params];
            let mut enc = ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("stream bounce"),
                });
            let stages: &[&Kernel] = if first {
                &[
                    &kernels.raygen,
                    &kernels.intersect,
                    &kernels.miss,
                    &kernels.shade,
                ]
            } else {
                &[&kernels.intersect, &kernels.miss, &kernels.shade]
            };
            for k in stages {
                let g0 = gpu.bind(ctx, k);
                let g1 = k.bind(ctx, 1, &shade.all());
                let g2 = k.bind(ctx, 2, &buffers);
                dispatch(&mut enc, k, &[&g0, &g1, &g2], (x, y));
            }
            ctx.queue.submit([enc.finish()]);
            let queued = super::read_counters(ctx, shade)?[3] as usize;
            if first && sample == 0 {
                // The camera rays sit at their pixels' slots.
                first_hits = read_words(ctx, &hits.buffer, 4 * n)?;
            }
            if queued > next.capacity {
                return Err(GpuError::Readback(format!(
                    "the next-bounce queue overflowed ({queued} rays for {} slots)",
                    next.capacity
                )));
            }
            secondary += queued as u64;
            std::mem::swap(&mut current, &mut next);
            count = queued;
            first = false;
        }
        let rays = (sample as u64 + 1) * n as u64 + secondary + counted(ctx, shade)?;
        progress(n as u64, rays);
    }
    Ok(RunReport {
        secondary: Some(secondary),
        compile_seconds,
        first_hits,
    })
}
