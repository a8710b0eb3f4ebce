//! Pinhole camera shared by the renderers and the ray-set generator.

use crate::aabb::Aabb;
use crate::ray::Ray;
use glam::Vec3;

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
        let radius = (bounds.diagonal() * 0.5).max(1e-6);
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

    /// Orthonormal basis (right, up, forward).
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let forward = (self.target - self.eye).normalize();
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
