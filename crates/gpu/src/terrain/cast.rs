//! Casting a view on the GPU: rays uploaded in chunks, one kernel dispatch
//! per chunk, hits read back as the CPU's
//! [`CastImage`](raykit_terrain::view::CastImage) so the host shades and
//! heat-maps them with the same code.

use super::boxes::{box_words, row_lists};
use super::rays::{ray_words, view_rays, GpuGridRay};
use super::{GpuTerrain, TerrainParams};
use crate::buffers::{output, read_words, storage, uniform};
use crate::context::GpuContext;
use crate::error::GpuResult;
use crate::kernel::{dispatch, grid};
use crate::trace::CHUNK;
use raykit_terrain::boxes::select_boxes;
use raykit_terrain::view::CastImage;
use raykit_terrain::TerrainCamera;
use raykit_terrain::{HeightField, MaxMipmap, Steps, TerrainHit};
use std::time::Instant;

/// Words of one result: t, cell, nodes (or boxes) visited, cells tested.
const OUT_WORDS: usize = 4;

/// Which GPU caster (both exact for the declared surface up to f32
/// rounding, like their CPU counterparts).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GpuCaster {
    /// Per-ray maximum-mipmap traversal (Tevs et al. 2008).
    MaxMipmap,
    /// per-frame quadtree boxes with LOD parameter τ (pixels): the CPU
    /// selects the boxes, the GPU finds each pixel's nearest box entry and
    /// marches from there.
    Boxes {
        /// Refine a node while it covers at least 4 τ² pixels.
        tau: f64,
    },
}

/// Uniform block of `shaders/terrain_boxes.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BoxParams {
    first: u32,
    width: u32,
    cw: u32,
    ch: u32,
}

/// Up to [`CHUNK`] pixels' rays uploaded with their result buffer, for one
/// dispatch (repeatable, for timing).
///
/// The result buffer holds [`OUT_WORDS`] words per ray and a status word
/// after them, which a kernel sets when a ray's loop was cut short by the
/// driver (see `shaders/terrain_cell.wgsl`); [`GpuTerrain::results`] then
/// refuses the results.
pub struct GpuView {
    /// The rays as uploaded (the host keeps each ray's `t0`).
    pub rays: Vec<GpuGridRay>,
    ray_buf: wgpu::Buffer,
    out: wgpu::Buffer,
    params: wgpu::Buffer,
    groups: (u32, u32),
    /// per-frame quadtree boxes, row lists and chunk parameters (boxes caster).
    boxes: Option<[wgpu::Buffer; 3]>,
    /// Boxes the frame uses (0 for the maximum mipmap).
    pub box_count: usize,
}

impl GpuTerrain {
    /// Upload the rays of pixels `first .. first + count` of `camera`
    /// (`count` is cut to [`CHUNK`] and to the image) and, for per-frame quadtree boxes, the frame's
    /// boxes (selected on the CPU from `pyramid`).
    #[allow(clippy::too_many_arguments)]
    pub fn upload_view(
        &self,
        ctx: &GpuContext,
        field: &HeightField,
        pyramid: &MaxMipmap,
        camera: &TerrainCamera,
        caster: GpuCaster,
        first: usize,
        count: usize,
    ) -> GpuResult<GpuView> {
        let pixels = camera.width as usize * camera.height as usize;
        let count = count.min(CHUNK).min(pixels.saturating_sub(first));
        let rays = view_rays(field, camera, first, count);
        let (x, y, row) = grid(ctx, count)?;
        let params = TerrainParams {
            count: count as u32,
            row,
            ..self.params
        };
        let (boxes, box_count) = match caster {
            GpuCaster::MaxMipmap => (None, 0),
            GpuCaster::Boxes { tau } => {
                let b = select_boxes(field, pyramid, camera, tau);
                let bufs = [
                    storage(ctx, "terrain boxes", &box_words(&b))?,
                    storage(ctx, "terrain box rows", &row_lists(&b, camera.height))?,
                    uniform(
                        ctx,
                        "terrain box parameters",
                        &BoxParams {
                            first: first as u32,
                            width: camera.width,
                            cw: self.cells.0,
                            ch: self.cells.1,
                        },
                    ),
                ];
                (Some(bufs), b.len())
            }
        };
        Ok(GpuView {
            boxes,
            box_count,
            ray_buf: storage(ctx, "terrain rays", &ray_words(&rays))?,
            out: output(ctx, "terrain hits", count * OUT_WORDS + 1)?,
            params: uniform(ctx, "terrain parameters", &params),
            rays,
            groups: (x, y),
        })
    }

    /// Cast the uploaded rays and wait; returns the seconds from submission
    /// to completion.
    pub fn run(&self, ctx: &GpuContext, view: &GpuView) -> GpuResult<f64> {
        let kernel = match view.boxes {
            Some(_) => &self.boxes_kernel,
            None => &self.kernel,
        };
        let g = kernel.bind(
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
        let g1 = view
            .boxes
            .as_ref()
            .map(|[b, r, p]| kernel.bind(ctx, 1, &[b, r, p]));
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("terrain maxmip"),
            });
        let mut groups = vec![&g];
        groups.extend(g1.as_ref());
        dispatch(&mut enc, kernel, &groups, view.groups);
        let start = Instant::now();
        ctx.queue.submit([enc.finish()]);
        ctx.wait()?;
        let secs = start.elapsed().as_secs_f64();
        ctx.take_error()?;
        Ok(secs)
    }

    /// The hits and steps of a finished [`GpuTerrain::run`]; distances are
    /// the CPU ray's parameter (metres from the eye). An error if the
    /// driver cut a ray's march short.
    pub fn results(
        &self,
        ctx: &GpuContext,
        view: &GpuView,
    ) -> GpuResult<(Vec<Option<TerrainHit>>, Vec<Steps>)> {
        let mut words = read_words(ctx, &view.out, view.rays.len() * OUT_WORDS + 1)?;
        if words.pop() != Some(0) {
            return Err(ctx.loop_limit("a ray's march over the DEM"));
        }
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
    /// counterpart of `raykit_terrain::view::cast_image`.
    pub fn cast(
        &self,
        ctx: &GpuContext,
        field: &HeightField,
        pyramid: &MaxMipmap,
        camera: &TerrainCamera,
        caster: GpuCaster,
    ) -> GpuResult<CastImage> {
        let pixels = camera.width as usize * camera.height as usize;
        let mut hits = Vec::with_capacity(pixels);
        let mut steps = Vec::with_capacity(pixels);
        let mut first = 0;
        let mut boxes = 0;
        while first < pixels {
            let count = (pixels - first).min(CHUNK);
            let view = self.upload_view(ctx, field, pyramid, camera, caster, first, count)?;
            boxes = view.box_count;
            self.run(ctx, &view)?;
            let (h, s) = self.results(ctx, &view)?;
            hits.extend(h);
            steps.extend(s);
            first += count;
        }
        Ok(CastImage { hits, steps, boxes })
    }
}
