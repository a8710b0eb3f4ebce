//! The maximum mipmap of Tevs et al. (2008), as the quadtree-box caster uses it: a
//! quadtree stored as an image pyramid whose level 0 holds each cell's
//! highest corner and each higher texel the maximum of its (up to) four
//! children. A minimum pyramid is kept beside it, so a node's box spans
//! `[min, max]` of its surface.

use crate::heightfield::HeightField;
use rayon::prelude::*;

/// One level of the pyramid.
#[derive(Clone, Debug)]
pub struct Level {
    /// Texels along x.
    pub width: usize,
    /// Texels along y.
    pub height: usize,
    /// Highest and lowest surface point below each texel, side by side so
    /// one cache line holds both (the walks are bound by these loads).
    pub max_min: Vec<[f32; 2]>,
}

impl Level {
    /// The texels of this level under texel (`i`, `j`) of the level above:
    /// up to four, fewer at the right and bottom edges.
    pub fn children(&self, i: usize, j: usize) -> impl Iterator<Item = (usize, usize)> + '_ {
        [
            (2 * i, 2 * j),
            (2 * i + 1, 2 * j),
            (2 * i, 2 * j + 1),
            (2 * i + 1, 2 * j + 1),
        ]
        .into_iter()
        .filter(|&(ci, cj)| ci < self.width && cj < self.height)
    }

    /// Highest surface point below texel `k`.
    #[inline]
    pub fn max(&self, k: usize) -> f32 {
        self.max_min[k][0]
    }

    /// Lowest surface point below texel `k`.
    #[inline]
    pub fn min(&self, k: usize) -> f32 {
        self.max_min[k][1]
    }
}

/// Levels from the cells (level 0) up to a single texel.
#[derive(Clone, Debug)]
pub struct MaxMipmap {
    /// `levels[0]` is per cell; the last level is 1 × 1.
    pub levels: Vec<Level>,
}

impl MaxMipmap {
    /// Build the pyramid of `field` (parallel over rows).
    pub fn new(field: &HeightField) -> MaxMipmap {
        let (cw, ch) = field.cells();
        let mut max_min = vec![[0.0f32; 2]; cw * ch];
        max_min.par_chunks_mut(cw).enumerate().for_each(|(r, out)| {
            for (c, texel) in out.iter_mut().enumerate() {
                let h = [
                    field.at(c, r),
                    field.at(c + 1, r),
                    field.at(c, r + 1),
                    field.at(c + 1, r + 1),
                ];
                *texel = [
                    h.iter().copied().fold(f32::MIN, f32::max),
                    h.iter().copied().fold(f32::MAX, f32::min),
                ];
            }
        });
        let mut levels = vec![Level {
            width: cw,
            height: ch,
            max_min,
        }];
        while levels.last().is_some_and(|l| l.width > 1 || l.height > 1) {
            let prev = levels.last().expect("a level exists");
            let (w, h) = (prev.width.div_ceil(2), prev.height.div_ceil(2));
            let mut max_min = vec![[0.0f32; 2]; w * h];
            max_min.par_chunks_mut(w).enumerate().for_each(|(j, out)| {
                for (i, texel) in out.iter_mut().enumerate() {
                    let (mut a, mut b) = (f32::MIN, f32::MAX);
                    for (ci, cj) in prev.children(i, j) {
                        a = a.max(prev.max(cj * prev.width + ci));
                        b = b.min(prev.min(cj * prev.width + ci));
                    }
                    *texel = [a, b];
                }
            });
            levels.push(Level {
                width: w,
                height: h,
                max_min,
            });
        }
        MaxMipmap { levels }
    }

    /// Index of the top level (1 × 1).
    pub fn top(&self) -> usize {
        self.levels.len() - 1
    }

    /// Cells covered by node (`i`, `j`) of `level`, clipped to the grid:
    /// columns `[x0, x1)` and rows `[y0, y1)`.
    pub fn extent(&self, level: usize, i: usize, j: usize) -> (usize, usize, usize, usize) {
        let l0 = &self.levels[0];
        let s = 1usize << level;
        (
            i * s,
            ((i + 1) * s).min(l0.width),
            j * s,
            ((j + 1) * s).min(l0.height),
        )
    }

    /// Bytes held by all levels.
    pub fn bytes(&self) -> usize {
        self.levels.iter().map(|l| 8 * l.max_min.len()).sum()
    }
}
