//! Casting a view on the GPU: rays uploaded in chunks, one kernel dispatch
//! per chunk, hits read back as the CPU's
//! [`CastImage`](raykit_terrain::view::CastImage) so the host shades and
//! heat-maps them with the same code.

use super::rays::{ray_words, view_rays, GpuGridRay};
use super::{GpuTerrain, TerrainParams};
use crate::buffers::{output, read_words, storage, uniform};
use crate::context::GpuContext;
use crate::error::GpuResult;
use crate::kernel::{dispatch, grid};
use crate::trace::CHUNK;
use raykit_terrain::view::{CastImage, TerrainCamera};
use raykit_terrain::{HeightField, Steps, TerrainHit};
use std::time::Instant;

/// Words of one result: t, cell, nodes visited, cells tested.
const OUT_WORDS: usize = 4;

/// Up to [`CHUNK`] pixels' rays uploaded with their result buffer, for one
/// dispatch (repeatable, for timing).
pub struct GpuView {
    /// The rays as uploaded (the host keeps each ray's `t0`).
    pub rays: Vec<GpuGridRay>,
    ray_buf: wgpu::Buffer,
    out: wgpu::Buffer,
    params: wgpu::Buffer,
    groups: (u32, u32),
}

impl GpuTerrain {
    /// Upload the rays of pixels `first .. first + count` of `camera`
    /// (`count` at most [`CHUNK`]).
    pub fn upload_view(
        &self,
        ctx: &GpuContext,
        field: &HeightField,
        camera: &TerrainCamera,
        first: usize,
        count: usize,
    ) -> GpuResult<GpuView> {
        let count = count.min(CHUNK);
        let rays = view_rays(field, camera, first, count);
        let (x, y, row) = grid(ctx, count)?;
        let params = TerrainParams {
            count: count as u32,
            row,
            ..self.params
        };
        Ok(GpuView {
            ray_buf: storage(ctx, "terrain rays", &ray_words(&rays))?,
            out: output(ctx, "terrain hits", count * OUT_WORDS)?,
            params: uniform(ctx, "terrain parameters", &params),
            rays,
            groups: (x, y),
        })
    }

    /// Cast the uploaded rays and wait; returns the seconds from submission
    /// to completion.
    pub fn run(&self, ctx: &GpuContext, view: &GpuView) -> GpuResult<f64> {
        let g = self.kernel.bind(
            ctx,
            0,
            &[
                &self.heights,
                &self.maxes,
                &view.ray_buf,
                &view.out,
                &view.params,
            ],
        );
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("terrain maxmip"),
            });
        dispatch(&mut enc, &self.kernel, &[&g], view.groups);
        let start = Instant::now();
        ctx.queue.submit([enc.finish()]);
        ctx.wait()?;
        let secs = start.elapsed().as_secs_f64();
        ctx.take_error()?;
        Ok(secs)
    }

    /// The hits and steps of a finished [`GpuTerrain::run`]; distances are
    /// the CPU ray's parameter (metres from the eye).
    pub fn results(
        &self,
        ctx: &GpuContext,
        view: &GpuView,
    ) -> GpuResult<(Vec<Option<TerrainHit>>, Vec<Steps>)> {
        let words = read_words(ctx, &view.out, view.rays.len() * OUT_WORDS)?;
        Ok(words
            .chunks_exact(OUT_WORDS)
            .zip(&view.rays)
            .map(|(w, r)| {
                let hit = (w[1] != u32::MAX).then(|| TerrainHit {
                    t: r.t0 + f32::from_bits(w[0]) as f64,
                    col: w[1] & 0xffff,
                    row: w[1] >> 16,
                });
                let steps = Steps {
                    nodes: w[2],
                    cells: w[3],
                };
                (hit, steps)
            })
            .unzip())
    }

    /// One ray per pixel of `camera` (row-major from the top): the GPU
    /// counterpart of `raykit_terrain::view::cast_image` with the
    /// maximum-mipmap caster.
    pub fn cast(
        &self,
        ctx: &GpuContext,
        field: &HeightField,
        camera: &TerrainCamera,
    ) -> GpuResult<CastImage> {
        let pixels = camera.width as usize * camera.height as usize;
        let mut hits = Vec::with_capacity(pixels);
        let mut steps = Vec::with_capacity(pixels);
        let mut first = 0;
        while first < pixels {
            let count = (pixels - first).min(CHUNK);
            let view = self.upload_view(ctx, field, camera, first, count)?;
            self.run(ctx, &view)?;
            let (h, s) = self.results(ctx, &view)?;
            hits.extend(h);
            steps.extend(s);
            first += count;
        }
        Ok(CastImage {
            hits,
            steps,
            boxes: 0,
        })
    }
}
