//! A pinhole camera over a terrain and the image-wide casting loop shared by
//! the three casters.

use crate::boxes::{pixel_starts, select_boxes};
use crate::heightfield::{GridRay, HeightField, Steps, TerrainHit};
use crate::march::{march, march_from};
use crate::maxmip::trace;
use crate::pyramid::MaxMipmap;
use rayon::prelude::*;

/// A pinhole camera in world metres (x east, y north, z up), z up on screen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerrainCamera {
    /// Eye position.
    pub eye: [f64; 3],
    /// Point looked at.
    pub target: [f64; 3],
    /// Vertical field of view, degrees.
    pub vfov_deg: f64,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
/// Dot product.
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn normalize(a: [f64; 3]) -> [f64; 3] {
    let l = dot(a, a).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

impl TerrainCamera {
    /// Orthonormal (right, up, forward); up is world z made orthogonal.
    pub fn basis(&self) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let f = normalize(sub(self.target, self.eye));
        let mut r = cross(f, [0.0, 0.0, 1.0]);
        if dot(r, r) < 1e-18 {
            r = cross(f, [0.0, 1.0, 0.0]);
        }
        let r = normalize(r);
        (r, cross(r, f), f)
    }

    /// tan of half the vertical and horizontal fields of view.
    pub fn tan_half(&self) -> (f64, f64) {
        let tv = (self.vfov_deg.to_radians() * 0.5).tan();
        (tv, tv * self.width as f64 / self.height.max(1) as f64)
    }

    /// The per-image constants of [`TerrainCamera::direction`].
    pub fn frame(&self) -> CameraFrame {
        let (right, up, forward) = self.basis();
        let (tan_v, tan_h) = self.tan_half();
        CameraFrame {
            camera: *self,
            right,
            up,
            forward,
            tan_v,
            tan_h,
        }
    }

    /// Unit world direction through the centre of pixel (`x`, `y`), rows
    /// from the top.
    pub fn direction(&self, x: u32, y: u32) -> [f64; 3] {
        self.frame().direction(x, y)
    }

    /// Pixel (`x`, `y`)'s ray in grid units; `t` is metres from the eye.
    pub fn ray(&self, field: &HeightField, x: u32, y: u32) -> GridRay {
        self.frame().ray(field, x, y)
    }
}

/// A camera with its basis and field-of-view tangents computed once.
#[derive(Clone, Copy, Debug)]
pub struct CameraFrame {
    /// The camera.
    pub camera: TerrainCamera,
    /// Right axis.
    pub right: [f64; 3],
    /// Up axis.
    pub up: [f64; 3],
    /// View direction.
    pub forward: [f64; 3],
    /// tan of half the vertical field of view.
    pub tan_v: f64,
    /// tan of half the horizontal field of view.
    pub tan_h: f64,
}

impl CameraFrame {
    /// Unit world direction through the centre of pixel (`x`, `y`).
    pub fn direction(&self, x: u32, y: u32) -> [f64; 3] {
        let (r, u, f, tv, th) = (self.right, self.up, self.forward, self.tan_v, self.tan_h);
        let c = &self.camera;
        let sx = (2.0 * (x as f64 + 0.5) / c.width as f64 - 1.0) * th;
        let sy = (1.0 - 2.0 * (y as f64 + 0.5) / c.height as f64) * tv;
        normalize([
            f[0] + r[0] * sx + u[0] * sy,
            f[1] + r[1] * sx + u[1] * sy,
            f[2] + r[2] * sx + u[2] * sy,
        ])
    }

    /// Pixel (`x`, `y`)'s ray in grid units.
    pub fn ray(&self, field: &HeightField, x: u32, y: u32) -> GridRay {
        field.grid_ray(self.camera.eye, self.direction(x, y))
    }
}

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
