//! Per-pixel rays of a terrain view for the GPU casters: computed on the
//! host in f64 exactly as the CPU casters compute them
//! (`raykit_terrain::camera::CameraFrame::ray`), clipped to the grid's
//! bounding box, and rounded to f32 with the origin moved to the clip entry
//! (grid coordinates stay small there, which keeps the rounding small).

use raykit_terrain::camera::TerrainCamera;
use raykit_terrain::{GridRay, HeightField};
use rayon::prelude::*;

/// Floats per ray record: origin (3), span, direction (3), unused.
pub const RAY_WORDS: usize = 8;

/// One pixel's ray as the GPU sees it: grid units, origin at the entry into
/// the grid's bounding box (parameter `t0` of the CPU's ray).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuGridRay {
    /// Origin (column, row, height), f32.
    pub o: [f32; 3],
    /// Direction per unit `t` (metres), f32.
    pub d: [f32; 3],
    /// Parameter of the exit from the bounding box, from `o`; negative when
    /// the ray misses the box.
    pub span: f32,
    /// The CPU ray's parameter at `o` (f64, added back to GPU distances).
    pub t0: f64,
}

impl GpuGridRay {
    /// The record as an f64 [`GridRay`] (exactly the rounded ray), for
    /// checking GPU answers with the CPU casters.
    pub fn grid_ray(&self) -> GridRay {
        GridRay {
            o: self.o.map(f64::from),
            d: self.d.map(f64::from),
        }
    }

    /// True when the ray meets the grid's bounding box.
    pub fn meets_grid(&self) -> bool {
        self.span >= 0.0
    }
}

/// The rays of pixels `first .. first + count` (row-major from the top) of
/// `camera`, with `t` in `[0, ∞)` as the CPU's image loop casts them.
pub fn view_rays(
    field: &HeightField,
    camera: &TerrainCamera,
    first: usize,
    count: usize,
) -> Vec<GpuGridRay> {
    let frame = camera.frame();
    let w = camera.width.max(1) as usize;
    (first..first + count)
        .into_par_iter()
        .map(|k| {
            let ray = frame.ray(field, (k % w) as u32, (k / w) as u32);
            match field.clip(&ray, 0.0, f64::INFINITY) {
                Some((t0, t1)) if t1.is_finite() => GpuGridRay {
                    o: ray.at(t0).map(|x| x as f32),
                    d: ray.d.map(|x| x as f32),
                    span: (t1 - t0) as f32,
                    t0,
                },
                _ => GpuGridRay {
                    o: [0.0; 3],
                    d: ray.d.map(|x| x as f32),
                    span: -1.0,
                    t0: 0.0,
                },
            }
        })
        .collect()
}

/// The records' words for upload ([`RAY_WORDS`] per ray).
pub fn ray_words(rays: &[GpuGridRay]) -> Vec<u32> {
    let mut words = Vec::with_capacity(rays.len() * RAY_WORDS);
    for r in rays {
        words.extend(
            [r.o[0], r.o[1], r.o[2], r.span, r.d[0], r.d[1], r.d[2], 0.0].map(f32::to_bits),
        );
    }
    words
}
