//! The answer of a ray query on an instanced scene.

use glam::Vec3;

/// A hit in an instanced scene: distance `t` along the world ray,
/// barycentric `(u, v)` of the hit point in the triangle (as [`crate::Hit`];
/// an affine map keeps them), the triangle's index in its geometry's mesh,
/// the geometry and instance ids, and the geometric normal in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneHit {
    /// Distance along the ray, in units of the ray direction.
    pub t: f32,
    /// Barycentric weight of the triangle's second vertex.
    pub u: f32,
    /// Barycentric weight of the triangle's third vertex.
    pub v: f32,
    /// Triangle index in the geometry's mesh.
    pub prim: u32,
    /// The geometry hit.
    pub geometry: u32,
    /// The instance hit.
    pub instance: u32,
    /// Unit geometric normal in world space of the triangle's front (the
    /// side from which its corners run counter-clockwise in object space,
    /// `e1 × e2` with `e1 = v1 - v0`, `e2 = v2 - v0`), whichever side the
    /// ray came from; a mirroring instance keeps the front (see
    /// [`super::InstanceTransform::world_normal`]).
    pub normal: Vec3,
}

impl SceneHit {
    /// True when the ray meets the triangle's back (the side its normal
    /// points away from), for a ray with direction `dir`.
    pub fn is_back_face(&self, dir: Vec3) -> bool {
        self.normal.dot(dir) > 0.0
    }
}
