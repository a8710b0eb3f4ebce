//! Batch ray queries on the GPU: one thread per ray, nearest hits or
//! occlusion, over any [`GpuScene`].

use crate::buffers::{output, read_words, storage, uniform};
use crate::context::GpuContext;
use crate::error::GpuResult;
use crate::kernel::{dispatch, grid, wgsl, BindingKind, Kernel, SCENE_GROUP};
use crate::scene::GpuScene;
use raykit_core::{Hit, Ray};
use std::time::Instant;

/// Rays per dispatch: bounds the ray and hit buffers (32 MB and 16 MB).
pub const CHUNK: usize = 1 << 20;

const TRACE_GROUP: [BindingKind; 3] = [
    BindingKind::Storage,
    BindingKind::StorageRw,
    BindingKind::Uniform,
];

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct TraceParams {
    count: u32,
    row: u32,
    _pad: [u32; 2],
}

/// The two batch kernels (nearest hit, any hit) compiled for one scene.
pub struct GpuTracer<'a> {
    ctx: &'a GpuContext,
    scene: &'a GpuScene,
    nearest: Kernel,
    any: Kernel,
}

/// Rays uploaded once, for repeated timing runs.
pub struct GpuRays {
    rays: wgpu::Buffer,
    out: wgpu::Buffer,
    params: wgpu::Buffer,
    count: usize,
    groups: (u32, u32),
}

impl<'a> GpuTracer<'a> {
    /// Compile the batch kernels for `scene`.
    pub fn new(ctx: &'a GpuContext, scene: &'a GpuScene) -> GpuResult<GpuTracer<'a>> {
        let mut src = scene.wgsl();
        src.push(wgsl::TRACE);
        let groups: [&[BindingKind]; 2] = [&SCENE_GROUP, &TRACE_GROUP];
        let name = format!("{} {}", scene.kind.name(), scene.test.name());
        let nearest = Kernel::new(
            ctx,
            &format!("{name} nearest"),
            &src,
            "trace_nearest",
            &groups,
        )?;
        let any = Kernel::new(ctx, &format!("{name} any"), &src, "trace_any", &groups)?;
        Ok(GpuTracer {
            ctx,
            scene,
            nearest,
            any,
        })
    }

    /// Upload up to [`CHUNK`] rays.
    pub fn upload(&self, rays: &[Ray]) -> GpuResult<GpuRays> {
        assert!(rays.len() <= CHUNK, "upload at most CHUNK rays at a time");
        let mut words = Vec::with_capacity(rays.len() * 8);
        for r in rays {
            words.extend(
                [
                    r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z, r.tnear, r.tfar,
                ]
                .map(f32::to_bits),
            );
        }
        let (x, y, row) = grid(self.ctx, rays.len())?;
        Ok(GpuRays {
            rays: storage(self.ctx, "rays", &words)?,
            out: output(self.ctx, "hits", rays.len() * 4)?,
            params: uniform(
                self.ctx,
                "trace parameters",
                &TraceParams {
                    count: rays.len() as u32,
                    row,
                    _pad: [0; 2],
                },
            ),
            count: rays.len(),
            groups: (x, y),
        })
    }

    /// Trace uploaded rays (nearest hits, or occlusion when `any`) and wait;
    /// returns the seconds from submission to completion.
    pub fn run(&self, rays: &GpuRays, any: bool) -> GpuResult<f64> {
        let kernel = if any { &self.any } else { &self.nearest };
        let g0 = self.scene.bind(self.ctx, kernel);
        let g1 = kernel.bind(self.ctx, 1, &[&rays.rays, &rays.out, &rays.params]);
        let mut enc = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("trace"),
            });
        dispatch(&mut enc, kernel, &[&g0, &g1], rays.groups);
        let start = Instant::now();
        self.ctx.queue.submit([enc.finish()]);
        self.ctx.wait()?;
        let secs = start.elapsed().as_secs_f64();
        self.ctx.take_error()?;
        Ok(secs)
    }

    /// Nearest hits of a finished [`GpuTracer::run`].
    pub fn hits(&self, rays: &GpuRays) -> GpuResult<Vec<Option<Hit>>> {
        let words = read_words(self.ctx, &rays.out, rays.count * 4)?;
        Ok(words
            .chunks_exact(4)
            .map(|w| {
                (w[1] != u32::MAX).then(|| Hit {
                    t: f32::from_bits(w[0]),
                    u: f32::from_bits(w[2]),
                    v: f32::from_bits(w[3]),
                    prim: w[1],
                })
            })
            .collect())
    }

    /// Occlusion flags of a finished [`GpuTracer::run`] with `any`.
    pub fn occlusion(&self, rays: &GpuRays) -> GpuResult<Vec<bool>> {
        let words = read_words(self.ctx, &rays.out, rays.count)?;
        Ok(words.into_iter().map(|w| w != 0).collect())
    }

    /// Nearest hits of any number of rays.
    pub fn intersect_batch(&self, rays: &[Ray]) -> GpuResult<Vec<Option<Hit>>> {
        let mut out = Vec::with_capacity(rays.len());
        for chunk in rays.chunks(CHUNK) {
            let up = self.upload(chunk)?;
            self.run(&up, false)?;
            out.extend(self.hits(&up)?);
        }
        Ok(out)
    }

    /// Occlusion of any number of rays.
    pub fn occluded_batch(&self, rays: &[Ray]) -> GpuResult<Vec<bool>> {
        let mut out = Vec::with_capacity(rays.len());
        for chunk in rays.chunks(CHUNK) {
            let up = self.upload(chunk)?;
            self.run(&up, true)?;
            out.extend(self.occlusion(&up)?);
        }
        Ok(out)
    }
}
