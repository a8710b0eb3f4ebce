//! raykit core: rays, axis-aligned boxes, indexed triangle meshes, the three
//! ray/triangle tests and the acceleration structures that are generic over them.
//!
//! The triangle tests are Möller–Trumbore (1997), the Plücker test (Jones 2000)
//! and Wald's projection (Wald 2004); the structures include the binned-SAH BVH
//! (Wald 2007), the threaded (escape-index) BVH (Smits 1998) and kd-trees
//! traversed with a per-ray stack, ropes (Popov et al. 2007) or restart and
//! backtrack (Foley & Sugerman 2005). [`instancing`] puts several meshes and
//! their instances under a two-level BVH (Wald et al. 2014).
//!
//! A BVH from vertex and index arrays, one ray and a batch
//! (`examples/first_rays.rs` draws a sphere with the same calls):
//!
//! ```
//! use raykit_core::prelude::*;
//!
//! // A unit square in the plane z = 0, as two triangles.
//! let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
//! let indices = [[0, 1, 2], [0, 2, 3]];
//! let mesh = TriangleMesh::from_arrays(&positions, &indices)?;
//! let bvh = Bvh8::<Moller>::build(&mesh, &BuildOptions::balanced());
//!
//! // One ray straight down onto the upper-left triangle (y > x).
//! let ray = Ray::new(Vec3::new(0.25, 0.5, 2.0), Vec3::new(0.0, 0.0, -1.0));
//! let hit = bvh.intersect(&ray).expect("the ray meets the square");
//! assert_eq!(hit.prim, 1);
//! assert!((hit.t - 2.0).abs() < 1e-6);
//! assert!(bvh.occluded(&ray));
//!
//! // A batch of parallel rays over [-0.5, 1.5]²: all cores, coherent rays
//! // in packets. A ray hits where its (x, y) lies inside the square.
//! let (n, lo, step) = (16, -0.5f32, 2.0f32 / 16.0);
//! let rays: Vec<Ray> = (0..n * n)
//!     .map(|i| {
//!         let (x, y) = (lo + step * (i % n) as f32 + 0.01, lo + step * (i / n) as f32 + 0.01);
//!         Ray::new(Vec3::new(x, y, 1.0), Vec3::new(0.0, 0.0, -1.0))
//!     })
//!     .collect();
//! let mut hits = vec![None; rays.len()];
//! bvh.intersect_batch(&rays, &mut hits);
//! for (ray, hit) in rays.iter().zip(&hits) {
//!     let inside = (0.0..=1.0).contains(&ray.origin.x) && (0.0..=1.0).contains(&ray.origin.y);
//!     assert_eq!(hit.is_some(), inside, "{ray:?}");
//! }
//! # Ok::<(), MeshError>(())
//! ```

pub mod aabb;
pub mod accel;
pub mod camera;
pub mod hit;
pub mod icosphere;
pub mod instancing;
pub mod light;
pub mod mesh;
mod mesh_subset;
pub mod names;
pub mod prelude;
pub mod query;
pub mod ray;
pub mod raysets;
pub mod rng;
#[cfg(test)]
mod test_soup;
pub mod texture;
pub mod tjunction;
pub mod tri;
pub mod unit_scale;
pub mod verify;

pub use aabb::Aabb;
pub use accel::{Accel, AccelStats};
pub use camera::{Camera, MAX_CAMERA_COORDINATE};
pub use glam;
pub use glam::{Vec2, Vec3, Vec3A};
pub use hit::Hit;
pub use icosphere::Icosphere;
pub use light::{Light, LightSample, PointLight};
pub use mesh::{Material, MeshError, Part, TriangleMesh, MAX_COORDINATE};
pub use ray::Ray;
pub use texture::Texture;
pub use tri::TriangleTest;
pub use unit_scale::UnitScale;
