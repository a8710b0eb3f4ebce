//! What the Whitted renderer is asked to do.

use crate::image::Encoding;
use crate::tiles::Tile;
use raykit_core::glam::Vec3;

/// How direct light is tested for occlusion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadowMode {
    /// No shadows: every light in front of a surface reaches it.
    Off,
    /// Shadow rays: an occlusion query with early exit per light and hit.
    Rays,
    /// Shadow maps rasterized from each light, filtered (Purcell-style stream tracer).
    Maps,
}

/// Where the first hit of each camera sample comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrimaryMode {
    /// Trace the camera rays through the acceleration structure.
    Traced,
    /// Rasterize a visibility buffer with the camera's projection (hybrid
    /// rendering); rays are traced only from the first hit on.
    Rasterized,
}

/// How the rays of a frame are organised.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntegratorKind {
    /// Depth-first recursion per camera sample, tile-parallel.
    Recursive,
    /// The Purcell-style stream tracer's stream organisation: each stage a batch over a ray queue.
    Wavefront,
}

/// Image size, sampling, recursion and shading settings.
#[derive(Clone, Debug, PartialEq)]
pub struct WhittedOptions {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Camera samples per pixel: 1 shoots through the pixel centre; more are
    /// jittered over the pixel (see [`crate::whitted::sample_position`]).
    pub samples_per_pixel: u32,
    /// Seed of the jitter.
    pub seed: u64,
    /// Longest path in rays, counting the camera ray: 1 gives direct
    /// lighting only, 2 adds one reflection/refraction bounce (the Purcell-style stream tracer's
    /// "passes"), and so on.
    pub max_depth: u32,
    /// Ambient radiance (linear RGB), multiplied by the diffuse colour.
    pub ambient: Vec3,
    /// Shadow test.
    pub shadows: ShadowMode,
    /// First-hit source.
    pub primary: PrimaryMode,
    /// Ray organisation.
    pub integrator: IntegratorKind,
    /// Factor on the linear radiance before encoding.
    pub exposure: f32,
    /// Transfer function to 8 bits.
    pub encoding: Encoding,
    /// Crop window (pbrt's "cropwindow"): render only this rectangle of the
    /// `width` × `height` frame. The image, the first hits and the counts
    /// cover the rectangle only, and its pixels equal those of the whole
    /// frame's render bit for bit (each camera sample depends on its pixel
    /// alone), so separately rendered windows assemble into the whole
    /// image. `None` renders the whole frame.
    pub window: Option<Tile>,
}

/// Default recursion depth.
pub const DEFAULT_MAX_DEPTH: u32 = 5;

impl Default for WhittedOptions {
    /// 800 × 600, 1 sample, depth 5, ambient 0.06, shadow rays, traced
    /// primaries, recursive, exposure 1, sRGB, the whole frame.
    fn default() -> Self {
        WhittedOptions {
            width: 800,
            height: 600,
            samples_per_pixel: 1,
            seed: 0,
            max_depth: DEFAULT_MAX_DEPTH,
            ambient: Vec3::splat(0.06),
            shadows: ShadowMode::Rays,
            primary: PrimaryMode::Traced,
            integrator: IntegratorKind::Recursive,
            exposure: 1.0,
            encoding: Encoding::Srgb,
            window: None,
        }
    }
}
