//! Batch ray queries on the GPU: one thread per ray, nearest hits or
//! occlusion, over any [`GpuScene`].

use crate::buffers::{output, read_words, read_words_at, storage, uniform};
use crate::context::GpuContext;
use crate::error::GpuResult;
use crate::kernel::{dispatch_timed, grid, wgsl, BindingKind, Kernel, SCENE_GROUP};
use crate::scene::GpuScene;
use raykit_core::{Hit, Ray};
use std::time::Instant;

/// Rays per dispatch: bounds the ray and hit buffers (32 MB and 16 MB).
pub const CHUNK: usize = 1 << 20;

pub(crate) const TRACE_GROUP: [BindingKind; 3] = [
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
///
/// The output buffer holds four words per ray and a status word after
/// them, which a kernel sets when a ray's traversal loop was cut short by
/// the driver (see `shaders/scene.wgsl`); [`GpuTracer::hits`] and
/// [`GpuTracer::occlusion`] then refuse the results.
pub struct GpuRays {
    pub(crate) rays: wgpu::Buffer,
    pub(crate) out: wgpu::Buffer,
    pub(crate) params: wgpu::Buffer,
    count: usize,
    pub(crate) groups: (u32, u32),
}

impl GpuRays {
    /// An error if a finished run found a ray's traversal loop cut short.
    pub(crate) fn check(&self, ctx: &GpuContext) -> GpuResult<()> {
        if read_words_at(ctx, &self.out, self.count * 4, 1)? != [0] {
            return Err(ctx.loop_limit("a ray's traversal"));
        }
        Ok(())
    }
}

/// The clock a kernel run is timed with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Clock {
    /// The GPU's timestamps written at the start and end of the compute
    /// pass: the kernel alone, without submission or the wait.
    Timestamps,
    /// Wall-clock time from submission until `device.poll` has waited for
    /// the queue: the kernel plus submission and completion latency.
    WallClock,
}

impl Clock {
    /// The name the experiment reports.
    pub fn name(self) -> &'static str {
        match self {
            Clock::Timestamps => "GPU timestamp queries",
            Clock::WallClock => "wall clock, submission to device.poll wait",
        }
    }
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
            words.extend(r.to_array().map(f32::to_bits));
        }
        let (x, y, row) = grid(self.ctx, rays.len())?;
        Ok(GpuRays {
            rays: storage(self.ctx, "rays", &words)?,
            out: output(self.ctx, "hits", rays.len() * 4 + 1)?,
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
        self.run_clocked(rays, any, Clock::WallClock)
    }

    /// The best clock the device offers: its timestamps where it has them.
    pub fn clock(&self) -> Clock {
        if self.ctx.timestamps {
            Clock::Timestamps
        } else {
            Clock::WallClock
        }
    }

    /// [`GpuTracer::run`] timed with `clock` ([`Clock::Timestamps`] needs a
    /// device with timestamp queries, see [`GpuTracer::clock`]); returns
    /// seconds.
    pub fn run_clocked(&self, rays: &GpuRays, any: bool, clock: Clock) -> GpuResult<f64> {
        let kernel = if any { &self.any } else { &self.nearest };
        let g0 = self.scene.bind(self.ctx, kernel);
        let g1 = kernel.bind(self.ctx, 1, &[&rays.rays, &rays.out, &rays.params]);
        let mut enc = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("trace"),
            });
        let queries = (clock == Clock::Timestamps).then(|| {
            let set = self.ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("kernel timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            });
            let resolved = self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("kernel timestamps"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            (set, resolved)
        });
        dispatch_timed(
            &mut enc,
            kernel,
            &[&g0, &g1],
            rays.groups,
            queries.as_ref().map(|q| &q.0),
        );
        if let Some((set, resolved)) = &queries {
            enc.resolve_query_set(set, 0..2, resolved, 0);
        }
        let start = Instant::now();
        self.ctx.queue.submit([enc.finish()]);
        self.ctx.wait()?;
        let secs = start.elapsed().as_secs_f64();
        self.ctx.take_error()?;
        match &queries {
            None => Ok(secs),
            Some((_, resolved)) => {
                let w = crate::buffers::read_words(self.ctx, resolved, 4)?;
                let begin = w[0] as u64 | (w[1] as u64) << 32;
                let end = w[2] as u64 | (w[3] as u64) << 32;
                let period = self.ctx.queue.get_timestamp_period() as f64;
                Ok(end.saturating_sub(begin) as f64 * period * 1e-9)
            }
        }
    }

    /// Nearest hits of a finished [`GpuTracer::run`]; an error if the
    /// driver cut a ray's traversal short.
    pub fn hits(&self, rays: &GpuRays) -> GpuResult<Vec<Option<Hit>>> {
        let mut words = read_words(self.ctx, &rays.out, rays.count * 4 + 1)?;
        if words.pop() != Some(0) {
            return Err(self.ctx.loop_limit("a ray's traversal"));
        }
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

    /// Occlusion flags of a finished [`GpuTracer::run`] with `any`; an
    /// error if the driver cut a ray's traversal short.
    pub fn occlusion(&self, rays: &GpuRays) -> GpuResult<Vec<bool>> {
        rays.check(self.ctx)?;
        let words = read_words(self.ctx, &rays.out, rays.count)?;
        Ok(words.into_iter().map(|w| w != 0).collect())
    }

    /// Nearest hits of any number of rays.
    pub fn intersect_batch(&self, rays: &[Ray]) -> GpuResult<Vec<Option<Hit>>> {
        Ok(self.intersect_timed(rays)?.0)
    }

    /// Occlusion of any number of rays.
    pub fn occluded_batch(&self, rays: &[Ray]) -> GpuResult<Vec<bool>> {
        Ok(self.occluded_timed(rays)?.0)
    }

    /// Nearest hits of any number of rays, in chunks of [`CHUNK`], and the
    /// seconds the kernels ran.
    pub fn intersect_timed(&self, rays: &[Ray]) -> GpuResult<(Vec<Option<Hit>>, f64)> {
        let mut out = Vec::with_capacity(rays.len());
        let mut seconds = 0.0;
        for chunk in rays.chunks(CHUNK) {
            let up = self.upload(chunk)?;
            seconds += self.run(&up, false)?;
            out.extend(self.hits(&up)?);
        }
        Ok((out, seconds))
    }

    /// Occlusion of any number of rays, in chunks of [`CHUNK`], and the
    /// seconds the kernels ran.
    pub fn occluded_timed(&self, rays: &[Ray]) -> GpuResult<(Vec<bool>, f64)> {
        let mut out = Vec::with_capacity(rays.len());
        let mut seconds = 0.0;
        for chunk in rays.chunks(CHUNK) {
            let up = self.upload(chunk)?;
            seconds += self.run(&up, true)?;
            out.extend(self.occlusion(&up)?);
        }
        Ok((out, seconds))
    }
}
