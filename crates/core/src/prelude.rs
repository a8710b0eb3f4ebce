//! The names most programs need, in one import:
//!
//! ```
//! use raykit_core::prelude::*;
//! ```
//!
//! A mesh ([`TriangleMesh`]), a structure over it ([`Bvh8`] over
//! [`Moller`], the fastest pair, or any [`AccelKind`] × [`TestKind`]
//! through [`build_accel`]), its build presets ([`BuildOptions::fast`],
//! [`BuildOptions::balanced`], [`BuildOptions::best`]), and the rays and
//! hits it answers through [`Accel`].

pub use crate::accel::{
    build_accel, Accel, AccelKind, BuildOptions, BuildQuality, Bvh2, Bvh4, Bvh8, WideBvh,
};
pub use crate::tri::{Moller, Plucker, TestKind, TriangleTest};
pub use crate::{Aabb, Hit, MeshError, Ray, TriangleMesh, Vec3};
