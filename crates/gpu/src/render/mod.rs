//! The GPU Whitted renderer behind `raykit render --backend gpu`: the CPU
//! renderer's image (crates/render/src/whitted) from WGSL kernels, in the
//! two organisations of the papers:
//!
//! - one kernel per ray path ([`megakernel`]): one thread per pixel
//!   sample traces the camera ray, the shadow rays and the reflection and
//!   refraction rays with a small per-thread stack;
//! - the Purcell-style stream tracer's stream ([`stream`]): ray generation, intersection,
//!   environment and shading kernels chained through ray queues.
//!
//! Both run the same WGSL shading (`shaders/render/`: surface, lights,
//! base-colour textures, Blinn-Phong, Fresnel, refraction, the sky, equirectangular maps and
//! the environment box) as the CPU's
//! `Tracer::scatter`, with camera samples placed by the CPU's
//! `sample_position`, and hand back linear radiance that the caller encodes
//! as the CPU renderer does.

mod env_upload;
mod megakernel;
mod records;
mod stream;
mod upload;

pub use upload::ShadeScene;

use crate::context::GpuContext;
use crate::error::{GpuError, GpuResult};
use crate::kernel::{wgsl, BindingKind, Kernel, SCENE_GROUP};
use crate::scene::GpuScene;
use raykit_core::glam::Vec3;
use raykit_core::{Camera, Hit};
use raykit_render::whitted::{
    sample_position, Frame, FrameStats, IntegratorKind, PrimaryMode, ShadowMode, WhittedOptions,
};
use raykit_render::Image;
use std::time::Instant;
use upload::{FrameSettings, ShadeBuffers, COUNTER_WORDS};

/// The longest path (`--depth`) one kernel per ray path follows: the size
/// of its per-thread stack of pending rays.
pub const MAX_GPU_DEPTH: u32 = 16;

/// Bind group 1 of every render kernel (`shade_data.wgsl`).
const SHADE_GROUP: [BindingKind; 7] = [
    BindingKind::Storage,
    BindingKind::Storage,
    BindingKind::Uniform,
    BindingKind::StorageRw,
    BindingKind::StorageRw,
    BindingKind::Storage,
    BindingKind::Storage,
];

/// Uniform `StageParams` of the render kernels: threads, threads per grid
/// row, next-queue capacity.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct StageParams {
    count: u32,
    row: u32,
    capacity: u32,
    record_first: u32,
}

/// What one organisation's run reports.
struct RunReport {
    /// Secondary rays, when the run counted them on the host.
    secondary: Option<u64>,
    /// Seconds spent compiling its kernels.
    compile_seconds: f64,
    /// The first camera sample's nearest hits (t, u, v, prim words).
    first_hits: Vec<u32>,
}

/// A frame rendered on the GPU by one kernel per ray path or the Purcell-style stream tracer's
/// stream.
pub struct GpuFrame {
    /// The image, first hits (for AOVs) and ray counts; `stats.seconds`
    /// excludes compiling the kernels.
    pub frame: Frame,
    /// Seconds spent compiling the WGSL kernels (once per process).
    pub compile_seconds: f64,
}

/// Refuse options the GPU renderer (Whitted (1980), on the GPU after Purcell et al. (2002) on wgpu) does not
/// implement, naming them (never a silently different image): the Purcell-style stream tracer's
/// shadow maps and rasterized primaries, and paths longer than the stack kd-tree GPU tracer's
/// single kernel's ray stack.
pub fn check_options(opts: &WhittedOptions) -> GpuResult<()> {
    if opts.shadows == ShadowMode::Maps {
        return Err(GpuError::Unsupported(
            "--shadows maps (shadow maps); use --shadows rays or off".into(),
        ));
    }
    if opts.primary == PrimaryMode::Rasterized {
        return Err(GpuError::Unsupported(
            "--primary raster (rasterized first hits); use --primary traced".into(),
        ));
    }
    if opts.integrator == IntegratorKind::Recursive && opts.max_depth > MAX_GPU_DEPTH {
        return Err(GpuError::Unsupported(format!(
            "--depth {} with --integrator recursive (the single kernel's ray stack holds {MAX_GPU_DEPTH}); \
             use --integrator wavefront or a smaller --depth",
            opts.max_depth
        )));
    }
    Ok(())
}

