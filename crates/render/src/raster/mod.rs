//! CPU rasterization of primary visibility, after the Purcell-style stream tracer's hybrid
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
//! The rasterizer is conservative: coverage is tested at each pixel's own
//! sample position against the projected triangle expanded by the triangle
//! tests' barycentric tolerance band and a bound on rounding
//! ([`tight`](self::tight), in `f32`), or, for triangles crossing or near
//! the eye plane, with homogeneous edge functions widened by half a pixel
//! ([`setup`](self::setup), in `f64`, no clipping needed); for every
//! candidate pixel the ray of that pixel is intersected with the triangle by
//! the very test and precomputed data the accelerators use. The depth test
//! on that `t` therefore keeps exactly the hit the accelerator would report,
//! except at ties.

mod bins;
mod samples;
mod screen;
mod setup;
mod tight;
mod view;
mod visibility;

pub use view::RasterView;
pub use visibility::{primary_visibility, rasterize, visibility};
