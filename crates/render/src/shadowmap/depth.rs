//! One depth map: a view from the light and the distance to the nearest
//! surface along the ray of every texel.

use crate::raster::{rasterize, RasterView};
use raykit_core::tri::TestKind;
use raykit_core::{TriangleMesh, Vec3};

/// A square depth map rendered by the rasterizer: per texel the distance
/// along the texel-centre ray of `view` to the nearest triangle (`+inf`
/// where none).
pub(crate) struct DepthMap {
    pub view: RasterView,
    pub res: u32,
    pub depth: Vec<f32>,
}

impl DepthMap {
    /// Render `mesh` from `view` at `res` × `res` texels.
    pub fn render(mesh: &TriangleMesh, view: RasterView, res: u32) -> DepthMap {
        let hits = rasterize(mesh, TestKind::Moller, &view, res, res, &|x, y| {
            view.pixel(x, y)
        });
        let depth = hits
            .iter()
            .map(|h| h.map_or(f32::INFINITY, |h| h.t))
            .collect();
        DepthMap { view, res, depth }
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.depth.len() * std::mem::size_of::<f32>() + std::mem::size_of::<Self>()
    }

    /// Fraction of the `pcf × pcf` taps around `p` that see `p`'s surface
    /// (the plane through `p` with unit normal `n`, or `p` itself where `n`
    /// is unusable) no farther than their stored depth plus `bias`. Taps
    /// outside the map count as lit. `None` when `p` does not project into
    /// the view.
    pub fn lit_fraction(&self, p: Vec3, n: Vec3, pcf: u32, bias: f32) -> Option<f32> {
        let (x, y, _) = self.view.project(p)?;
        let own = self.distance(p);
        let half = pcf as f32 * 0.5;
        let (bx, by) = ((x - half + 0.5).floor(), (y - half + 0.5).floor());
        if !(bx.abs() < 1e9 && by.abs() < 1e9) {
            return None;
        }
        let (bx, by) = (bx as i64, by as i64);
        let res = self.res as i64;
        let mut lit = 0u32;
        for j in 0..pcf as i64 {
            for i in 0..pcf as i64 {
                let (tx, ty) = (bx + i, by + j);
                if tx < 0 || ty < 0 || tx >= res || ty >= res {
                    lit += 1;
                    continue;
                }
                let stored = self.depth[(ty * res + tx) as usize];
                if stored == f32::INFINITY {
                    lit += 1;
                    continue;
                }
                // The receiver's distance along this tap's ray: where the
                // ray meets the plane of the surface at `p` (exact for
                // planar receivers), or `p`'s own distance for grazing rays.
                let ray = self.view.pixel(tx as u32, ty as u32);
                let cos = ray.dir().dot(n);
                let mut receiver = own;
                if cos.abs() > 0.05 {
                    let t = (p - ray.origin).dot(n) / cos;
                    if t.is_finite() && t > 0.0 {
                        receiver = t;
                    }
                }
                lit += (stored >= receiver - bias) as u32;
            }
        }
        Some(lit as f32 / (pcf * pcf) as f32)
    }

    /// Distance of `p` along its own ray of the view.
    pub fn distance(&self, p: Vec3) -> f32 {
        match self.view {
            RasterView::Perspective { eye, .. } => (p - eye).length(),
            RasterView::Orthographic { dir, o0, .. } => (p - o0).dot(dir),
        }
    }

    /// World size of a texel at `p`.
    pub fn texel_size(&self, p: Vec3) -> f32 {
        match self.view {
            RasterView::Perspective { dx, d0, .. } => {
                self.distance(p) * dx.length() / d0.length().max(f32::MIN_POSITIVE)
            }
            RasterView::Orthographic { ox, .. } => ox.length(),
        }
    }
}
