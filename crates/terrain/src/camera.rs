//! A pinhole camera over a terrain and its per-frame ray basis.

use crate::heightfield::{GridRay, HeightField};

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
