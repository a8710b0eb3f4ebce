//! The result of a nearest-hit query.

/// A ray/triangle hit: distance `t` along the ray, barycentric coordinates
/// `(u, v)` of the hit point (the point is `(1-u-v)·v0 + u·v1 + v·v2` for the
/// triangle's vertices in mesh order) and the triangle's index in the mesh.
///
/// A miss is `None`; in hit files it is written as `t = +inf, prim = u32::MAX`.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Hit {
    /// Distance along the ray, in units of the ray direction.
    pub t: f32,
    /// Barycentric weight of the second vertex.
    pub u: f32,
    /// Barycentric weight of the third vertex.
    pub v: f32,
    /// Triangle index in the mesh.
    pub prim: u32,
}
