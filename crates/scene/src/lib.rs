//! raykit built-in scenes, each deterministic from a seed (every random
//! number comes from [`raykit_core::rng::Pcg32`]):
//!
//! - [`cornell()`]: a Cornell box with two boxes and a sphere, and
//!   [`whitted()`], the same box with a mirror and a glass sphere;
//! - [`shirley6()`]: after Peter Shirley's test scene 6, used in the stack kd-tree GPU tracer;
//! - [`terrain()`]: an fBm noise height field of configurable size;
//! - [`scatter()`]: many stretched, rotated icospheres in a box.
//!
//! [`builtin`] builds one from a `NAME:key=value,...` specification. Meshes
//! carry per-vertex normals (shared vertices on smooth surfaces, split ones on
//! flat faces), one material per triangle and one part per object.

#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod builder;
mod builtins;
pub mod cornell;
mod error;
pub mod noise;
pub mod scatter;
pub mod shirley6;
mod spec;
pub mod terrain;

pub use builder::{material, MeshBuilder};
pub use builtins::{description, BuiltinInfo, BUILTINS, BUILTIN_NAMES};
pub use cornell::{cornell, whitted};
pub use error::SceneError;
pub use raykit_core::Icosphere;
pub use raykit_core::{Light, LightSample, PointLight};
pub use scatter::scatter;
pub use shirley6::shirley6;
pub use spec::{builtin, DEFAULT_SEED, MAX_TRIANGLES};
pub use terrain::terrain;

use raykit_core::{Camera, TriangleMesh};

/// A scene: a mesh with materials, point lights and an optional camera.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Short name (the built-in name, or a file name).
    pub name: String,
    /// All geometry, with normals, materials and parts.
    pub mesh: TriangleMesh,
    /// Lights (point, spot, directional).
    pub lights: Vec<Light>,
    /// The scene's own camera, if it has one.
    pub camera: Option<Camera>,
}

impl Scene {
    /// The scene's camera, or one framing the mesh bounds
    /// ([`Camera::framing`]) with vertical field of view `vfov_deg`.
    pub fn camera_or_framing(&self, vfov_deg: f32) -> Camera {
        self.camera
            .unwrap_or_else(|| Camera::framing(&self.mesh.bounds(), vfov_deg))
    }
}
