//! Bounding volume hierarchies.
//!
//! - `build`: the binned surface-area-heuristic (SAH) build shared by all BVH
//!   layouts, parallel over subtrees with rayon.
//! - [`Bvh2`]: binary BVH in depth-first order with sibling pairs side by side,
//!   traversed with a per-ray stack, nearest child first.
//! - [`WideBvh`], with its instances [`Bvh4`] and [`Bvh8`]: the wide BVH
//!   written once for both node widths (`node_width`), made directly by the
//!   SAH build (`wide_build`) or collapsed from the linear BVH's binary tree,
//!   four or eight box tests at once (SSE; AVX detected at run time),
//!   ordered stack traversal; over Möller its leaves are packs of four
//!   triangles tested at once (`tri4`, Embree's `triangle4`).
//! - `packet` (with its `kernel` and `gather`, over `lanes` and `frustum`): the coherent-ray path
//!   behind [`Bvh4`]'s and [`Bvh8`]'s `intersect_batch` / `occluded_batch`
//!   over Möller: packets of rays of one octant traced
//!   together (Wald et al. 2001), sixteen with AVX-512 or eight with AVX2,
//!   one kernel generic over the node width and the packet width, handing their last rays to the tree's own single-ray traversal
//!   (Benthin et al. 2012), with the single-ray answers.
//! - [`ThreadedBvh`]: the threaded layout (Smits 1998), nodes in pre-order
//!   with escape indices, traversed without a stack.
//! - `refit`: [`Bvh4`] and [`Bvh8`] refit to moved vertices in O(n),
//!   topology kept, with an SAH degradation measure and a rebuild past a
//!   limit (Embree's refit).
//! - `persist`: [`Bvh4`] and [`Bvh8`] saved to and loaded from a versioned,
//!   checksummed binary file without a build (read, or the leaf packs
//!   memory-mapped with `load_mapped`); `mapped` holds the mapped array and
//!   `wide_parts` the view of both widths that refit and persist share.

mod bin_pass;
mod binning;
mod box4;
mod box8;
mod box_path;
#[cfg(target_arch = "x86_64")]
pub(crate) use box_path::{avx2, BoxPath};
mod boxes;
pub(crate) mod build;
mod bvh2;
mod bvh8_flat;
mod collapse;
mod enter;
mod fit;
#[cfg(target_arch = "x86_64")]
mod frustum;
pub(crate) mod huge_pages;
#[cfg(target_arch = "x86_64")]
mod lanes;
mod mapped;
mod node4;
mod node8;
mod node_width;
mod packet;
#[cfg(test)]
mod packet_agreement;
mod persist;
mod persist_error;
mod prefetch;
pub(crate) use prefetch::prefetch_lines;
mod ray_box;
mod refit;
mod refit_report;
mod sah_sweep;
#[cfg(target_arch = "x86_64")]
mod sort8;
mod stack;
mod threaded;
mod tri4;
mod wide_build;
mod wide_bvh;
mod wide_leaf;
mod wide_node;
mod wide_parts;
mod wide_tree;
mod words;

pub(crate) use build::BuildNode;
pub use build::{BuildOptions, BuildQuality};
pub use bvh2::Bvh2;
pub use node4::Node4;
pub use node8::Node8;
pub(crate) use persist::saved_scale;
pub use persist::{saved_kind, FORMAT_VERSION, MAGIC};
pub use persist_error::PersistError;
pub use refit_report::{RefitError, RefitReport, DEFAULT_MAX_DEGRADATION};
pub use threaded::ThreadedBvh;
pub(crate) use wide_bvh::CrossingVisitor;
pub use wide_bvh::{Bvh4, Bvh8, WideBvh};

/// Deepest tree the builders produce; traversal stacks are sized from it.
pub const MAX_DEPTH: usize = 128;
