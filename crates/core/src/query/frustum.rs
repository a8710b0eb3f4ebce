//! Planes and view frustums in f64, for frustum culling as in Kim 2013.

use crate::camera::Camera;
use glam::DVec3;

/// An oriented plane `normal · x + offset = 0`; its inside is the closed
/// half-space `normal · x + offset >= 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// Normal, pointing into the inside (need not be unit length).
    pub normal: DVec3,
    /// Offset: the signed distance of the origin times `|normal|`.
    pub offset: f64,
}

impl Plane {
    /// The plane `normal · x + offset = 0`.
    pub fn new(normal: DVec3, offset: f64) -> Self {
        Plane { normal, offset }
    }

    /// The plane through `point` whose inside lies towards `normal`.
    pub fn through(point: DVec3, normal: DVec3) -> Self {
        Plane {
            normal,
            offset: -normal.dot(point),
        }
    }

    /// `normal · p + offset`: positive inside, zero on the plane; the signed
    /// distance when the normal is unit length.
    #[inline]
    pub fn distance(&self, p: DVec3) -> f64 {
        self.normal.dot(p) + self.offset
    }
}

/// A view frustum: the convex region inside six planes (near, far, left,
/// right, bottom, top), the volume a game tests its objects against to cull
/// those that cannot be seen (frustum culling on kd-trees, Kim 2013).
///
/// Any six planes are accepted ([`Frustum::from_planes`]); the queries only
/// use the intersection of their insides, so the region may also be
/// unbounded or empty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    planes: [Plane; 6],
}

impl Frustum {
    /// The frustum bounded by six planes, inside towards their normals.
    pub fn from_planes(planes: [Plane; 6]) -> Self {
        Frustum { planes }
    }

    /// The frustum seen by `camera` for an image of the given `aspect`
    /// (width / height) between the distances `near` and `far` along the
    /// view direction: the volume [`Camera::rays`] samples, cut at both
    /// depths. Planes in the order near, far, left, right, bottom, top, with
    /// unit normals.
    pub fn from_camera(camera: &Camera, aspect: f32, near: f32, far: f32) -> Self {
        let (right, up, forward) = camera.basis();
        let (right, up, forward) = (right.as_dvec3(), up.as_dvec3(), forward.as_dvec3());
        let eye = camera.eye.as_dvec3();
        let tan_v = ((camera.vfov_deg as f64).to_radians() * 0.5).tan();
        let tan_h = tan_v * aspect as f64;
        // A side plane through the eye contains the image border's rays:
        // e.g. the left one holds forward - tan_h · right and the up axis.
        let side = |n: DVec3| Plane::through(eye, n.normalize_or_zero());
        Frustum {
            planes: [
                Plane::through(eye + forward * near as f64, forward),
                Plane::through(eye + forward * far as f64, -forward),
                side(right + forward * tan_h),
                side(-right + forward * tan_h),
                side(up + forward * tan_v),
                side(-up + forward * tan_v),
            ],
        }
    }

    /// The six planes.
    pub fn planes(&self) -> &[Plane; 6] {
        &self.planes
    }

    /// True when `p` lies inside or on the boundary.
    pub fn contains(&self, p: DVec3) -> bool {
        self.planes.iter().all(|pl| pl.distance(p) >= 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn camera_frustum_contains_exactly_the_image_rays_between_near_and_far() {
        let cam = Camera {
            eye: Vec3::new(1.0, 2.0, 3.0),
            target: Vec3::new(0.0, 0.5, -1.0),
            up: Vec3::Y,
            vfov_deg: 50.0,
        };
        let (w, h) = (64u32, 32u32);
        let f = Frustum::from_camera(&cam, w as f32 / h as f32, 0.5, 10.0);
        let rays = cam.rays(w, h);
        let forward = (cam.target - cam.eye).normalize().as_dvec3();
        for (x, y) in [(0.5, 0.5), (32.0, 16.0), (63.5, 31.5), (10.0, 30.0)] {
            let r = rays.ray(x, y);
            let d = r.dir.as_dvec3();
            let o = r.origin.as_dvec3();
            let cos = d.dot(forward);
            // Inside between the depths 0.5 and 10, outside before and after.
            assert!(f.contains(o + d * (0.6 / cos)));
            assert!(f.contains(o + d * (9.9 / cos)));
            assert!(!f.contains(o + d * (0.4 / cos)));
            assert!(!f.contains(o + d * (10.1 / cos)));
        }
        // Beyond the image border (x = -1 pixel, y = h + 1) is outside.
        for (x, y) in [(-1.0, 10.0), (65.0, 10.0), (10.0, -1.0), (10.0, 33.0)] {
            let r = rays.ray(x, y);
            let p = r.origin.as_dvec3() + r.dir.as_dvec3() * 5.0;
            assert!(!f.contains(p), "({x}, {y}) should be outside");
        }
    }
}
