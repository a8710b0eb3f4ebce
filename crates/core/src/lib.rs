//! raykit core: rays, axis-aligned boxes, indexed triangle meshes, the three
//! ray/triangle tests and the acceleration structures that are generic over them.
//!
//! The triangle tests are Möller–Trumbore (1997), the Plücker test (Jones 2000)
//! and Wald's projection (Wald 2004); the structures include the binned-SAH BVH
//! (Wald 2007), the threaded (escape-index) BVH (Smits 1998) and kd-trees
//! traversed with a per-ray stack, ropes (Popov et al. 2007) or restart and
//! backtrack (Foley & Sugerman 2005). [`instancing`] puts several meshes and
//! their instances under a two-level BVH (Wald et al. 2014).

pub mod aabb;
pub mod accel;
pub mod camera;
pub mod hit;
pub mod icosphere;
pub mod instancing;
pub mod light;
pub mod mesh;
pub mod query;
pub mod ray;
pub mod raysets;
pub mod rng;
pub mod texture;
pub mod tjunction;
pub mod tri;

pub use aabb::Aabb;
pub use accel::{Accel, AccelStats};
pub use camera::Camera;
pub use glam;
pub use glam::{Vec2, Vec3, Vec3A};
pub use hit::Hit;
pub use icosphere::Icosphere;
pub use light::{Light, LightSample, PointLight};
pub use mesh::{Material, MeshError, Part, TriangleMesh};
pub use ray::Ray;
pub use texture::Texture;
pub use tri::TriangleTest;
