//! Bounding volume hierarchies.
//!
//! - [`build`]: the binned surface-area-heuristic (SAH) build shared by all BVH
//!   layouts, parallel over subtrees with rayon.
//! - [`Bvh2`]: binary BVH in depth-first order with sibling pairs side by side,
//!   traversed with a per-ray stack, nearest child first.
//! - [`ThreadedBvh`]: paper 001's layout, nodes in pre-order with escape
//!   indices, traversed without a stack.

pub mod build;
mod bvh2;
mod node_box;
pub(crate) use node_box::NodeBox;
mod threaded;

pub use build::{BuildNode, BuildOptions};
pub use bvh2::Bvh2;
pub use threaded::ThreadedBvh;

/// Deepest tree the builders produce; traversal stacks are sized from it.
pub const MAX_DEPTH: usize = 128;
