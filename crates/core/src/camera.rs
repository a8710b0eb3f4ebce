//! Pinhole camera shared by the renderers and the ray-set generator.

use crate::aabb::Aabb;
use crate::ray::Ray;
use glam::Vec3;

/// The largest magnitude of a camera coordinate (eye, target, up) and of a
/// light's position where a command or the server takes them: far beyond
/// any mesh ([`crate::MAX_COORDINATE`]), and small enough that squared
/// distances (a point light's intensity is its irradiance times the squared
/// distance) stay finite in f32.
pub const MAX_CAMERA_COORDINATE: f32 = 1e18;

/// A pinhole camera: eye point, view target, up vector and vertical field of
/// view in degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye point.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Approximate up direction.
    pub up: Vec3,
    /// Vertical field of view, degrees.
    pub vfov_deg: f32,
}

impl Camera {
    /// A camera that frames `bounds`: looks at the box centre from the
    /// front-right-above (direction (1, 0.6, 1.6) relative to +z, y up), far
    /// enough that the bounding sphere fills the vertical field of view.
    pub fn framing(bounds: &Aabb, vfov_deg: f32) -> Camera {
        let center = bounds.center();
        let radius = bounds.placing_length() * 0.5;
        let dir = Vec3::new(0.55, 0.45, 1.0).normalize();
        let half = (vfov_deg.to_radians() * 0.5).max(1e-3);
        let dist = radius / half.sin() * 1.02;
        Camera {
            eye: center + dir * dist,
            target: center,
            up: Vec3::Y,
            vfov_deg,
        }
    }

    /// A camera that frames `bounds` tightly for an image of the given
    /// `aspect` (width / height): [`Camera::fit_points`] on the box corners.
    pub fn fit(bounds: &Aabb, vfov_deg: f32, aspect: f32) -> Camera {
        Camera::fit_points(bounds, &bounds.corners(), vfov_deg, aspect)
    }

    /// A camera that frames `points` (which lie in `bounds`) tightly for an
    /// image of the given `aspect` (width / height): it looks at the box
    /// centre from the same direction as [`Camera::framing`], at the smallest
    /// distance at which every point projects inside the image (with a 4%
    /// margin), so elongated objects fill the picture instead of their
    /// bounding sphere. Pass a mesh's vertices for the tightest fit.
    pub fn fit_points(bounds: &Aabb, points: &[Vec3], vfov_deg: f32, aspect: f32) -> Camera {
        let mut camera = Camera::framing(bounds, vfov_deg);
        if bounds.is_empty() || points.is_empty() {
            return camera;
        }
        let (right, up, forward) = camera.basis();
        let tan_v = (vfov_deg.to_radians() * 0.5).tan() / 1.04;
        let tan_h = tan_v * aspect.max(1e-3);
        let center = bounds.center();
        // A point at depth offset z lies at dist + z from the eye; it fits
        // when |x| <= tan_h (dist + z) and |y| <= tan_v (dist + z). The eye
        // stays outside the box: dist >= 1.05 · (largest depth offset).
        let dist = points.iter().fold(0.0f32, |dist, &p| {
            let q = p - center;
            let (x, y, z) = (q.dot(right), q.dot(up), q.dot(forward));
            dist.max(x.abs() / tan_h - z).max(y.abs() / tan_v - z)
        });
        let depth = (bounds.extent() * 0.5).dot(forward.abs());
        let dist = dist.max(depth * 1.05);
        if dist > 0.0 && dist.is_finite() {
            camera.eye = center - forward * dist;
        }
        camera
    }

    /// Orthonormal basis (right, up, forward).
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        // A camera nanometres from its target or closer is still pointed.
        let forward = crate::ray::unit_direction(self.target - self.eye);
        let mut right = forward.cross(self.up);
        if right.length_squared() < 1e-12 {
            right = forward.cross(Vec3::X);
        }
        let right = right.normalize();
        let up = right.cross(forward);
        (right, up, forward)
    }

    /// A generator for the primary rays of a `width` × `height` image.
    pub fn rays(&self, width: u32, height: u32) -> PrimaryRays {
        let (right, up, forward) = self.basis();
        let h = (self.vfov_deg.to_radians() * 0.5).tan();
        let aspect = width as f32 / height.max(1) as f32;
        PrimaryRays {
            eye: self.eye,
            forward,
            right: right * h * aspect,
            up: up * h,
            width,
            height,
        }
    }
}

/// Precomputed camera frame for generating primary rays.
#[derive(Clone, Copy, Debug)]
pub struct PrimaryRays {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    width: u32,
    height: u32,
}

impl PrimaryRays {
    /// The ray through image position (`x`, `y`) in pixels, (0, 0) the
    /// top-left corner of the image; pixel centres are at half-integers.
    /// The direction is unit length.
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let sx = 2.0 * x / self.width as f32 - 1.0;
        let sy = 1.0 - 2.0 * y / self.height as f32;
        let d = (self.forward + self.right * sx + self.up * sy).normalize();
        Ray::new(self.eye, d)
    }

    /// The ray through the centre of pixel (`px`, `py`).
    #[inline]
    pub fn pixel(&self, px: u32, py: u32) -> Ray {
        self.ray(px as f32 + 0.5, py as f32 + 0.5)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_keeps_every_corner_inside_and_touches_the_border() {
        let boxes = [
            Aabb::new(Vec3::new(-1.0, -0.2, -3.0), Vec3::new(2.0, 0.5, 4.0)),
            Aabb::new(Vec3::splat(10.0), Vec3::new(10.1, 13.0, 10.2)),
            Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0)),
            // Nanometres across in metres, and far smaller.
            Aabb::new(Vec3::splat(1e-12), Vec3::new(3e-12, 2e-12, 1.5e-12)),
            Aabb::new(Vec3::splat(-1e-30), Vec3::new(2e-30, 1e-30, 1e-30)),
        ];
        for b in boxes {
            for aspect in [0.5f32, 1.0, 16.0 / 9.0] {
                let (w, h) = ((400.0 * aspect) as u32, 400);
                let cam = Camera::fit(&b, 40.0, w as f32 / h as f32);
                let (right, up, forward) = cam.basis();
                let tan_v = (20f32).to_radians().tan();
                let tan_h = tan_v * w as f32 / h as f32;
                let mut most = 0.0f32;
                for i in 0..8 {
                    let p = Vec3::new(
                        if i & 1 == 0 { b.min.x } else { b.max.x },
                        if i & 2 == 0 { b.min.y } else { b.max.y },
                        if i & 4 == 0 { b.min.z } else { b.max.z },
                    ) - cam.eye;
                    let depth = p.dot(forward);
                    assert!(depth > 0.0, "corner behind the eye");
                    let sx = p.dot(right) / depth / tan_h;
                    let sy = p.dot(up) / depth / tan_v;
                    assert!(
                        sx.abs() <= 1.0 && sy.abs() <= 1.0,
                        "{b:?} {aspect}: corner at {sx}, {sy}"
                    );
                    most = most.max(sx.abs()).max(sy.abs());
                }
                // The box is not lost in the middle of the frame.
                assert!(
                    most > 0.9,
                    "{b:?} {aspect}: the box reaches only {most} of the frame"
                );
            }
        }
    }
}
