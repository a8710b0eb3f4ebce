//! GPU terrain ray casting: the height field and its maximum
//! mipmap (Tevs et al. 2008, as the quadtree-box caster uses it) in storage buffers, and
//! a WGSL kernel casting one ray per pixel by per-ray top-down traversal,
//! the same walk as `raykit_terrain::maxmip` on the same declared surface
//! (two triangles per cell, split along the (col, row)–(col+1, row+1)
//! diagonal), in f32 with conservative tests (`shaders/terrain_maxmip.wgsl`).
//!
//! - [`GpuTerrain`]: the uploaded surface and the compiled kernel;
//! - [`GpuTerrain::cast`]: a [`CastImage`](raykit_terrain::view::CastImage)
//!   like the CPU's `cast_image`, so the host shades it the same way;
//! - [`time_terrain_casts`]: Mrays/s of the kernel for benchmarks;
//! - per-frame quadtree boxes ([`GpuCaster::Boxes`],
//!   `shaders/terrain_boxes.wgsl`): the CPU's boxes uploaded, each pixel's
//!   nearest box entry found on the GPU, a march from there.

mod boxes;
mod cast;
mod rays;
mod timing;

pub use cast::{GpuCaster, GpuView};
pub use rays::{ray_words, view_rays, GpuGridRay, RAY_WORDS};
pub use timing::{time_terrain_boxes, time_terrain_casts, TerrainTiming};

use crate::buffers::storage;
use crate::context::GpuContext;
use crate::error::{GpuError, GpuResult};
use crate::kernel::{wgsl, BindingKind, Kernel};
use raykit_terrain::{HeightField, MaxMipmap};

/// Most pyramid levels the kernel's parameter block holds.
pub const MAX_LEVELS: usize = 24;
/// Most cells along x or y: the kernels pack (col, row) into 16 bits each.
pub const MAX_CELLS: usize = 65_535;

/// The kernel's bindings: heights, pyramid maxima, rays (storage),
/// results (read-write), parameters (uniform).
const TERRAIN_GROUP: [BindingKind; 5] = [
    BindingKind::Storage,
    BindingKind::Storage,
    BindingKind::Storage,
    BindingKind::StorageRw,
    BindingKind::Uniform,
];

/// Group 1 of `shaders/terrain_boxes.wgsl`: boxes, row lists (storage),
/// chunk parameters (uniform).
const BOXES_GROUP: [BindingKind; 3] = [
    BindingKind::Storage,
    BindingKind::Storage,
    BindingKind::Uniform,
];

/// Uniform block of `shaders/terrain_cell.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct TerrainParams {
    width: u32,
    top: u32,
    count: u32,
    row: u32,
    /// Per level: texels along x, along y, offset of the first texel, 0.
    levels: [[u32; 4]; MAX_LEVELS],
}

/// A height field and its maximum mipmap uploaded, with the per-ray
/// maximum-mipmap kernel compiled (Tevs et al. 2008).
pub struct GpuTerrain {
    heights: wgpu::Buffer,
    maxes: wgpu::Buffer,
    params: TerrainParams,
    kernel: Kernel,
    boxes_kernel: Kernel,
    cells: (u32, u32),
    /// Bytes uploaded (heights and pyramid maxima).
    pub bytes: u64,
}

impl GpuTerrain {
    /// Upload `field` and `pyramid` (built from it) and compile the kernel.
    /// A DEM whose heights or pyramid exceed one storage binding of the
    /// device gives [`GpuError::Limit`] naming the buffer and the limit.
    pub fn new(
        ctx: &GpuContext,
        field: &HeightField,
        pyramid: &MaxMipmap,
    ) -> GpuResult<GpuTerrain> {
        let (cw, ch) = field.cells();
        if cw > MAX_CELLS || ch > MAX_CELLS {
            return Err(GpuError::Unsupported(format!(
                "a DEM of {}x{} samples; the GPU terrain caster takes at most {} cells along each axis",
                field.width, field.height, MAX_CELLS
            )));
        }
        let l0 = &pyramid.levels[0];
        if pyramid.levels.len() > MAX_LEVELS || (l0.width, l0.height) != (cw, ch) {
            return Err(GpuError::Unsupported(format!(
                "a pyramid of {} levels over {}x{} texels for {cw}x{ch} cells",
                pyramid.levels.len(),
                l0.width,
                l0.height
            )));
        }
        let mut levels = [[0u32; 4]; MAX_LEVELS];
        let mut maxes = Vec::with_capacity(pyramid.levels.iter().map(|l| l.max_min.len()).sum());
        for (k, l) in pyramid.levels.iter().enumerate() {
            levels[k] = [l.width as u32, l.height as u32, maxes.len() as u32, 0];
            maxes.extend(l.max_min.iter().map(|m| m[0].to_bits()));
        }
        let heights: Vec<u32> = field.heights.iter().map(|h| h.to_bits()).collect();
        let what = format!("the heights of a {}x{} DEM", field.width, field.height);
        let heights_buf = storage(ctx, &what, &heights)?;
        let maxes_buf = storage(
            ctx,
            &format!(
                "the maximum mipmap of a {}x{} DEM",
                field.width, field.height
            ),
            &maxes,
        )?;
        let kernel = Kernel::new(
            ctx,
            "terrain maxmip",
            &[wgsl::COMMON, wgsl::TERRAIN_CELL, wgsl::TERRAIN_MAXMIP],
            "terrain_maxmip",
            &[&TERRAIN_GROUP],
        )?;
        let boxes_kernel = Kernel::new(
            ctx,
            "terrain boxes",
            &[wgsl::COMMON, wgsl::TERRAIN_CELL, wgsl::TERRAIN_BOXES],
            "terrain_boxes",
            &[&TERRAIN_GROUP, &BOXES_GROUP],
        )?;
        Ok(GpuTerrain {
            heights: heights_buf,
            maxes: maxes_buf,
            params: TerrainParams {
                width: field.width as u32,
                top: pyramid.top() as u32,
                count: 0,
                row: 0,
                levels,
            },
            kernel,
            boxes_kernel,
            cells: (cw as u32, ch as u32),
            bytes: 4 * (heights.len() + maxes.len()) as u64,
        })
    }
}
