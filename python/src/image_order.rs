//! The order in which the rays of an image are traced: 4 × 4 pixel
//! blocks. The wide BVHs trace eight or sixteen consecutive rays of a
//! batch together as a packet (Wald et al. 2001); in 4 × 4 blocks a packet
//! is a square of pixels, whose rays stay together deeper in the tree
//! than a strip of one row does. raykit-render traces its primary rays
//! in the same blocks.

use rayon::prelude::*;

/// Side of a block, pixels.
const BLOCK: usize = 4;

/// A permutation of the rays of a `width`-wide image into blocks.
pub struct ImageOrder {
    /// `order[k]`: the ray traced `k`-th.
    pub order: Vec<u32>,
    /// `position[i]`: where ray `i` is traced (the inverse of `order`).
    pub position: Vec<u32>,
}

impl ImageOrder {
    /// The block order of `n` rays in rows of `width`, or `None` when they
    /// do not form an image of at least one block.
    pub fn new(n: usize, width: usize) -> Option<ImageOrder> {
        if width < BLOCK || !n.is_multiple_of(width) || n / width < BLOCK || n > u32::MAX as usize {
            return None;
        }
        let height = n / width;
        let mut order = Vec::with_capacity(n);
        for by in (0..height).step_by(BLOCK) {
            for bx in (0..width).step_by(BLOCK) {
                for y in by..(by + BLOCK).min(height) {
                    for x in bx..(bx + BLOCK).min(width) {
                        order.push((y * width + x) as u32);
                    }
                }
            }
        }
        let mut position = vec![0u32; n];
        for (k, &i) in order.iter().enumerate() {
            position[i as usize] = k as u32;
        }
        Some(ImageOrder { order, position })
    }

    /// `traced` (in the order traced) back in the rays' own order.
    pub fn restore<T: Copy + Send + Sync>(&self, traced: &[T]) -> Vec<T> {
        self.position
            .par_iter()
            .map(|&k| traced[k as usize])
            .collect()
    }
}
