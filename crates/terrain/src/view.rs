//! The image-wide casting loop shared by the three casters.

use crate::boxes::{pixel_starts, select_boxes};
use crate::camera::TerrainCamera;
use crate::heightfield::{HeightField, Steps, TerrainHit};
use crate::march::{march, march_from};
use crate::maxmip::trace;
use crate::pyramid::MaxMipmap;
use rayon::prelude::*;

/// Which caster to use.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Caster {
    /// Cell-by-cell DDA from the grid's bounding box (the reference).
    March,
    /// Per-ray maximum-mipmap traversal.
    MaxMipmap,
    /// Per-frame quadtree boxes with LOD parameter τ (pixels).
    Boxes {
        /// Side of the pixel square a node's footprint is compared with
        /// (refine while the footprint is at least 4 τ² pixels).
        tau: f64,
    },
}

/// One image's hits and work.
pub struct CastImage {
    /// Per pixel, row-major from the top: the first hit, if any.
    pub hits: Vec<Option<TerrainHit>>,
    /// Per pixel work.
    pub steps: Vec<Steps>,
    /// Boxes the frame used (the quadtree-box caster only).
    pub boxes: usize,
}

/// Cast one ray per pixel of `camera` with `caster` (parallel over rows).
pub fn cast_image(
    field: &HeightField,
    pyramid: &MaxMipmap,
    camera: &TerrainCamera,
    caster: Caster,
) -> CastImage {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let (starts, boxes) = match caster {
        Caster::Boxes { tau } => {
            let b = select_boxes(field, pyramid, camera, tau);
            let n = b.len();
            (Some(pixel_starts(field, camera, &b)), n)
        }
        _ => (None, 0),
    };
    let frame = camera.frame();
    let mut hits = vec![None; w * h];
    let mut steps = vec![Steps::default(); w * h];
    hits.par_chunks_mut(w)
        .zip(steps.par_chunks_mut(w))
        .enumerate()
        .for_each(|(y, (hrow, srow))| {
            for x in 0..w {
                let ray = frame.ray(field, x as u32, y as u32);
                let s = &mut srow[x];
                hrow[x] = match caster {
                    Caster::March => march(field, &ray, 0.0, f64::INFINITY, s),
                    Caster::MaxMipmap => trace(field, pyramid, &ray, 0.0, f64::INFINITY, s),
                    Caster::Boxes { .. } => {
                        let st = starts.as_ref().expect("starts computed for boxes");
                        let (start, visits) = st[y * w + x];
                        s.nodes += visits;
                        if start.is_finite() {
                            field.clip(&ray, 0.0, f64::INFINITY).and_then(|(t0, t1)| {
                                // Start a hair before the box entry, so a hit on
                                // the box's face is not lost to rounding.
                                let from = (start - 1e-7 * start.abs().max(1.0)).max(t0);
                                march_from(field, &ray, from, t1, s)
                            })
                        } else {
                            None
                        }
                    }
                };
            }
        });
    CastImage { hits, steps, boxes }
}
