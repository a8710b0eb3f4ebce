//! Primary-ray hits without shading, traced in packet-shaped blocks.

use raykit_core::{Accel, Camera, Hit, Ray};
use rayon::prelude::*;

/// Side of the pixel blocks camera rays are handed to the batch API in:
/// its packets of sixteen (eight) rays are then 4 × 4 (4 × 2) pixels rather
/// than a strip of one row, whose rays part ways in the tree sooner (Wald
/// et al. 2001). 1024² primary rays through `bvh8` in one batch got 1.16×
/// (1M-triangle terrain), 1.27× (full dragon) and 1.31× (500k scatter)
/// faster on one thread (BENCHMARKS.md).
const BLOCK_SIDE: u32 = 4;

/// The pixels of a `width` × `height` image in the order they are traced:
/// [`BLOCK_SIDE`]² blocks, row of blocks after row of blocks, each block
/// row by row (blocks at the right and bottom edges clipped).
fn packet_order(width: u32, height: u32) -> Vec<(u32, u32)> {
    let mut order = Vec::with_capacity(width as usize * height as usize);
    for by in (0..height).step_by(BLOCK_SIDE as usize) {
        for bx in (0..width).step_by(BLOCK_SIDE as usize) {
            for y in by..(by + BLOCK_SIDE).min(height) {
                for x in bx..(bx + BLOCK_SIDE).min(width) {
                    order.push((x, y));
                }
            }
        }
    }
    order
}

/// The nearest hit of every pixel's ray (`ray_of(x, y)`) of a `width` ×
/// `height` image, row-major, through [`Accel::intersect_batch`] in
/// packet-shaped blocks (see [`BLOCK_SIDE`]), with the single-ray answers.
pub(crate) fn trace_primaries(
    accel: &dyn Accel,
    width: u32,
    height: u32,
    ray_of: &(dyn Fn(u32, u32) -> Ray + Sync),
) -> Vec<Option<Hit>> {
    let order = packet_order(width, height);
    let rays: Vec<Ray> = order.par_iter().map(|&(x, y)| ray_of(x, y)).collect();
    let mut traced = vec![None; rays.len()];
    accel.intersect_batch(&rays, &mut traced);
    let mut hits = vec![None; rays.len()];
    for (&(x, y), h) in order.iter().zip(traced) {
        hits[y as usize * width as usize + x as usize] = h;
    }
    hits
}

/// The nearest hit of the ray through the centre of every pixel of a
/// `width` × `height` image, row-major, in parallel (traced as
/// [`trace_primaries`] does).
pub fn primary_hits(
    accel: &dyn Accel,
    camera: &Camera,
    width: u32,
    height: u32,
) -> Vec<Option<Hit>> {
    let rays = camera.rays(width, height);
    trace_primaries(accel, width, height, &|x, y| rays.pixel(x, y))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every pixel once; with sides that are multiples of four, every run
    /// of sixteen is one 4 × 4 block, and the edges are clipped otherwise.
    #[test]
    fn packet_order_is_a_permutation_of_blocks() {
        for (w, h) in [(16, 8), (20, 15), (1, 1), (3, 7), (64, 4)] {
            let order = packet_order(w, h);
            let mut seen = vec![0u32; (w * h) as usize];
            for &(x, y) in &order {
                assert!(x < w && y < h);
                seen[(y * w + x) as usize] += 1;
            }
            assert!(seen.iter().all(|&s| s == 1), "{w} x {h}");
            if w % 4 == 0 && h % 4 == 0 {
                for run in order.chunks(16) {
                    let (x0, y0) = (run[0].0, run[0].1);
                    assert!(run.iter().all(|&(x, y)| x / 4 == x0 / 4 && y / 4 == y0 / 4));
                }
            }
        }
    }
}
