//! The family of rays a raster image samples: one ray per image position,
//! from a common eye (perspective) or in a common direction (orthographic).

use raykit_core::glam::DVec3;
use raykit_core::{Camera, Ray, Vec3};

/// How image positions map to rays (the Purcell-style stream tracer's hybrid renderer: the raster
/// projection must equal the ray camera's). Image positions `(x, y)` are in
/// pixels, `(0, 0)` the top-left corner, pixel centres at half-integers.
///
/// Both kinds are affine in `(x, y)`: a perspective view has a fixed eye and
/// directions `d0 + x·dx + y·dy`; an orthographic view a fixed direction and
/// origins `o0 + x·ox + y·oy`. The axes must be orthogonal (`dx ⟂ dy`, and
/// for orthographic views `ox ⟂ oy ⟂ dir`), as [`RasterView::camera`] and the
/// shadow maps build them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RasterView {
    /// Rays from `eye` in direction `d0 + x·dx + y·dy` (normalised).
    Perspective {
        /// Common origin.
        eye: Vec3,
        /// Direction at image position (0, 0), before normalisation.
        d0: Vec3,
        /// Change of the direction per pixel to the right.
        dx: Vec3,
        /// Change of the direction per pixel down.
        dy: Vec3,
    },
    /// Rays from `o0 + x·ox + y·oy` in the unit direction `dir`.
    Orthographic {
        /// Common unit direction.
        dir: Vec3,
        /// Origin at image position (0, 0).
        o0: Vec3,
        /// Change of the origin per pixel to the right.
        ox: Vec3,
        /// Change of the origin per pixel down.
        oy: Vec3,
    },
}

impl RasterView {
    /// The view of `camera` for a `width` × `height` image: exactly the
    /// mapping of [`Camera::rays`] (`PrimaryRays::ray`), so the rasterizer
    /// of the Purcell-style stream tracer's hybrid renderer sees what the ray caster sees.
    pub fn camera(camera: &Camera, width: u32, height: u32) -> RasterView {
        let (right, up, forward) = camera.basis();
        let h = (camera.vfov_deg.to_radians() * 0.5).tan();
        let aspect = width as f32 / height.max(1) as f32;
        let (r, u) = (right * h * aspect, up * h);
        RasterView::Perspective {
            eye: camera.eye,
            d0: forward - r + u,
            dx: r * (2.0 / width.max(1) as f32),
            dy: u * (-2.0 / height.max(1) as f32),
        }
    }

    /// The ray through image position (`x`, `y`), unit direction, over
    /// `[0, +inf)`.
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        match *self {
            RasterView::Perspective { eye, d0, dx, dy } => {
                Ray::new(eye, (d0 + dx * x + dy * y).normalize_or_zero())
            }
            RasterView::Orthographic { dir, o0, ox, oy } => Ray::new(o0 + ox * x + oy * y, dir),
        }
    }

    /// The ray through the centre of pixel (`px`, `py`).
    #[inline]
    pub fn pixel(&self, px: u32, py: u32) -> Ray {
        self.ray(px as f32 + 0.5, py as f32 + 0.5)
    }

    /// Image position of `p` and its depth along the view (for perspective
    /// views the multiple of the direction `d(x, y)`, positive in front of
    /// the eye; for orthographic views the distance along `dir`). `None`
    /// when `p` lies on or behind the eye plane of a perspective view or the
    /// result is not finite.
    pub fn project(&self, p: Vec3) -> Option<(f32, f32, f32)> {
        let (x, y, depth) = self.project_f64(p.as_dvec3())?;
        let out = (x as f32, y as f32, depth as f32);
        (out.0.is_finite() && out.1.is_finite() && out.2.is_finite()).then_some(out)
    }

    /// [`RasterView::project`] in `f64`, without the range check.
    pub(crate) fn project_f64(&self, p: DVec3) -> Option<(f64, f64, f64)> {
        match *self {
            RasterView::Perspective { eye, d0, dx, dy } => {
                let (d0, dx, dy) = (d0.as_dvec3(), dx.as_dvec3(), dy.as_dvec3());
                let n = dx.cross(dy);
                let q = p - eye.as_dvec3();
                let (qn, dn) = (q.dot(n), d0.dot(n));
                let z = qn / dn;
                if z.is_nan() || z <= 0.0 {
                    return None;
                }
                let w = q / z - d0;
                Some((
                    w.dot(dx) / dx.length_squared(),
                    w.dot(dy) / dy.length_squared(),
                    z,
                ))
            }
            RasterView::Orthographic { dir, o0, ox, oy } => {
                let (ox, oy) = (ox.as_dvec3(), oy.as_dvec3());
                let w = p - o0.as_dvec3();
                Some((
                    w.dot(ox) / ox.length_squared(),
                    w.dot(oy) / oy.length_squared(),
                    w.dot(dir.as_dvec3()),
                ))
            }
        }
    }
}
