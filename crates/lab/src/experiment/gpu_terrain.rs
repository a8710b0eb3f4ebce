//! The terrain part of `raykit experiment gpu`: the terrain casters on the
//! GPU backend — per-ray maximum-mipmap traversal (Tevs et al. 2008) and the
//! per-frame boxes (τ = 16, the best) — beside the same casters on
//! the CPU, on one low oblique view per DEM. Every GPU pixel is checked
//! against the CPU's cell-by-cell march of the same ray.

use crate::measure::median_min_max;
use anyhow::{anyhow, Result};
use raykit_gpu::{time_terrain_boxes, time_terrain_casts, GpuCaster, GpuContext, GpuTerrain};
use raykit_terrain::io::{load_dem, LoadOptions};
use raykit_terrain::view::{cast_image, Caster};
use raykit_terrain::{HeightField, MaxMipmap, TerrainCamera, TerrainHit};
use serde::Serialize;
use std::time::Instant;

/// Mrays/s of the four casters on one DEM and view.
#[derive(Serialize, Clone)]
pub struct TerrainRow {
    /// DEM file name.
    pub dem: String,
    /// Grid samples `W×H`.
    pub grid: String,
    /// View pixels `W×H`.
    pub view: String,
    /// GPU maximum mipmap, kernel time.
    pub gpu_maxmip: f64,
    /// GPU boxes τ = 16, kernel time (box selection on the CPU not included).
    pub gpu_boxes16: f64,
    /// CPU maximum mipmap, all threads.
    pub cpu_maxmip: f64,
    /// CPU boxes τ = 16, all threads.
    pub cpu_boxes16: f64,
    /// Worst (max − min) / median.
    pub spread: f64,
    /// GPU pixels compared with the CPU march (both GPU casters).
    pub checked: usize,
    /// Of those, pixels where hit and miss differ or the distances differ
    /// by more than [`T_TOLERANCE`] of the distance.
    pub differ: usize,
}

/// Relative difference of a GPU hit's distance from the CPU's accepted as
/// the same hit: the GPU adds an f32 distance to the ray's f64 entry.
pub const T_TOLERANCE: f64 = 1e-4;

/// Whether a GPU pixel's hit is the CPU's.
fn same_hit(gpu: &Option<TerrainHit>, cpu: &Option<TerrainHit>) -> bool {
    match (gpu, cpu) {
        (None, None) => true,
        (Some(g), Some(c)) => (g.t - c.t).abs() <= T_TOLERANCE * c.t.abs().max(1.0),
        _ => false,
    }
}

/// A low oblique view across the whole terrain from its north-west corner.
fn oblique(field: &HeightField, width: u32, height: u32) -> TerrainCamera {
    let (wx, wy) = (
        (field.width - 1) as f64 * field.sx,
        (field.height - 1) as f64 * field.sy,
    );
    TerrainCamera {
        eye: [-0.1 * wx, 0.1 * wy, field.zmax as f64 + 0.05 * wx.max(wy)],
        target: [0.6 * wx, -0.6 * wy, field.zmin as f64],
        vfov_deg: 50.0,
        width,
        height,
    }
}

/// A DEM loaded for [`measure_dem`]: its path as given and its height field.
pub struct LoadedDem {
    path: String,
    field: HeightField,
}

impl LoadedDem {
    /// The path the DEM was loaded from.
    pub fn path(&self) -> &str {
        &self.path
    }
}

/// Load the DEM at `path` (`--dem`), so that a missing or unreadable file is
/// refused before the long measurements start.
pub fn load(path: &str) -> Result<LoadedDem> {
    let dem = load_dem(path, &LoadOptions::default()).map_err(|e| {
        // The loader's message names the file itself.
        let e = e.to_string();
        anyhow!(
            "--dem {path}: {}",
            e.strip_prefix(&format!("{path}: ")).unwrap_or(&e)
        )
    })?;
    let field = HeightField::new(&dem).map_err(|e| anyhow!("--dem {path}: {e}"))?;
    Ok(LoadedDem {
        path: path.to_string(),
        field,
    })
}

