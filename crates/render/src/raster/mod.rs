//! CPU rasterization of primary visibility, after paper 001's hybrid
//! renderer: the first hit of every pixel is found by rasterizing the mesh
//! with a projection matched to the ray camera, and rays are traced only
//! from there on.
//!
//! - [`RasterView`]: the projection, perspective (a camera, a spot light, a
//!   cube-map face) or orthographic (a directional light).
//! - [`visibility`] / [`primary_visibility`]: the visibility buffer, per
//!   pixel the same `Option<Hit>` as tracing the pixel's ray through an
//!   accelerator, up to ties; [`rasterize`] for any view.
//!
//! The rasterizer is conservative: triangle setup computes edge functions of
//! the projected triangle (homogeneous, so triangles crossing the eye plane
//! need no clipping) widened by half a pixel, a band of barycentric
//! tolerance and rounding slack, and for every candidate pixel the ray of
//! that pixel is intersected with the triangle by the very test and
//! precomputed data the accelerators use. The depth test on that `t`
//! therefore keeps exactly the hit the accelerator would report, except at
//! ties.

mod bins;
mod setup;
mod view;
mod visibility;

pub use view::RasterView;
pub use visibility::{primary_visibility, rasterize, visibility};
