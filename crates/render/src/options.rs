//! What [`crate::render`] is asked to do.

use crate::image::Encoding;
use crate::tiles::Tile;
use raykit_core::glam::Vec3;

/// Image size, sampling and shading settings.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Primary rays per pixel: 1 shoots through the pixel centre; more are
    /// jittered uniformly over the pixel by a [`raykit_core::rng::Pcg32`] per
    /// pixel (stream = pixel index), so images do not depend on scheduling.
    pub samples_per_pixel: u32,
    /// Seed of the jitter.
    pub seed: u64,
    /// Ambient radiance (linear RGB), multiplied by the diffuse colour.
    pub ambient: Vec3,
    /// Trace shadow rays to the lights.
    pub shadows: bool,
    /// Factor on the linear radiance before encoding.
    pub exposure: f32,
    /// Transfer function to 8 bits.
    pub encoding: Encoding,
    /// Crop window (pbrt's "cropwindow"): render only this rectangle of the
    /// `width` × `height` frame; the image is the rectangle's size and its
    /// pixels equal those of the whole frame's render bit for bit, so
    /// separately rendered windows assemble into the whole image. `None`
    /// renders the whole frame.
    pub window: Option<Tile>,
}

impl Default for RenderOptions {
    /// 800 × 600, one sample per pixel, ambient 0.06, shadows on, exposure 1,
    /// sRGB, the whole frame.
    fn default() -> Self {
        RenderOptions {
            width: 800,
            height: 600,
            samples_per_pixel: 1,
            seed: 0,
            ambient: Vec3::splat(0.06),
            shadows: true,
            exposure: 1.0,
            encoding: Encoding::Srgb,
            window: None,
        }
    }
}
