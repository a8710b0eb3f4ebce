//! The stack kd-tree GPU tracer's single kernel: one thread per pixel sample follows its whole
//! path — camera ray, shadow rays, reflection and refraction rays — with a
//! fixed-size per-thread stack (`shaders/render/megakernel.wgsl`).

use super::upload::ShadeBuffers;
use super::{counted, kernel, positions, RunReport, StageParams};
use crate::buffers::{output, read_words, storage, uniform};
use crate::context::GpuContext;
use crate::error::GpuResult;
use crate::kernel::{dispatch, grid, wgsl, BindingKind};
use crate::scene::GpuScene;
use raykit_render::whitted::WhittedOptions;

const STAGE_GROUP: [BindingKind; 3] = [
    BindingKind::Storage,
    BindingKind::Uniform,
    BindingKind::StorageRw,
];

/// Render every camera sample of the frame into `shade.radiance`, one
/// dispatch per sample (the counters hold the secondary rays).
pub(super) fn run(
    ctx: &GpuContext,
    gpu: &GpuScene,
    shade: &ShadeBuffers,
    opts: &WhittedOptions,
    progress: &dyn Fn(u64, u64),
) -> GpuResult<RunReport> {
    let compile = std::time::Instant::now();
    let k = kernel(ctx, gpu, wgsl::MEGAKERNEL, "render_pixel", &STAGE_GROUP)?;
    let compile_seconds = compile.elapsed().as_secs_f64();
    let n = opts.width as usize * opts.height as usize;
    let (x, y, row) = grid(ctx, n)?;
    let params = uniform(
        ctx,
        "megakernel parameters",
        &StageParams {
            count: n as u32,
            row,
            capacity: 0,
            record_first: 1,
        },
    );
    let first = output(ctx, "first hits", 4 * n)?;
    let g0 = gpu.bind(ctx, &k);
    let g1 = k.bind(ctx, 1, &shade.all());
    for sample in 0..opts.samples_per_pixel.max(1) {
        let pos = storage(ctx, "sample positions", &positions(opts, sample))?;
        if sample == 1 {
            // Only the first sample's hits are kept.
            ctx.queue.write_buffer(&params, 12, &[0; 4]);
        }
        let g2 = k.bind(ctx, 2, &[&pos, &params, &first]);
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("megakernel"),
            });
        dispatch(&mut enc, &k, &[&g0, &g1, &g2], (x, y));
        ctx.queue.submit([enc.finish()]);
        ctx.wait()?;
        ctx.take_error()?;
        progress(
            n as u64,
            (sample as u64 + 1) * n as u64 + counted(ctx, shade)?,
        );
    }
    Ok(RunReport {
        secondary: None,
        compile_seconds,
        first_hits: read_words(ctx, &first, 4 * n)?,
    })
}
