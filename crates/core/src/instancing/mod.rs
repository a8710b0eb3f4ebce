//! Instanced scenes: several geometries (triangle meshes, each stored once
//! with its own BVH) placed by instances (a geometry and an affine
//! transform) under a two-level BVH, Embree's design (Wald et al. 2014,
//! "Embree: a kernel framework for efficient CPU ray tracing"; pbrt-v4's
//! `TransformedPrimitive` under a BVH over instances).
//!
//! - [`transform`]: [`InstanceTransform`], a checked affine map with its
//!   inverse (rays into object space) and normal matrix; a transform that
//!   is not finite or not invertible is refused.
//! - [`geometry`]: [`Geometry`], a mesh with its bottom-level
//!   [`crate::accel::Bvh8`] (and, for multi-hit queries, a
//!   [`crate::query::SurfaceBvh`]).
//! - [`instance`]: [`Instance`], a geometry placed in the world.
//! - `top_level`: the 8-wide BVH over the instances' world boxes, built by
//!   the binned SAH over boxes.
//! - [`scene`]: [`SceneBuilder`] and [`InstancedScene`], with ray masks.
//! - `nearest`: nearest hit and occlusion; `multi_hit`: all hits sorted
//!   by `t` with a cap (the first `k`), counts, any-hit with a filter
//!   callback; `batch`: the same for many rays in parallel.
//! - [`hit`]: [`SceneHit`] (`t`, `u`, `v`, triangle, geometry and instance
//!   ids, world normal).
//! - [`error`] holds [`SceneError`], each naming the geometry or instance.

mod batch;
pub mod error;
pub mod geometry;
pub mod hit;
pub mod instance;
mod multi_hit;
mod nearest;
pub mod scene;
mod top_level;
pub mod transform;

pub use error::SceneError;
pub use geometry::Geometry;
pub use hit::SceneHit;
pub use instance::Instance;
pub use scene::{InstancedScene, SceneBuilder, SceneStats, MASK_ALL};
pub use transform::{InstanceTransform, TransformError};
