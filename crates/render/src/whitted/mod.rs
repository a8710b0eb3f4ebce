//! The Whitted ray tracer of Whitted (1980), on the GPU after Purcell et al. (2002): Blinn-Phong direct light
//! from point, spot and directional lights with hard shadows (shadow rays or
//! shadow maps), perfect mirror reflection, dielectric refraction with
//! Fresnel and total internal reflection, HDR environments, and two ray
//! organisations — depth-first recursion and the Purcell-style stream tracer's wavefront stream —
//! fed by traced or rasterized primary visibility.

mod frame;
pub mod optics;
mod options;
mod samples;
mod tracer;
mod wavefront;

pub use frame::{render_whitted, Frame, FrameError, FrameStats, WhittedScene};
pub use options::{IntegratorKind, PrimaryMode, ShadowMode, WhittedOptions, DEFAULT_MAX_DEPTH};
pub use samples::sample_position;
pub use tracer::{Bounce, RayCounter, RayCounts, Scatter, Secondary, ShadowSource, Tracer};
pub use wavefront::RayState;
