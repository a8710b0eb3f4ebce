//! Fitting the light views: orthographic for directional lights,
//! perspective for spots, six cube faces for point lights.

use crate::raster::RasterView;
use raykit_core::{Aabb, Vec3};

/// Largest spot half-angle served by one perspective map; wider cones get
/// a cube map.
pub(crate) const MAX_SPOT_HALF_ANGLE_DEG: f32 = 60.0;

/// Texels kept free at each border for the filter taps: a point inside the
/// covered region never has a tap outside the map.
pub(crate) fn border(pcf: u32) -> u32 {
    pcf / 2 + 2
}

/// A unit vector perpendicular to `d`.
fn perpendicular(d: Vec3) -> Vec3 {
    let a = if d.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    d.cross(a).normalize_or_zero()
}

/// A square perspective view from `eye` along unit `forward`, covering
/// `tan(half-angle) <= half_tan` inside its `res - 2·border` central texels.
pub(crate) fn perspective(
    eye: Vec3,
    forward: Vec3,
    up_hint: Vec3,
    half_tan: f32,
    res: u32,
    border: u32,
) -> RasterView {
    let mut right = forward.cross(up_hint);
    if right.length_squared() < 1e-12 {
        right = perpendicular(forward);
    }
    let right = right.normalize_or_zero();
    let up = right.cross(forward);
    let inner = (res.saturating_sub(2 * border)).max(1) as f32;
    let e = half_tan * res as f32 / inner;
    RasterView::Perspective {
        eye,
        d0: forward - right * e + up * e,
        dx: right * (2.0 * e / res as f32),
        dy: up * (-2.0 * e / res as f32),
    }
}

/// The six 90° faces of a cube map around `eye` (+x, -x, +y, -y, +z, -z),
/// widened by the border.
pub(crate) fn cube(eye: Vec3, res: u32, border: u32) -> [RasterView; 6] {
    const FACES: [(Vec3, Vec3); 6] = [
        (Vec3::X, Vec3::Y),
        (Vec3::NEG_X, Vec3::Y),
        (Vec3::Y, Vec3::Z),
        (Vec3::NEG_Y, Vec3::Z),
        (Vec3::Z, Vec3::Y),
        (Vec3::NEG_Z, Vec3::Y),
    ];
    FACES.map(|(f, u)| perspective(eye, f, u, 1.0, res, border))
}

/// The cube face (index into [`cube`]'s order) that direction `d` falls in.
pub(crate) fn cube_face(d: Vec3) -> usize {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        if d.x >= 0.0 {
            0
        } else {
            1
        }
    } else if a.y >= a.z {
        if d.y >= 0.0 {
            2
        } else {
            3
        }
    } else if d.z >= 0.0 {
        4
    } else {
        5
    }
}

/// An orthographic view along unit `dir` covering `bounds` (with the
/// border), its origins on a plane before the box.
pub(crate) fn orthographic(dir: Vec3, bounds: &Aabb, res: u32, border: u32) -> RasterView {
    let right = perpendicular(dir);
    let up = right.cross(dir);
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for c in bounds.corners() {
        let q = Vec3::new(c.dot(right), c.dot(up), c.dot(dir));
        lo = lo.min(q);
        hi = hi.max(q);
    }
    let diag = bounds.placing_length();
    let side = (hi.x - lo.x).max(hi.y - lo.y).max(1e-6 * diag) * 1.01;
    let inner = (res.saturating_sub(2 * border)).max(1) as f32;
    let full = side * res as f32 / inner;
    let (cu, cv) = ((lo.x + hi.x) * 0.5, (lo.y + hi.y) * 0.5);
    let texel = full / res as f32;
    RasterView::Orthographic {
        dir,
        o0: right * (cu - full * 0.5) + up * (cv + full * 0.5) + dir * (lo.z - 0.01 * diag),
        ox: right * texel,
        oy: up * -texel,
    }
}
