//! the quadtree-box caster's per-frame box subdivision: traverse the quadtree of the
//! maximum mipmap once per frame, refining a node while its projected
//! footprint covers at least 4 τ² pixels and dropping nodes wholly outside
//! the view frustum; each surviving node becomes a box from its lowest to
//! its highest surface point; "rasterizing" the boxes gives every pixel the
//! nearest box entry along its ray, where the march starts.
//!
//! Exact for the declared surface: the boxes of the surviving nodes cover
//! every surface point inside the frustum, so no ray meets the surface
//! before the nearest box entry on it.

use crate::camera::{dot, CameraFrame, TerrainCamera};
use crate::heightfield::{slab, HeightField};
use crate::pyramid::MaxMipmap;
use rayon::prelude::*;

/// A surviving quadtree node as a box in grid units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeBox {
    /// Pyramid level (0 = one cell).
    pub level: u8,
    /// Lower corner (column, row, height).
    pub lo: [f64; 3],
    /// Upper corner.
    pub hi: [f64; 3],
    /// Pixel rectangle it may cover: x0, y0, x1, y1 (inclusive-exclusive).
    pub rect: [u32; 4],
}

/// Screen rectangle of a box and whether it is visible at all: `None` when
/// the box lies wholly outside one frustum plane. A box reaching behind the
/// eye covers the whole screen (conservative).
fn project(
    field: &HeightField,
    frame: &CameraFrame,
    lo: [f64; 3],
    hi: [f64; 3],
) -> Option<[u32; 4]> {
    let cam = &frame.camera;
    let (r, u, f) = (frame.right, frame.up, frame.forward);
    let (tv, th) = (frame.tan_v, frame.tan_h);
    let mut outside = [true; 5]; // left, right, bottom, top, behind
    let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
    let mut behind = false;
    for k in 0..8 {
        let g = [
            if k & 1 == 0 { lo[0] } else { hi[0] },
            if k & 2 == 0 { lo[1] } else { hi[1] },
            if k & 4 == 0 { lo[2] } else { hi[2] },
        ];
        let w = [
            g[0] * field.sx - cam.eye[0],
            -g[1] * field.sy - cam.eye[1],
            g[2] - cam.eye[2],
        ];
        let (cx, cy, cz) = (dot(w, r), dot(w, u), dot(w, f));
        outside[0] &= cx < -cz * th;
        outside[1] &= cx > cz * th;
        outside[2] &= cy < -cz * tv;
        outside[3] &= cy > cz * tv;
        outside[4] &= cz <= 0.0;
        if cz <= 1e-9 {
            behind = true;
            continue;
        }
        let (sx, sy) = (cx / (cz * th), cy / (cz * tv));
        x0 = x0.min(sx);
        x1 = x1.max(sx);
        y0 = y0.min(sy);
        y1 = y1.max(sy);
    }
    if outside.iter().any(|&o| o) {
        return None;
    }
    let (w, h) = (cam.width as f64, cam.height as f64);
    if behind {
        return Some([0, 0, cam.width, cam.height]);
    }
    // Normalised device x in [-1, 1] → pixels; y up → rows down. One pixel
    // of margin keeps pixel centres on the edge inside.
    let px = |s: f64| ((s + 1.0) * 0.5 * w).clamp(0.0, w);
    let py = |s: f64| ((1.0 - s) * 0.5 * h).clamp(0.0, h);
    let rx0 = (px(x0) - 1.0).max(0.0).floor() as u32;
    let rx1 = (px(x1) + 1.0).min(w).ceil() as u32;
    let ry0 = (py(y1) - 1.0).max(0.0).floor() as u32;
    let ry1 = (py(y0) + 1.0).min(h).ceil() as u32;
    // Corners whose projections are not finite (heights or a camera beyond
    // f64's range) give no rectangle rather than an inverted one.
    (rx0 < rx1 && ry0 < ry1).then_some([rx0, ry0, rx1, ry1])
}

/// The frame's boxes: the quadtree traversed once from the root with
/// view-distance LOD (refine while the footprint is at least 4 τ² pixels)
/// and frustum culling.
pub fn select_boxes(
    field: &HeightField,
    pyramid: &MaxMipmap,
    cam: &TerrainCamera,
    tau: f64,
) -> Vec<NodeBox> {
    let frame = cam.frame();
    let mut out = Vec::new();
    let mut stack = vec![(pyramid.top(), 0usize, 0usize)];
    let threshold = 4.0 * tau * tau;
    while let Some((level, i, j)) = stack.pop() {
        let lv = &pyramid.levels[level];
        let (x0, x1, y0, y1) = pyramid.extent(level, i, j);
        let lo = [x0 as f64, y0 as f64, lv.min(j * lv.width + i) as f64];
        let hi = [x1 as f64, y1 as f64, lv.max(j * lv.width + i) as f64];
        let Some(rect) = project(field, &frame, lo, hi) else {
            continue;
        };
        let area = (rect[2] - rect[0]) as f64 * (rect[3] - rect[1]) as f64;
        if level > 0 && area >= threshold {
            for (ci, cj) in pyramid.levels[level - 1].children(i, j) {
                stack.push((level - 1, ci, cj));
            }
        } else {
            out.push(NodeBox {
                level: level as u8,
                lo,
                hi,
                rect,
            });
        }
    }
    out
}

/// For every pixel, the nearest entry of its ray into any box (`t`, or
/// infinity when it meets none) and the number of boxes tested: the CPU
/// stand-in for the quadtree-box caster's rasterization of the boxes with a depth test.
pub fn pixel_starts(
    field: &HeightField,
    cam: &TerrainCamera,
    boxes: &[NodeBox],
) -> Vec<(f64, u32)> {
    let (w, h) = (cam.width as usize, cam.height as usize);
    // Boxes by the rows they may cover.
    let mut rows: Vec<Vec<u32>> = vec![Vec::new(); h];
    for (k, b) in boxes.iter().enumerate() {
        for row in &mut rows[b.rect[1] as usize..b.rect[3] as usize] {
            row.push(k as u32);
        }
    }
    let frame = cam.frame();
    let mut out = vec![(f64::INFINITY, 0u32); w * h];
    out.par_chunks_mut(w).enumerate().for_each(|(y, line)| {
        for &k in &rows[y] {
            let b = &boxes[k as usize];
            for x in b.rect[0]..b.rect[2] {
                let ray = frame.ray(field, x, y as u32);
                let cell = &mut line[x as usize];
                cell.1 += 1;
                if let Some((t0, _)) = slab(&ray, b.lo, b.hi, 0.0, cell.0) {
                    cell.0 = cell.0.min(t0);
                }
            }
        }
    });
    out
}