/// The WGSL of a render kernel: the scene's structure, the shared shading
/// pieces, then `entry_file`.
fn sources(scene: &GpuScene, entry_file: &'static str) -> Vec<&'static str> {
    let mut src = scene.wgsl();
    src.extend([
        wgsl::SHADE_DATA,
        wgsl::OPTICS,
        wgsl::LIGHTING,
        wgsl::ENVIRONMENT,
        wgsl::SCATTER,
        entry_file,
    ]);
    src
}

/// Compile render kernel `entry` of `entry_file` with `stage_group` as
/// group 2.
fn kernel(
    ctx: &GpuContext,
    scene: &GpuScene,
    entry_file: &'static str,
    entry: &str,
    stage_group: &[BindingKind],
) -> GpuResult<Kernel> {
    Kernel::new(
        ctx,
        &format!("render {entry}"),
        &sources(scene, entry_file),
        entry,
        &[&SCENE_GROUP, &SHADE_GROUP, stage_group],
    )
}

/// Sample positions (fx, fy) of every pixel for camera sample `sample`.
fn positions(opts: &WhittedOptions, sample: u32) -> Vec<u32> {
    let spp = opts.samples_per_pixel.max(1);
    let mut out = Vec::with_capacity(2 * opts.width as usize * opts.height as usize);
    for y in 0..opts.height {
        for x in 0..opts.width {
            let (fx, fy) = sample_position(opts.seed, opts.width, spp, x, y, sample);
            out.extend([fx.to_bits(), fy.to_bits()]);
        }
    }
    out
}

/// Render `scene` (uploaded as `gpu`) through `camera` with the
/// organisation `opts.integrator` picks: recursive → the stack kd-tree GPU tracer's single
/// kernel, wavefront → the Purcell-style stream tracer's stream. `progress(samples, rays)` is
/// called after each camera sample of every pixel. The frame holds the
/// average linear radiance times the exposure, encoded as the CPU's, and
/// the first camera sample's hits, as the CPU's frame does.
pub fn render_whitted_gpu(
    ctx: &GpuContext,
    gpu: &GpuScene,
    scene: &ShadeScene,
    camera: &Camera,
    opts: &WhittedOptions,
    progress: &dyn Fn(u64, u64),
) -> GpuResult<GpuFrame> {
    check_options(opts)?;
    let start = Instant::now();
    let settings = FrameSettings {
        width: opts.width,
        height: opts.height,
        max_depth: opts.max_depth,
        ambient: opts.ambient,
        shadows: opts.shadows == ShadowMode::Rays,
    };
    let shade = ShadeBuffers::upload(ctx, scene, camera, &settings)?;
    let n = opts.width as usize * opts.height as usize;
    let spp = opts.samples_per_pixel.max(1);
    let report = match opts.integrator {
        IntegratorKind::Recursive => megakernel::run(ctx, gpu, &shade, opts, progress)?,
        IntegratorKind::Wavefront => stream::run(ctx, gpu, &shade, opts, progress)?,
    };
    let sums = crate::buffers::read_words(ctx, &shade.radiance, 3 * n)?;
    let counters = read_counters(ctx, &shade)?;
    let scale = opts.exposure / spp as f32;
    let linear: Vec<Vec3> = sums
        .chunks_exact(3)
        .map(|c| {
            Vec3::new(
                f32::from_bits(c[0]),
                f32::from_bits(c[1]),
                f32::from_bits(c[2]),
            ) * scale
        })
        .collect();
    let stats = FrameStats {
        primary_rays: n as u64 * spp as u64,
        shadow_rays: counters[0] as u64,
        secondary_rays: report.secondary.unwrap_or(counters[1] as u64),
        raster_seconds: 0.0,
        seconds: start.elapsed().as_secs_f64() - report.compile_seconds,
        environment_hits: counters[2] as u64,
    };
    let first_hits = report
        .first_hits
        .chunks_exact(4)
        .map(|w| {
            (w[3] != u32::MAX).then(|| Hit {
                t: f32::from_bits(w[0]),
                u: f32::from_bits(w[1]),
                v: f32::from_bits(w[2]),
                prim: w[3],
            })
        })
        .collect();
    Ok(GpuFrame {
        frame: Frame {
            image: Image::from_linear(opts.width, opts.height, linear, opts.encoding),
            first_hits,
            stats,
        },
        compile_seconds: report.compile_seconds,
    })
}

/// The ray counters of a finished dispatch; an error if a kernel found one
/// of a thread's loops cut short by the driver (the status word, see
/// `shaders/render/shade_data.wgsl`), since the frame would be wrong.
fn read_counters(ctx: &GpuContext, shade: &ShadeBuffers) -> GpuResult<Vec<u32>> {
    let c = crate::buffers::read_words(ctx, &shade.counters, COUNTER_WORDS)?;
    if c[4] != 0 {
        return Err(ctx.loop_limit("a pixel's rays"));
    }
    Ok(c)
}

/// Rays counted so far (shadow + secondary), read from the counters; an
/// error if the driver cut a thread's loop short.
fn counted(ctx: &GpuContext, shade: &ShadeBuffers) -> GpuResult<u64> {
    let c = read_counters(ctx, shade)?;
    Ok(c[0] as u64 + c[1] as u64)
}
