//! An `f64` reference ray/triangle intersection, the yardstick that the three
//! `f32` tests of this module ([`Moller`](super::Moller),
//! [`Plucker`](super::Plucker), [`Projection`](super::Projection)) are checked
//! against in `tests/triangle_tests.rs` and by the acceleration-structure tests.
//!
//! The inputs are the `f32` corners and ray widened to `f64`, so the reference
//! answers the question "what would exact arithmetic say about these `f32`
//! inputs" up to `f64` rounding (about `1e-16` relative to the coordinates).
//! It uses the Plücker form (Jones 2000) in the ray's own frame: the corners
//! are translated by the ray origin first, so its error does not grow with the
//! distance of the scene from the world origin, and the three per-edge values
//! are the signed volumes `dir · (p × q)` of the translated corners.

use glam::DVec3;

/// Two-sided `f64` ray/triangle intersection (the reference for the `f32`
/// triangle tests).
///
/// Returns `(t, u, v)` with `t >= 0` the distance along `dir` (in units of
/// `dir`, which need not be unit length) and `(u, v)` the barycentric weights
/// of `b` and `c`, when the ray `origin + t * dir` meets the closed triangle
/// `a, b, c` (edges and corners included, either face). Returns `None` for a
/// miss, for a degenerate (zero-area) triangle, for a direction parallel to the
/// triangle's plane (including rays lying in it) and for non-finite input.
pub fn intersect_f64(
    a: DVec3,
    b: DVec3,
    c: DVec3,
    origin: DVec3,
    dir: DVec3,
) -> Option<(f64, f64, f64)> {
    let n = (b - a).cross(c - a);
    let den = n.dot(dir);
    if n == DVec3::ZERO || den == 0.0 || !den.is_finite() {
        return None;
    }
    let (pa, pb, pc) = (a - origin, b - origin, c - origin);
    // Signed volumes: each is proportional to the barycentric weight of the
    // corner opposite its edge.
    let wa = dir.dot(pb.cross(pc));
    let wb = dir.dot(pc.cross(pa));
    let wc = dir.dot(pa.cross(pb));
    let inside = (wa >= 0.0 && wb >= 0.0 && wc >= 0.0) || (wa <= 0.0 && wb <= 0.0 && wc <= 0.0);
    let sum = wa + wb + wc;
    if !inside || sum == 0.0 {
        return None;
    }
    let t = n.dot(pa) / den;
    if !(t >= 0.0 && t.is_finite()) {
        return None;
    }
    Some((t, wb / sum, wc / sum))
}

/// Distance `t` (any sign) at which the line `origin + t * dir` meets the plane
/// of the triangle `a, b, c`, in `f64`; `None` for a degenerate triangle or a
/// direction parallel to the plane.
pub fn plane_t_f64(a: DVec3, b: DVec3, c: DVec3, origin: DVec3, dir: DVec3) -> Option<f64> {
    let n = (b - a).cross(c - a);
    let den = n.dot(dir);
    if n == DVec3::ZERO || den == 0.0 {
        return None;
    }
    let t = n.dot(a - origin) / den;
    t.is_finite().then_some(t)
}

/// Distance from `p` to the nearest point of the triangle's boundary (its three
/// edge segments), divided by the triangle's size (its longest edge), in `f64`.
///
/// For `p` in the triangle's plane (e.g. the hit point of
/// [`intersect_f64`] or the plane point of [`plane_t_f64`]), this tells a
/// point clearly inside or outside (large value) from one on the boundary
/// within rounding (value near 0). Returns `+inf` for a triangle of size 0.
pub fn edge_distance_f64(a: DVec3, b: DVec3, c: DVec3, p: DVec3) -> f64 {
    fn seg(p: DVec3, q: DVec3, x: DVec3) -> f64 {
        let e = q - p;
        let len2 = e.length_squared();
        let s = if len2 > 0.0 {
            ((x - p).dot(e) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (x - (p + e * s)).length()
    }
    let size = (b - a).length().max((c - b).length()).max((a - c).length());
    if size.is_nan() || size <= 0.0 {
        return f64::INFINITY;
    }
    seg(a, b, p).min(seg(b, c, p)).min(seg(c, a, p)) / size
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_triangle() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        let o = DVec3::new(0.25, 0.5, 1.0);
        let (t, u, v) = intersect_f64(a, b, c, o, DVec3::NEG_Z * 2.0).unwrap();
        assert!((t - 0.5).abs() < 1e-15 && (u - 0.25).abs() < 1e-15 && (v - 0.5).abs() < 1e-15);
        // Back face, edge and corner are hits; outside, behind, parallel and
        // degenerate are not.
        assert!(intersect_f64(a, b, c, DVec3::new(0.25, 0.5, -1.0), DVec3::Z).is_some());
        assert!(intersect_f64(a, b, c, DVec3::new(0.5, 0.0, 1.0), DVec3::NEG_Z).is_some());
        assert!(intersect_f64(a, b, c, DVec3::new(1.0, 0.0, 1.0), DVec3::NEG_Z).is_some());
        assert!(intersect_f64(a, b, c, DVec3::new(0.6, 0.6, 1.0), DVec3::NEG_Z).is_none());
        assert!(intersect_f64(a, b, c, o, DVec3::Z).is_none());
        assert!(intersect_f64(a, b, c, DVec3::new(-1.0, 0.2, 0.0), DVec3::X).is_none());
        assert!(intersect_f64(a, b, b, o, DVec3::NEG_Z).is_none());
        assert!(
            (edge_distance_f64(a, b, c, DVec3::new(0.25, 0.25, 0.0)) - 0.25 / 2f64.sqrt()).abs()
                < 1e-15
        );
    }
}