/// Measure one loaded DEM.
pub fn measure_dem(
    ctx: &GpuContext,
    dem: &LoadedDem,
    (width, height): (u32, u32),
    reps: usize,
) -> Result<TerrainRow> {
    let (path, field) = (dem.path.as_str(), &dem.field);
    let pyramid = MaxMipmap::new(field);
    let cam = oblique(field, width, height);
    let gpu = |e: raykit_gpu::GpuError| anyhow!("{path}: {e}");
    let g_max = time_terrain_casts(ctx, field, &pyramid, &cam, reps).map_err(gpu)?;
    let g_box = time_terrain_boxes(ctx, field, &pyramid, &cam, 16.0, reps).map_err(gpu)?;
    let rays = width as f64 * height as f64;
    let mut spread: f64 = 0.0;
    let mut cpu = |caster: Caster| {
        let times: Vec<f64> = (0..reps.max(1))
            .map(|_| {
                let start = Instant::now();
                std::hint::black_box(cast_image(field, &pyramid, &cam, caster));
                start.elapsed().as_secs_f64()
            })
            .collect();
        let (med, lo, hi) = median_min_max(&times);
        spread = spread.max((hi - lo) / med);
        rays / med / 1e6
    };
    let cpu_maxmip = cpu(Caster::MaxMipmap);
    let cpu_boxes16 = cpu(Caster::Boxes { tau: 16.0 });
    let reference = cast_image(field, &pyramid, &cam, Caster::March).hits;
    let terrain = GpuTerrain::new(ctx, field, &pyramid).map_err(gpu)?;
    let (mut checked, mut differ) = (0, 0);
    for caster in [GpuCaster::MaxMipmap, GpuCaster::Boxes { tau: 16.0 }] {
        let got = terrain
            .cast(ctx, field, &pyramid, &cam, caster)
            .map_err(gpu)?
            .hits;
        checked += got.len();
        differ += got
            .iter()
            .zip(&reference)
            .filter(|(g, c)| !same_hit(g, c))
            .count();
    }
    if differ > 0 {
        eprintln!(
            "raykit: {path}: {differ} of {checked} GPU terrain pixels differ from the CPU's march \
             (hit against miss, or distances apart by more than {T_TOLERANCE} of the distance)"
        );
    }
    for t in [&g_max, &g_box] {
        let (med, lo, hi) = median_min_max(&t.seconds);
        spread = spread.max((hi - lo) / med);
    }
    Ok(TerrainRow {
        dem: std::path::Path::new(path)
            .file_name()
            .map_or(path.to_string(), |n| n.to_string_lossy().into_owned()),
        grid: format!("{}×{}", field.width, field.height),
        view: format!("{width}×{height}"),
        gpu_maxmip: g_max.median_mrays,
        gpu_boxes16: g_box.median_mrays,
        cpu_maxmip,
        cpu_boxes16,
        spread,
        checked,
        differ,
    })
}

/// The Markdown section for the rows.
pub fn markdown(rows: &[TerrainRow], threads: usize) -> String {
    let mut s = format!("\n## Terrain ray casting (per-frame quadtree boxes) on the GPU backend\n\nMrays/s, median: GPU kernel time (rays made and boxes selected on the host are not included); CPU on {threads} threads, rays made and cast. One low oblique view across the whole DEM. Checked: the GPU pixels (both casters) compared with the CPU's cell-by-cell march; differ: hit against miss, or distances apart by more than {T_TOLERANCE} of the distance.\n\n| DEM | grid | view | GPU max mipmap | GPU boxes τ=16 | CPU max mipmap | CPU boxes τ=16 | noise | checked | differ |\n|---|---|---|---:|---:|---:|---:|---:|---:|---:|\n");
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.0}% | {} | {} |\n",
            r.dem,
            r.grid,
            r.view,
            r.gpu_maxmip,
            r.gpu_boxes16,
            r.cpu_maxmip,
            r.cpu_boxes16,
            r.spread * 100.0,
            r.checked,
            r.differ
        );
    }
    s
}
