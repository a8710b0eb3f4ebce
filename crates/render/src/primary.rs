//! Primary-ray hits without shading.

use raykit_core::{Accel, Camera, Hit, Ray};

/// The nearest hit of the ray through the centre of every pixel of a
/// `width` × `height` image, row-major, in parallel.
pub fn primary_hits(
    accel: &dyn Accel,
    camera: &Camera,
    width: u32,
    height: u32,
) -> Vec<Option<Hit>> {
    let rays = camera.rays(width, height);
    let rays: Vec<Ray> = (0..height)
        .flat_map(|y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| rays.pixel(x, y))
        .collect();
    let mut hits = vec![None; rays.len()];
    accel.intersect_batch(&rays, &mut hits);
    hits
}
