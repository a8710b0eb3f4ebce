//! raykit core: rays, axis-aligned boxes, indexed triangle meshes, the three
//! ray/triangle tests and the acceleration structures that are generic over them.
//!
//! The layout follows the papers summarised in `PAPERS.md`: the triangle tests
//! of paper 000 (Plücker coordinates, Wald's projection) and paper 001
//! (Möller–Trumbore), the binned-SAH BVH and the threaded (escape-index) BVH
//! of paper 001.

pub mod aabb;
pub mod accel;
pub mod camera;
pub mod hit;
pub mod icosphere;
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
