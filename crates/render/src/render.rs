//! The tile-parallel render loop.

use crate::image::Image;
use crate::options::RenderOptions;
use crate::shade::Shader;
use crate::tiles::{map_pixels, Tile};
use raykit_core::glam::Vec3;
use raykit_core::rng::Pcg32;
use raykit_core::{Accel, Camera, TriangleMesh};

/// Render `mesh` (with `accel` built on it) lit by `lights` through `camera`.
///
/// Tiles of [`TILE_SIZE`]² pixels are rendered in parallel on the rayon pool;
/// after each tile `progress` is called with its number of pixels. Each pixel
/// averages `opts.samples_per_pixel` samples of [`Shader::radiance`] (see
/// [`crate::shade`] for the shading), times `opts.exposure`, then encodes it.
/// The result does not depend on the number of threads. With
/// `opts.window` only that rectangle of the frame is rendered (clipped to
/// the frame), each pixel as in the whole frame.
pub fn render(
    mesh: &TriangleMesh,
    lights: &[raykit_core::Light],
    accel: &dyn Accel,
    camera: &Camera,
    opts: &RenderOptions,
    progress: &(dyn Fn(u64) + Sync),
) -> Image {
    let (width, height) = (opts.width, opts.height);
    let shader = Shader::new(mesh, lights, accel, opts);
    let rays = camera.rays(width, height);
    let spp = opts.samples_per_pixel.max(1);
    let pixel = |x: u32, y: u32| -> Vec3 {
        if spp == 1 {
            return shader.radiance(&rays.pixel(x, y));
        }
        let index = y as u64 * width as u64 + x as u64;
        let mut rng = Pcg32::with_stream(opts.seed, index);
        let sum: Vec3 = (0..spp)
            .map(|_| {
                let (jx, jy) = (rng.next_f32(), rng.next_f32());
                shader.radiance(&rays.ray(x as f32 + jx, y as f32 + jy))
            })
            .sum();
        sum / spp as f32
    };
    let window = opts
        .window
        .unwrap_or(Tile::whole(width, height))
        .clipped(width, height);
    let linear = map_pixels(
        window.width,
        window.height,
        &|x, y| pixel(window.x + x, window.y + y) * opts.exposure,
        progress,
    );
    Image::from_linear(window.width, window.height, linear, opts.encoding)
}
