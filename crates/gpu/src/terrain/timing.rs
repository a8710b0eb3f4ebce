//! Throughput of the GPU terrain caster, for `raykit experiment gpu` and
//! benchmarks: per-ray maximum-mipmap traversal (Tevs et al.
//! 2008) timed from submission to completion of the kernel.

use super::{GpuCaster, GpuTerrain};
use crate::context::GpuContext;
use crate::error::{GpuError, GpuResult};
use crate::trace::CHUNK;
use raykit_terrain::TerrainCamera;
use raykit_terrain::{HeightField, MaxMipmap};
use std::time::Instant;

/// Timings of [`time_terrain_casts`].
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainTiming {
    /// Rays per run (the view's pixels).
    pub rays: usize,
    /// Kernel seconds of each run, submission to completion (summed over
    /// the view's chunks).
    pub seconds: Vec<f64>,
    /// Millions of rays per second of the fastest run.
    pub best_mrays: f64,
    /// Millions of rays per second of the median run.
    pub median_mrays: f64,
    /// Rays that hit the terrain.
    pub hits: usize,
    /// Mean nodes visited plus cells tested per ray.
    pub mean_steps: f64,
    /// Seconds to upload the heights and pyramid and compile the kernel.
    pub setup_seconds: f64,
    /// Seconds to make and upload the rays (host, f64, then rounded) and,
    /// for the boxes, to select and upload them.
    pub ray_seconds: f64,
}

/// Cast `camera`'s view of `field` `reps` times (after one warm-up run) on
/// the GPU with the per-ray maximum-mipmap kernel and time the kernel (one
/// dispatch per [`CHUNK`] pixels, their times summed); `reps` at least 1.
pub fn time_terrain_casts(
    ctx: &GpuContext,
    field: &HeightField,
    pyramid: &MaxMipmap,
    camera: &TerrainCamera,
    reps: usize,
) -> GpuResult<TerrainTiming> {
    time_caster(ctx, field, pyramid, camera, GpuCaster::MaxMipmap, reps)
}

/// [`time_terrain_casts`] for per-frame quadtree boxes with LOD `tau`:
/// the kernel time covers each pixel's nearest box entry and its march; the
/// CPU's box selection is in `ray_seconds`.
pub fn time_terrain_boxes(
    ctx: &GpuContext,
    field: &HeightField,
    pyramid: &MaxMipmap,
    camera: &TerrainCamera,
    tau: f64,
    reps: usize,
) -> GpuResult<TerrainTiming> {
    time_caster(ctx, field, pyramid, camera, GpuCaster::Boxes { tau }, reps)
}

fn time_caster(
    ctx: &GpuContext,
    field: &HeightField,
    pyramid: &MaxMipmap,
    camera: &TerrainCamera,
    caster: GpuCaster,
    reps: usize,
) -> GpuResult<TerrainTiming> {
    let pixels = camera.width as usize * camera.height as usize;
    if pixels == 0 {
        return Err(GpuError::Unsupported(format!(
            "timing a {}x{} view; the timed view needs at least one pixel",
            camera.width, camera.height
        )));
    }
    let start = Instant::now();
    let terrain = GpuTerrain::new(ctx, field, pyramid)?;
    ctx.wait()?;
    let setup_seconds = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let views = (0..pixels)
        .step_by(CHUNK)
        .map(|first| {
            let count = (pixels - first).min(CHUNK);
            terrain.upload_view(ctx, field, pyramid, camera, caster, first, count)
        })
        .collect::<GpuResult<Vec<_>>>()?;
    ctx.wait()?;
    let ray_seconds = start.elapsed().as_secs_f64();
    let run_all = || -> GpuResult<f64> { views.iter().map(|v| terrain.run(ctx, v)).sum() };
    run_all()?;
    let mut seconds = Vec::with_capacity(reps.max(1));
    for _ in 0..reps.max(1) {
        seconds.push(run_all()?);
    }
    let (mut hits, mut steps) = (Vec::new(), Vec::new());
    for v in &views {
        let (h, s) = terrain.results(ctx, v)?;
        hits.extend(h);
        steps.extend(s);
    }
    let mut sorted = seconds.clone();
    sorted.sort_by(f64::total_cmp);
    let mrays = |s: f64| pixels as f64 / s.max(1e-12) / 1e6;
    Ok(TerrainTiming {
        rays: pixels,
        best_mrays: mrays(sorted[0]),
        median_mrays: mrays(sorted[sorted.len() / 2]),
        seconds,
        hits: hits.iter().filter(|h| h.is_some()).count(),
        mean_steps: steps
            .iter()
            .map(|s| (s.nodes + s.cells) as f64)
            .sum::<f64>()
            / pixels as f64,
        setup_seconds,
        ray_seconds,
    })
}
